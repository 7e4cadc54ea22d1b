#!/usr/bin/python3
"""One forest as four vegetation sources, and their GEDI waveforms on one figure (issue 24).

Usage: plot_waveforms.py [--glaswave BINARY] [--out PNG] [--reuse] [--rays N]

The forest is share/vegetation/facet_trees.csv: 25 trees of make_facet_tree.py's model (crown
radius 3.5 m from 5 to 14 m, 124.7 m2 of leaves) scaled by 0.82-1.20, on level ground at 300 m.
It is simulated four ways, each with its configuration in share/vegetation/:

  facets.json       the facet trees themselves (leaves, trunk and branches as triangles);
  point_cloud.json  an ALS point cloud cast through the trees' crowns (make_als_cloud.py
                    --trees), voxelised at start, its ground the terrain;
  voxels.json       that cloud's voxel grid, as `glaswave voxelize` writes it;
  crowns.json       turbid ellipsoids of the trees' crowns holding their leaf area (the total;
                    one density for all: make_facet_tree.turbid_crowns, forest_crowns.csv).

The inputs are made under out/vegetation/ when missing (about a minute), each configuration is
run there (runs/NAME; --reuse keeps runs already made; --rays sets rays_per_shot, 10 000 in
the configurations, for a quicker look), and the mean waveform of each run's
three shots is drawn against height above the ground, with the ground and the tallest tree's
top. Default PNG: out/vegetation/waveforms.png. Any failure prints one line,
"plot_waveforms: error: ...", and exits with status 1.
"""
import argparse
import csv
import json
import os
import pathlib
import shutil
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import netCDF4  # noqa: E402
import numpy as np  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(HERE))
from make_facet_tree import MODEL, leaf_area_m2, turbid_crowns  # noqa: E402

DATA = ROOT / "out" / "vegetation"  # where the configurations' ../../out/vegetation/ points
GROUND_M = 300.0  # the plane's elevation_m in every configuration
SOURCES = [  # configuration, label, colour, line style
    ("facets", "facet trees", "darkgreen", "-"),
    ("crowns", "turbid crowns", "0.35", "-"),
    ("voxels", "voxel grid (glaswave voxelize)", "tab:blue", "-"),
    ("point_cloud", "ALS point cloud (voxelised, its own ground)", "tab:orange", "--")]


def run(command):
    done = subprocess.run([str(c) for c in command], capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, command))}: {done.stderr.strip()[-300:]}")


def crowns_pai(rows):
    """canopy.pai that gives turbid crowns (rows of turbid_crowns) the trees' total leaf area:
    per unit area of the crowns' bounding box grown by their mean radius, as glaswave reads a
    crowns_file (canopy/forest.cpp)."""
    x, y, radius = (np.array([r[k] for r in rows]) for k in (0, 1, 3))
    area = (np.ptp(x) + 2 * radius.mean()) * (np.ptp(y) + 2 * radius.mean())
    total = sum(r[5] * 4.0 / 3.0 * np.pi * r[3] ** 2 * r[4] for r in rows)
    return total / area


