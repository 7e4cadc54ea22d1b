#!/usr/bin/env python3
"""RAMI's scenes as glaswave configurations (PRODUCT.md section 13, docs/guide/rami.md).

Writes into --out (default: this folder) one configuration a scene, the trees and crowns files
they place, and the disc leaves of the discrete scenes under discs/ (generated, not kept in git:
a few MB each, the same bits from the same seed):

  hom_tur_{pla,ere,uni}  RAMI-III-style homogeneous turbid layers, LAI 3, 1 m deep
  hom_dis_{pla,ere,uni}  the same as discs of radius 0.05 m over a periodic 10 m tile
  het01                  15 floating spheres of 49 999 discs of 0.1 m radius (LAI 5 a sphere)
  het02                  the same spheres turbid, conservative (leaves 0.5/0.5, soil 1): RAMI's
                         purist corner
  het03                  the same spheres turbid under HET01's optics, leaf_size_m = the discs'
                         radius: HET01's turbid twin

With each of hom_tur_* and het01/02/03 goes `<scene>_lidar.json`, RAMI-IV's lidar measurements
(`lidar_sgl_co`, `lidar_tot`) through `glaswave run`: a delta pulse lighting a disc of 50 m
uniformly at nadir, 10 shots at the scene's centre, the return binned by height from the ground up
(0.05 m bins in the 1 m layers, 0.5 m over the spheres). The discrete layers have none: their
leaves are one 10 m tile, which `run` (unlike `brf`) does not repeat under a 50 m footprint.

RAMI-III's published statistics (rami-benchmark.jrc.ec.europa.eu, HET01/HET02 pages): a 100 m x
100 m scene, 15 spheres of radius 10 m whose centres lie 11 to 19 m above the ground, covering
0.471 of it (no two overlap seen from above), LAI 5 within a sphere's cross-section, discs of
radius 0.1 m with uniform (glaswave: spherical) normals. RAMI's own sphere file and sphere centres
are not reproduced here: both are drawn from those statistics with a fixed seed. RAMI's
"uniform" leaf normals are glaswave's `spherical` LAD.

Optics are RAMI-III's solar-domain values: RED leaves 0.0546/0.0149 over soil 0.127, NIR leaves
0.4957/0.4409 over soil 0.159. The sun is at 20 deg zenith (RAMI-III's first case), azimuth 0.
"""
import argparse
import json
import math
import os

import numpy as np

SEED = 41
RED = {"reflectance": 0.0546, "transmittance": 0.0149, "soil": 0.127}
NIR = {"reflectance": 0.4957, "transmittance": 0.4409, "soil": 0.159}
# RAMI-III's purist corner: conservative scattering.
CONSERVATIVE = {"reflectance": 0.5, "transmittance": 0.5, "soil": 1.0}

HOM_LAI, HOM_DEPTH_M, HOM_DISC_M, HOM_TILE_M = 3.0, 1.0, 0.05, 10.0
HET_TILE_M, HET_SPHERES, HET_RADIUS_M = 100.0, 15, 10.0
HET_LAI, HET_DISC_M, HET_DISCS = 5.0, 0.1, 49999
HET_CENTRE_M = (11.0, 19.0)
SUN_ZENITH_DEG, SUN_AZIMUTH_DEG = 20.0, 0.0
# glaswave's name of RAMI's leaf normal distributions.
LADS = {"pla": "planophile", "ere": "erectophile", "uni": "spherical"}


def band_names(optics):
    return ["RED", "NIR"] if optics is None else ["CON"]


def sensor(bands):
    wavelengths = {"RED": 670, "NIR": 865, "CON": 865}
    return {"preset": "gedi",
            "bands": [{"name": b, "wavelength_nm": wavelengths[b], "pulse_energy_mJ": 10.0,
                       "atmos_transmission_roundtrip": 1.0} for b in bands]}


def per_band(key, optics):
    """{band: value} for RED/NIR, or the conservative value."""
    if optics is not None:
        return optics[key]
    return {"RED": RED[key], "NIR": NIR[key]}


