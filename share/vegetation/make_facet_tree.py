#!/usr/bin/python3
"""Writes a facet tree model as OBJ (with its MTL): a trunk, branches and leaves, all triangles,
in metres with z up and the stem's foot at the origin, as `canopy.facets.models` reads it
(PRODUCT.md section 8). Nothing can be downloaded, so the example makes its own tree.

The tree: a trunk of 8 faces (radius --trunk-radius-m) from the ground to --height-m; branches
(thin prisms of 4 faces) from the trunk's upper half out to the crown's edge; --leaves leaf
triangles (equilateral, side --leaf-size-m) with their centres uniform in an ellipsoidal crown
(radius --crown-radius-m, from --crown-base-m to the top) and their normals uniform on the
sphere (spherical leaf angles). Materials: `wood` (trunk, branches) and `leaf`. The plant area
(one-sided leaf area, and the wood's) is printed, so that a plot's PAI can be worked out.

    /usr/bin/python3 share/vegetation/make_facet_tree.py out/vegetation/tree.obj [--leaves 20000]
"""
import argparse
import csv
import math
import os

import numpy as np

# The model's defaults: the tree of share/vegetation/facets.json's forest.
MODEL = {"leaves": 20000, "leaf_size_m": 0.12, "height_m": 14.0, "crown_base_m": 5.0,
         "crown_radius_m": 3.5}


def leaf_area_m2(leaves, leaf_size_m):
    """One-sided area of `leaves` equilateral triangles of side `leaf_size_m`."""
    return leaves * math.sqrt(3.0) / 4.0 * leaf_size_m ** 2


def turbid_crowns(trees_csv, model=MODEL):
    """The trees of a facets trees file (header x,y,model,rotation_deg,scale) as turbid crowns:
    each the model's ellipsoidal crown scaled, holding its leaf area. Rows of (x_m, y_m, base_m,
    radius_m, half_height_m, pad_m2_m3), x and y east and north of terrain.plane's origin; the
    crown's axis is the stem's, so the turn of a tree does not move it."""
    half_height = 0.5 * (model["height_m"] - model["crown_base_m"])
    rows = []
    with open(trees_csv, newline="") as f:
        for tree in csv.DictReader(f):
            s = float(tree["scale"])
            radius, half = model["crown_radius_m"] * s, half_height * s
            volume = 4.0 / 3.0 * math.pi * radius ** 2 * half
            area = leaf_area_m2(model["leaves"], model["leaf_size_m"]) * s ** 2
            rows.append((float(tree["x"]), float(tree["y"]), model["crown_base_m"] * s, radius,
                         half, area / volume))
    return rows