def make_inputs(glaswave):
    """The tree model, the cloud, its grid and the crowns file under out/vegetation/."""
    DATA.mkdir(parents=True, exist_ok=True)
    python = sys.executable or "/usr/bin/python3"
    if not (DATA / "tree.obj").exists():
        run([python, HERE / "make_facet_tree.py", DATA / "tree.obj"])
    if not (DATA / "forest.las").exists():
        run([python, HERE / "make_als_cloud.py", DATA / "forest.las", "--trees",
             HERE / "facet_trees.csv"])
    if not (DATA / "forest_pad.nc").exists():
        run([glaswave, "voxelize", DATA / "forest.las", "--out", DATA / "forest_pad.nc",
             "--voxel-size-m", "2"])
    rows = turbid_crowns(HERE / "facet_trees.csv")
    with open(DATA / "forest_crowns.csv", "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["x", "y", "base_m", "radius_m", "half_height_m"])
        for x, y, base, radius, half, _ in rows:
            out.writerow([x, y, f"{base:.4f}", f"{radius:.4f}", f"{half:.4f}"])
    pai = json.loads((HERE / "crowns.json").read_text())["canopy"]["pai"]
    if abs(pai / crowns_pai(rows) - 1.0) > 0.005:
        raise RuntimeError(f"crowns.json's canopy.pai {pai} is not the trees' "
                           f"{crowns_pai(rows):.4f}: set it so")


def mean_waveform(shots_nc):
    """Heights above the footprint's ground (m) and the shots' mean received power (W)."""
    with netCDF4.Dataset(shots_nc) as ds:
        ds.set_auto_mask(False)
        wave = ds["rx_waveform"][:, 0, :]
        bins = wave.shape[-1]
        heights = [np.linspace(ds["elev_bin0"][i], ds["elev_lastbin"][i], bins) - ds["elev"][i]
                   for i in range(wave.shape[0])]
    grid = heights[0]
    mean = np.mean([np.interp(grid, h[::-1], w[::-1]) for h, w in zip(heights, wave)], axis=0)
    return grid, mean


def plot(runs, path):
    fig, ax = plt.subplots(figsize=(6.4, 5.6))
    peak = 0.0
    for (name, label, colour, style), (height, power) in zip(SOURCES, runs):
        ax.plot(power * 1e9, height, color=colour, ls=style, lw=2.5 if name == "facets" else 1.5,
                label=label)
        peak = max(peak, power.max() * 1e9)
    scales = [float(r["scale"]) for r in csv.DictReader(open(HERE / "facet_trees.csv"))]
    top = MODEL["height_m"] * max(scales)
    ax.axhline(0.0, color="saddlebrown", lw=1, ls="--", label="ground (truth)")
    ax.axhline(top, color="forestgreen", lw=1, ls=":",
               label=f"tallest tree, {top:.1f} m (truth)")
    ax.set_ylim(-5.0, top + 6.0)
    ax.set_xlim(0.0, 1.05 * peak)
    ax.set_xlabel("received power (nW), mean of 3 shots")
    ax.set_ylabel("height above the ground (m)")
    area = leaf_area_m2(MODEL["leaves"], MODEL["leaf_size_m"])
    ax.set_title(f"One forest, four sources: 25 trees of {area:.0f} m² of leaves\n"
                 "GEDI at 420 km, 10 000 rays, order 8", fontsize=10)
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    part = str(path) + ".part"
    try:
        fig.savefig(part, format="png", dpi=100, bbox_inches="tight")
        os.replace(part, path)
    finally:
        plt.close(fig)
        if os.path.exists(part):
            os.remove(part)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--glaswave", default=ROOT / "build" / "pipeline" / "glaswave")
    parser.add_argument("--out", default=DATA / "waveforms.png")
    parser.add_argument("--reuse", action="store_true", help="keep runs already made")
    parser.add_argument("--rays", type=int, help="rays a shot (default: the configurations')")
    args = parser.parse_args()
    try:
        make_inputs(args.glaswave)
        runs = []
        for name, _, _, _ in SOURCES:
            out = DATA / "runs" / name
            if not (args.reuse and (out / "shots.nc").exists()):
                shutil.rmtree(out, ignore_errors=True)
                rays = ["--set", f"simulation.rays_per_shot={args.rays}"] if args.rays else []
                run([args.glaswave, "run", HERE / f"{name}.json", "--out", out, "--quiet"] + rays)
            runs.append(mean_waveform(out / "shots.nc"))
        plot(runs, args.out)
    except (OSError, RuntimeError, KeyError, ValueError) as error:
        print(f"plot_waveforms: error: {error}", file=sys.stderr)
        return 1
    print(f"plot_waveforms: {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