def base_config(name, tile_m, optics, experiment):
    bands = band_names(optics)
    return {
        "seed": SEED,
        "sensor": sensor(bands),
        "simulation": {"rays_per_shot": 1000},
        "terrain": {"plane": {"origin_lat_deg": 0.0, "origin_lon_deg": 0.0, "elevation_m": 0.0},
                    "soil_reflectance": per_band("soil", optics)},
        "track": {"type": "points", "points": [{"lat_deg": 0.0, "lon_deg": 0.0}],
                  "altitude_m": 420000.0},
        "output": {"footprints": False},
        "brf": {"sun_zenith_deg": SUN_ZENITH_DEG, "sun_azimuth_deg": SUN_AZIMUTH_DEG,
                "photons": 100000, "scene_size_m": tile_m, "image_resolution_m": tile_m / 10,
                # On RAMI's grid (odd zeniths): nadir's neighbour, either side of the hotspot,
                # the orthogonal plane.
                "views": [{"zenith_deg": 1.0, "azimuth_deg": 0.0},
                          {"zenith_deg": 21.0, "azimuth_deg": 0.0},
                          {"zenith_deg": 21.0, "azimuth_deg": 180.0},
                          {"zenith_deg": 45.0, "azimuth_deg": 270.0}],
                "rami": {"measurements": ["brfpp", "brfop", "brfpp_co_sgl", "brfpp_uc_sgl",
                                          "brfpp_mlt", "brf1", "fabs", "ftran", "falb"],
                         "experiment": experiment, "model": "glaswave"}},
        "_scene": name,
    }


def turbid_layer(lad, optics=None):
    cfg = base_config(f"hom_tur_{lad}", HOM_TILE_M, optics,
                      f"HOM03_TUR_{lad.upper()}_{{band}}_20")
    cfg["canopy"] = {"crown_shape": "layer", "crown_base_m": [0.0, 0.0],
                     "crown_half_height_m": HOM_DEPTH_M / 2, "pai": HOM_LAI, "cover": 1.0,
                     "lad": LADS[lad], "leaf_size_m": HOM_DISC_M, "dbh_m": 0.0,
                     "green_fraction": 1.0, "bark_fraction": 0.0,
                     "leaf_reflectance": per_band("reflectance", optics),
                     "leaf_transmittance": per_band("transmittance", optics)}
    return cfg


def normals(rng, n, lad):
    """Unit normals (upper hemisphere) drawn from the LAD's inclination density."""
    if lad == "uni":  # uniform on the sphere: cos(inclination) uniform
        mu = rng.uniform(0.0, 1.0, n)
        theta = np.arccos(mu)
    else:  # 2/pi (1 +- cos 2t) on [0, pi/2], by rejection under its maximum 4/pi
        sign = 1.0 if lad == "pla" else -1.0
        theta = np.empty(0)
        while theta.size < n:
            t = rng.uniform(0.0, math.pi / 2, 2 * n)
            keep = rng.uniform(0.0, 2.0, 2 * n) < 1.0 + sign * np.cos(2 * t)
            theta = np.concatenate([theta, t[keep]])
        theta = theta[:n]
    phi = rng.uniform(0.0, 2 * math.pi, n)
    s = np.sin(theta)
    return np.column_stack([s * np.cos(phi), s * np.sin(phi), np.cos(theta)])


def write_def(path, radius, centres, normal):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    table = np.column_stack([np.full(len(centres), radius), centres, normal])
    with open(path, "w") as out:
        out.write("# radius x y z nx ny nz (m): glaswave share/rami/make_scenes.py\n")
        np.savetxt(out, table, fmt="%.6f")


def periodic_copies(points, reach_m, tile_m):
    """The points near the tile's sides, again one tile over: a periodic tile wraps paths, not
    geometry, so what pokes out of one side must come back in at the other."""
    h = tile_m / 2
    copies = []
    for dx in (-tile_m, 0.0, tile_m):
        for dy in (-tile_m, 0.0, tile_m):
            if dx == 0.0 and dy == 0.0:
                continue
            shifted = points.copy()
            shifted[:, 0] += dx
            shifted[:, 1] += dy
            near = (np.abs(shifted[:, 0]) < h + reach_m) & (np.abs(shifted[:, 1]) < h + reach_m)
            copies.append(shifted[near])
    return np.concatenate([points] + copies)


