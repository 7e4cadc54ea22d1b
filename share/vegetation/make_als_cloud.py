#!/usr/bin/python3
"""Writes an ALS-like point cloud of a small forest on hills, by casting discrete returns through
a known scene, so that `glaswave voxelize` has a cloud whose truth is known (nothing can be
downloaded).

The scene: 200 m x 200 m of hills (a few Gaussian bumps, up to 25 m high) in UTM zone 33N near
45 N 15 E, with turbid ellipsoidal crowns (plant area density 0.6 m2/m3, radius 3-5 m, on 0.5 m
voxels of height above the ground) at random, cover about 0.4. The scanner: pulses at `--density` a square metre, scan angles
within +-15 degrees across track (x), each pulse four independent beamlets (a footprint of four
gaps); a beamlet meets foliage at an optical depth drawn from Exp(1), with G = 1/2, or the
ground. Each beamlet gives one return (number_of_returns 4), as glaswave's inversion expects.

With --trees TREES_CSV (a facets trees file, x and y from facets.json's terrain.plane origin,
45.0009 N 15.00127 E, the plot's centre), the crowns are instead those trees' as turbid
ellipsoids of the facet model's crown and leaf area (make_facet_tree.turbid_crowns), on level
ground at 300 m: the forest of share/vegetation/facets.json, so that the point cloud, its voxels,
the facet trees and turbid crowns are one scene (plot_waveforms.py).

Writes CLOUD (LAS 1.4, point format 6, with the CRS as a WKT record) and, beside it,
CLOUD.truth.csv: the scene's mean plant area density by 1 m layer above the ground, for
comparison with `glaswave voxelize`'s grid.

    /usr/bin/python3 share/vegetation/make_als_cloud.py out/forest.las [--density 2] [--seed 1]
        [--trees share/vegetation/facet_trees.csv]
    build/glaswave voxelize out/forest.las --out out/forest_pad.nc
"""
import argparse
import struct

import numpy as np

from make_facet_tree import turbid_crowns

UTM33 = ('PROJCS["WGS 84 / UTM zone 33N",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",'
         '6378137,298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],'
         'PROJECTION["Transverse_Mercator"],PARAMETER["latitude_of_origin",0],'
         'PARAMETER["central_meridian",15],PARAMETER["scale_factor",0.9996],'
         'PARAMETER["false_easting",500000],PARAMETER["false_northing",0],UNIT["metre",1],'
         'AUTHORITY["EPSG","32633"]]')
X0, Y0, SIDE = 500000.0, 4982950.0, 200.0  # the plot's south-west corner, near 45 N 15 E
# facets.json's terrain.plane origin (45.0009 N, 15.00127 E) in UTM 33N, by PROJ: the plot's
# centre. Trees files are in metres from it (UTM's scale, 0.9996, moves a tree 1 cm at 26 m).
ORIGIN = (500100.094, 4983050.380)
G = 0.5
HILLS = [True]  # level ground at 300 m for a trees file's forest (main sets it)


def ground(x, y):
    """The hills: height above the ellipsoid (m)."""
    h = np.full(np.shape(x), 300.0)
    if not HILLS[0]:
        return h
    for cx, cy, height, width in ((60, 70, 25, 40), (150, 130, 18, 30), (120, 20, 10, 25)):
        h = h + height * np.exp(-((x - X0 - cx) ** 2 + (y - Y0 - cy) ** 2) / (2 * width ** 2))
    return h


def crowns(rng, trees=None):
    """Ellipsoids (x, y, base above ground, radius, half height, PAD) of cover about 0.5, or
    those of a trees file's facet trees."""
    if trees:
        c = np.array(turbid_crowns(trees))
        c[:, 0] += ORIGIN[0]
        c[:, 1] += ORIGIN[1]
        return c
    r = rng.uniform(3.0, 5.0, 400)
    keep = np.cumsum(np.pi * r ** 2) < -np.log(1 - 0.5) * SIDE ** 2
    r = r[keep]
    n = len(r)
    return np.column_stack([X0 + rng.uniform(0, SIDE, n), Y0 + rng.uniform(0, SIDE, n),
                            rng.uniform(6.0, 12.0, n), r, rng.uniform(4.0, 7.0, n),
                            np.full(n, 0.6)])


CELL = 0.5  # the scene's plant area density on a grid of this size, height above the ground
LAYERS = 80


def pad_grid(trees):
    """PAD (m2/m3) on CELL-sized voxels: [i (east), j (north), k (height above the ground)]."""
    n = int(SIDE / CELL)
    grid = np.zeros((n, n, LAYERS), dtype=np.float32)
    c = (np.arange(n) + 0.5) * CELL
    h = (np.arange(LAYERS) + 0.5) * CELL
    for cx, cy, base, r, hh, pad in trees:
        i0, i1 = max(0, int((cx - X0 - r) / CELL)), min(n, int((cx - X0 + r) / CELL) + 1)
        j0, j1 = max(0, int((cy - Y0 - r) / CELL)), min(n, int((cy - Y0 + r) / CELL) + 1)
        dx = (c[i0:i1] - (cx - X0))[:, None, None] / r
        dy = (c[j0:j1] - (cy - Y0))[None, :, None] / r
        dz = (h - base - hh)[None, None, :] / hh
        inside = dx ** 2 + dy ** 2 + dz ** 2 < 1.0
        grid[i0:i1, j0:j1, :][inside] = pad
    return grid