def prism(a, b, radius, sides, vertices, faces):
    """A closed-sided prism of `sides` faces from point a to point b."""
    axis = (b - a) / np.linalg.norm(b - a)
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[2]) > 0.9 else np.array([0.0, 0.0, 1.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    first = len(vertices)
    for k in range(sides):
        angle = 2 * math.pi * k / sides
        offset = radius * (math.cos(angle) * u + math.sin(angle) * v)
        vertices.append(a + offset)
        vertices.append(b + offset)
    area = 0.0
    for k in range(sides):
        p, q = first + 2 * k, first + 2 * ((k + 1) % sides)
        faces.append((p, q, q + 1))
        faces.append((p, q + 1, p + 1))
    area = sides * 2 * radius * math.sin(math.pi / sides) * np.linalg.norm(b - a)
    return area


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("obj")
    parser.add_argument("--leaves", type=int, default=MODEL["leaves"])
    parser.add_argument("--leaf-size-m", type=float, default=MODEL["leaf_size_m"])
    parser.add_argument("--height-m", type=float, default=MODEL["height_m"])
    parser.add_argument("--crown-base-m", type=float, default=MODEL["crown_base_m"])
    parser.add_argument("--crown-radius-m", type=float, default=MODEL["crown_radius_m"])
    parser.add_argument("--trunk-radius-m", type=float, default=0.15)
    parser.add_argument("--branches", type=int, default=12)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)

    wood_vertices, wood_faces = [], []
    wood_area = prism(np.zeros(3), np.array([0.0, 0.0, args.height_m]), args.trunk_radius_m, 8,
                      wood_vertices, wood_faces)
    half_height = 0.5 * (args.height_m - args.crown_base_m)
    centre_z = args.crown_base_m + half_height
    for k in range(args.branches):
        z = args.crown_base_m + (k + 0.5) / args.branches * (args.height_m - args.crown_base_m) * 0.8
        azimuth = 2.4 * k  # the golden angle, roughly: branches all round
        # To the crown's edge at that height, rising a little.
        reach = 0.8 * args.crown_radius_m * math.sqrt(max(0.0, 1 - ((z - centre_z) / half_height) ** 2))
        end = np.array([reach * math.cos(azimuth), reach * math.sin(azimuth), z + 0.3 * reach])
        wood_area += prism(np.array([0.0, 0.0, z]), end, 0.04, 4, wood_vertices, wood_faces)

    # Leaf centres uniform in the ellipsoid, normals uniform on the sphere.
    centres = []
    while len(centres) < args.leaves:
        p = rng.uniform(-1.0, 1.0, size=(2 * args.leaves, 3))
        p = p[(p ** 2).sum(axis=1) <= 1.0]
        centres.extend(p[: args.leaves - len(centres)])
    centres = np.array(centres) * [args.crown_radius_m, args.crown_radius_m, half_height]
    centres[:, 2] += centre_z
    normals = rng.normal(size=(args.leaves, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    helper = np.where(np.abs(normals[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    u = np.cross(normals, helper)
    u /= np.linalg.norm(u, axis=1)[:, None]
    v = np.cross(normals, u)
    spin = rng.uniform(0.0, 2 * math.pi, size=(args.leaves, 1))
    circumradius = args.leaf_size_m / math.sqrt(3.0)
    leaf_vertices = []
    for k in range(3):
        angle = spin + 2 * math.pi * k / 3
        leaf_vertices.append(centres + circumradius * (np.cos(angle) * u + np.sin(angle) * v))
    leaf_vertices = np.stack(leaf_vertices, axis=1).reshape(-1, 3)
    leaf_area = leaf_area_m2(args.leaves, args.leaf_size_m)

    os.makedirs(os.path.dirname(os.path.abspath(args.obj)), exist_ok=True)
    mtl = os.path.splitext(args.obj)[0] + ".mtl"
    with open(mtl, "w") as out:
        out.write("newmtl wood\nKd 0.3 0.2 0.1\nnewmtl leaf\nKd 0.1 0.5 0.1\n")
    with open(args.obj, "w") as out:
        out.write("# facet tree by make_facet_tree.py: metres, z up, the stem's foot at 0 0 0\n")
        out.write(f"# leaf area {leaf_area:.4f} m2, wood area {wood_area:.4f} m2\n")
        out.write(f"mtllib {os.path.basename(mtl)}\n")
        for p in wood_vertices:
            out.write(f"v {p[0]:.5f} {p[1]:.5f} {p[2]:.5f}\n")
        np.savetxt(out, leaf_vertices, fmt="v %.5f %.5f %.5f")
        out.write("g wood\nusemtl wood\n")
        for a, b, c in wood_faces:
            out.write(f"f {a + 1} {b + 1} {c + 1}\n")
        out.write("g leaves\nusemtl leaf\n")
        first = len(wood_vertices) + 1
        index = first + np.arange(3 * args.leaves).reshape(-1, 3)
        np.savetxt(out, index, fmt="f %d %d %d")
    triangles = len(wood_faces) + args.leaves
    print(f"{args.obj}: {triangles} triangles, leaf area {leaf_area:.2f} m2, "
          f"wood area {wood_area:.2f} m2")


if __name__ == "__main__":
    main()