def discrete_layer(lad, out, optics=None, tile_m=HOM_TILE_M):
    rng = np.random.default_rng([SEED, ord(lad[0])])
    n = int(round(HOM_LAI * tile_m * tile_m / (math.pi * HOM_DISC_M ** 2)))
    h = tile_m / 2
    centres = np.column_stack([rng.uniform(-h, h, n), rng.uniform(-h, h, n),
                               rng.uniform(HOM_DISC_M, HOM_DEPTH_M - HOM_DISC_M, n)])
    leaves = np.column_stack([centres, normals(rng, n, lad)])
    leaves = periodic_copies(leaves, HOM_DISC_M, tile_m)
    name = f"hom_dis_{lad}"
    write_def(os.path.join(out, "discs", f"{name}.def"), HOM_DISC_M, leaves[:, :3], leaves[:, 3:])
    with open(os.path.join(out, f"{name}_trees.csv"), "w") as f:
        f.write("x,y,model,rotation_deg,scale\n0,0,layer,0,1\n")
    cfg = base_config(name, tile_m, optics, f"HOM03_DIS_{lad.upper()}_{{band}}_20")
    cfg["canopy"] = facets_canopy(f"{name}_trees.csv", {"layer": f"discs/{name}.def"}, optics)
    return cfg


def facets_canopy(trees, models, optics):
    return {"facets": {"trees_file": trees, "models": models,
                       "materials": {"leaf": {"reflectance": per_band("reflectance", optics),
                                              "transmittance": per_band("transmittance",
                                                                        optics)}}}}


def sphere_centres(tile_m=HET_TILE_M, count=HET_SPHERES, radius_m=HET_RADIUS_M):
    """Centres no two of which overlap seen from above on the periodic tile (RAMI's cover
    15 pi r^2 / A = 0.471), heights uniform in RAMI's 11-19 m; random sequential placement, the
    first seed's that completes."""
    for attempt in range(1000):
        rng = np.random.default_rng([SEED, attempt])
        xy = []
        for _ in range(20000):
            p = rng.uniform(-tile_m / 2, tile_m / 2, 2)
            d = [np.hypot(*((p - q + tile_m / 2) % tile_m - tile_m / 2)) for q in xy]
            if all(x >= 2 * radius_m for x in d):
                xy.append(p)
                if len(xy) == count:
                    z = rng.uniform(*HET_CENTRE_M, count)
                    return np.column_stack([np.array(xy), z])
    raise RuntimeError("no placement of the spheres found")