def march(grid, px, py, pz, dx, dz, length, step=0.2):
    """Beamlets from (px, py, pz) along (dx, 0, dz): the optical depth G u reached at each step,
    and the steps' points."""
    t = np.arange(0.0, length, step) + step / 2
    x = px[:, None] + t[None, :] * dx[:, None]
    y = np.broadcast_to(py[:, None], x.shape)
    z = pz[:, None] + t[None, :] * dz[:, None]
    n = grid.shape[0]
    i = np.clip(((x - X0) / CELL).astype(int), 0, n - 1)
    j = np.clip(((y - Y0) / CELL).astype(int), 0, n - 1)
    k = ((z - ground(x, y)) / CELL).astype(int)
    pad = np.where((k >= 0) & (k < LAYERS), grid[i, j, np.clip(k, 0, LAYERS - 1)], 0.0)
    return np.cumsum(G * pad * step, axis=1), x, y, z


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("cloud")
    parser.add_argument("--density", type=float, default=2.0, help="pulses per square metre")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--trees", help="a facets trees file (x,y): its forest, on level ground")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    HILLS[0] = args.trees is None
    trees = crowns(rng, args.trees)
    grid = pad_grid(trees)
    n = int(args.density * SIDE * SIDE)
    records = []
    top = 45.0  # pulses start this high above the ground under them
    for first in range(0, n, 2000):
        m = min(2000, n - first)
        px = X0 + rng.uniform(0, SIDE, m)
        py = Y0 + rng.uniform(0, SIDE, m)
        angle = rng.uniform(-15.0, 15.0, m)
        theta = np.radians(angle)
        start_z = ground(px, py) + top
        sx = px - top * np.tan(theta)  # aimed so that the pulse reaches (px, py) at the ground
        for b in range(4):
            depth, x, y, z = march(grid, sx, py, start_z, np.sin(theta), -np.cos(theta),
                                   top / np.cos(np.radians(15)) + 5)
            target = rng.exponential(1.0, m)
            hit = depth >= target[:, None]
            first_hit = np.where(hit.any(axis=1), hit.argmax(axis=1), -1)
            below = z < ground(x, y)
            first_ground = below.argmax(axis=1)
            stop = np.where((first_hit >= 0) & (first_hit < first_ground), first_hit, first_ground)
            rows = np.arange(m)
            rx, ry, rz = x[rows, stop], y[rows, stop], z[rows, stop]
            is_ground = stop == first_ground
            rz = np.where(is_ground, ground(rx, ry), rz)
            for i in range(m):
                records.append((rx[i], ry[i], rz[i], b + 1, 4, 2 if is_ground[i] else 5, angle[i]))
    write_las(args.cloud, records)
    write_truth(args.cloud + ".truth.csv", grid)
    print("%d returns of %d pulses, %d crowns; %s" % (len(records), n, len(trees), args.cloud))


def write_las(path, records):
    scale = 0.001
    offset = (X0, Y0, 0.0)
    wkt = UTM33.encode() + b"\0"
    vlr = struct.pack("<H16sHH32s", 0, b"LASF_Projection", 2112, len(wkt), b"OGC WKT") + wkt
    header = bytearray(375)
    header[0:4] = b"LASF"
    struct.pack_into("<HH", header, 4, 0, 16)  # global encoding: WKT
    header[24], header[25] = 1, 4
    header[26:26 + 9] = b"glaswave "
    struct.pack_into("<HIIBHI", header, 94, 375, 375 + len(vlr), 1, 6, 30, 0)
    xyz = np.array([r[:3] for r in records])
    struct.pack_into("<3d3d", header, 131, scale, scale, scale, *offset)
    struct.pack_into("<6d", header, 179, xyz[:, 0].max(), xyz[:, 0].min(), xyz[:, 1].max(),
                     xyz[:, 1].min(), xyz[:, 2].max(), xyz[:, 2].min())
    struct.pack_into("<QIQ", header, 235, 0, 0, len(records))
    with open(path, "wb") as out:
        out.write(header)
        out.write(vlr)
        for i, (x, y, z, ret, num, cls, angle) in enumerate(records):
            out.write(struct.pack("<iiiHBBBBhHd", round((x - offset[0]) / scale),
                                  round((y - offset[1]) / scale), round((z - offset[2]) / scale),
                                  100, ret | num << 4, 0, cls, 0, round(angle / 0.006), 0,
                                  float(i)))


def write_truth(path, grid):
    """The scene's mean PAD by 1 m layer above the ground."""
    per_cell = grid.mean(axis=(0, 1))
    layers = per_cell.reshape(-1, int(1 / CELL)).mean(axis=1)
    with open(path, "w") as out:
        out.write("z_bottom_m,z_top_m,pad_m2_m3\n")
        for k, value in enumerate(layers):
            out.write("%d,%d,%.5f\n" % (k, k + 1, value))


if __name__ == "__main__":
    main()