def sphere_leaves(rng, count=HET_DISCS, radius_m=HET_RADIUS_M):
    """Disc centres uniform in the sphere, normals uniform on the sphere."""
    r = radius_m * rng.uniform(0.0, 1.0, count) ** (1.0 / 3.0)
    direction = rng.normal(size=(count, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    return r[:, None] * direction, normals(rng, count, "uni")


def spheres_file(out, name, centres, tile_m):
    """The sphere centres and their periodic copies."""
    placed = periodic_copies(centres, HET_RADIUS_M, tile_m)
    return placed


def het_discrete(out, centres, optics=None, tile_m=HET_TILE_M, discs=HET_DISCS):
    rng = np.random.default_rng([SEED, 1])
    leaf_centres, leaf_normals = sphere_leaves(rng, discs)
    write_def(os.path.join(out, "discs", "het01_sphere.def"), HET_DISC_M, leaf_centres,
              leaf_normals)
    placed = spheres_file(out, "het01", centres, tile_m)
    with open(os.path.join(out, "het01_trees.csv"), "w") as f:
        f.write("x,y,model,rotation_deg,scale,z_m\n")
        for x, y, z in placed:
            f.write(f"{x:.3f},{y:.3f},sphere,0,1,{z:.3f}\n")
    cfg = base_config("het01", tile_m, optics, "HET01_DIS_UNI_{band}_20")
    cfg["canopy"] = facets_canopy("het01_trees.csv", {"sphere": "discs/het01_sphere.def"}, optics)
    return cfg


def het_turbid(out, name, centres, optics, experiment, tile_m=HET_TILE_M):
    placed = spheres_file(out, name, centres, tile_m)
    with open(os.path.join(out, f"{name}_crowns.csv"), "w") as f:
        f.write("x,y,base_m,radius_m,half_height_m,crown_lai\n")
        for x, y, z in placed:
            f.write(f"{x:.3f},{y:.3f},{z - HET_RADIUS_M:.3f},{HET_RADIUS_M},{HET_RADIUS_M},"
                    f"{HET_LAI}\n")
    cfg = base_config(name, tile_m, optics, experiment)
    cfg["canopy"] = {"crowns_file": f"{name}_crowns.csv", "crown_shape": "ellipsoid",
                     "pai": 1.0, "cover": 0.471, "lad": "spherical", "leaf_size_m": HET_DISC_M,
                     "dbh_m": 0.0, "green_fraction": 1.0, "bark_fraction": 0.0,
                     "leaf_reflectance": per_band("reflectance", optics),
                     "leaf_transmittance": per_band("transmittance", optics)}
    return cfg


# RAMI-IV's lidar: a 50 m footprint lit uniformly (the beam's half-angle 2 sigma = 25 m / range),
# a delta pulse (1 ps: its neighbour bins get e^-500 of it), the rows 10 window bins each.
LIDAR_FOOTPRINT_M, LIDAR_SHOTS, LIDAR_ROWS_PER_BIN = 50.0, 10, 10
SPEED_OF_LIGHT_M_S = 299792458.0


def lidar_config(cfg, height_bin_m, top_m):
    """The scene's configuration for `glaswave run` and RAMI-IV's lidar measurements."""
    lidar = json.loads(json.dumps(cfg))
    name = lidar.pop("_scene")
    del lidar["brf"]
    altitude_m = lidar["track"]["altitude_m"]
    window_bin_m = height_bin_m / LIDAR_ROWS_PER_BIN
    # The ground's return two thirds into the window: room for the canopy and a half above it.
    bins = int(math.ceil(1.5 * (1.5 * top_m) / window_bin_m))
    lidar["sensor"].update({"beam_profile": "uniform",
                            "divergence_sigma_rad": LIDAR_FOOTPRINT_M / 4.0 / altitude_m,
                            "pulse_sigma_ns": 0.001,
                            "bin_ns": 2.0 * window_bin_m / SPEED_OF_LIGHT_M_S * 1e9,
                            "bins": bins})
    lidar["track"]["points"] = [{"lat_deg": 0.0, "lon_deg": 0.0}] * LIDAR_SHOTS
    # Not flagged for want of a Gaussian fit: RAMI asks for the return alone.
    lidar["output"] = {"footprints": False, "per_order": True, "metrics": False,
                       "rami": {"measurements": ["lidar_sgl_co", "lidar_tot"],
                                "experiment": cfg["brf"]["rami"]["experiment"].replace("_20", ""),
                                "model": "glaswave", "height_bin_m": height_bin_m}}
    lidar["_scene"] = f"{name}_lidar"
    return lidar


def make_scenes(out):
    os.makedirs(out, exist_ok=True)
    configs = [turbid_layer(lad) for lad in LADS] + [discrete_layer(lad, out) for lad in LADS]
    centres = sphere_centres()
    configs.append(het_discrete(out, centres))
    configs.append(het_turbid(out, "het02", centres, CONSERVATIVE, "HET02_TUR_UNI_{band}_20"))
    configs.append(het_turbid(out, "het03", centres, None, "HET03_TUR_UNI_{band}_20"))
    het_top_m = HET_CENTRE_M[1] + HET_RADIUS_M
    configs += [lidar_config(cfg, 0.05, HOM_DEPTH_M) for cfg in configs[:3]]
    configs += [lidar_config(cfg, 0.5, het_top_m) for cfg in configs[6:9]]
    written = []
    for cfg in configs:
        name = cfg.pop("_scene")
        path = os.path.join(out, f"{name}.json")
        with open(path, "w") as f:
            json.dump(cfg, f, indent=1)
            f.write("\n")
        written.append(path)
    return written


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)),
                        help="folder for the configurations and discs/ (default: share/rami)")
    args = parser.parse_args()
    for path in make_scenes(args.out):
        print(path)


if __name__ == "__main__":
    main()
