#!/usr/bin/python3
"""RAMI's scenes (share/rami) through `glaswave brf`: ROMC's measurements, their Monte Carlo
standard errors and each scene's energy closure (docs/guide/rami.md).

Usage: rami.py --glaswave BINARY [--quick] [--out DIR] [--threads N]

The scenes are built by share/rami/make_scenes.py into DIR/scenes (the disc files are generated,
the same bits each time). Each is traced once with `glaswave brf`, RAMI's measurements asked for
(brf.rami), under DIR/runs/ named by a hash of the resolved configuration, so that an interrupted
study picks up where it stopped. Written: rami.csv and rami.md (per scene and band: albedo,
fabs, ftran, the closure fabs + falb + ftran (1 - soil) and each one's standard error, the BRF at
1 deg and either side of the hotspot), brfpp.png and its CSV (every scene's principal plane),
hotspot.png and its CSV (HET01's discs against their turbid twin HET03 with leaf_size_m the
discs' radius and their diameter), the ROMC files of every run under runs/, and summary.json.
RAMI-IV's lidar measurements (lidar_sgl_co, lidar_tot) come from `glaswave run` over the scenes'
`<scene>_lidar.json` (the turbid layers and HET01-03: 10 shots at the centre, a uniform 50 m
footprint, a delta pulse): lidar.csv, lidar.png and a table in rami.md.
"""
import argparse
import copy
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "rami"))
import make_scenes  # noqa: E402
from studies import write_atomic, write_csv  # noqa: E402  (the seed driver's writers)

SCENES = ["hom_tur_pla", "hom_tur_ere", "hom_tur_uni", "hom_dis_pla", "hom_dis_ere",
          "hom_dis_uni", "het01", "het02", "het03"]
# Photons a scene: the full run's fits ~20 minutes on two cores.
PHOTONS = {"quick": 1500, "full": 40000}
PATH_KEYS = [("canopy", "crowns_file"), ("canopy", "facets", "trees_file")]
# RAMI-IV's lidar: where it applies (make_scenes.py says why not the discrete layers), and the
# rays of each of the 10 shots.
LIDAR_SCENES = ["hom_tur_pla", "hom_tur_ere", "hom_tur_uni", "het01", "het02", "het03"]
LIDAR_RAYS = {"quick": 200, "full": 10000}


def log(message):
    print("rami: " + message, file=sys.stderr, flush=True)


def absolute_paths(document, folder):
    """The scene's files named from anywhere: the resolved configuration lives under runs/."""
    for path in PATH_KEYS:
        node = document
        for key in path[:-1]:
            node = node.get(key, {}) if isinstance(node, dict) else {}
        if isinstance(node, dict) and path[-1] in node:
            node[path[-1]] = os.path.join(folder, node[path[-1]])
    models = document.get("canopy", {}).get("facets", {}).get("models", {})
    for name in models:
        models[name] = os.path.join(folder, models[name])
    return document


def run_brf(glaswave, runs_dir, document, label, threads):
    text = json.dumps(document, sort_keys=True, indent=1)
    stem = os.path.join(runs_dir, "brf-" + hashlib.sha1(text.encode()).hexdigest()[:10])
    out = stem + ".out"
    if os.path.exists(os.path.join(out, "brf.json")):
        return out
    write_atomic(stem + ".json", text)
    shutil.rmtree(out, ignore_errors=True)  # an interrupted run: start it again
    start = time.monotonic()
    result = subprocess.run([glaswave, "brf", stem + ".json", "--out", out, "--quiet",
                             "--threads", str(threads)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"glaswave brf {label} failed ({result.returncode}): "
                           f"{result.stderr.strip()}")
    log(f"brf {label}: {time.monotonic() - start:.1f} s")
    return out


def run_lidar(glaswave, runs_dir, document, label, threads):
    """`glaswave run` with output.rami: RAMI-IV's lidar files under the run's rami/."""
    text = json.dumps(document, sort_keys=True, indent=1)
    stem = os.path.join(runs_dir, "run-" + hashlib.sha1(text.encode()).hexdigest()[:10])
    out = stem + ".out"
    if os.path.isdir(os.path.join(out, "rami")):
        return out
    write_atomic(stem + ".json", text)
    shutil.rmtree(out, ignore_errors=True)
    start = time.monotonic()
    result = subprocess.run([glaswave, "run", stem + ".json", "--out", out, "--quiet",
                             "--threads", str(threads)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"glaswave run {label} failed ({result.returncode}): "
                           f"{result.stderr.strip()}")
    log(f"run {label}: {time.monotonic() - start:.1f} s")
    return out


def read_lidar(path):
    """RAMI-IV's lidar file: rows, columns, interval; then height, signal, its deviation."""
    with open(path) as f:
        lines = [line.split() for line in f.read().splitlines() if line.strip()]
    return np.array([[float(v) for v in line] for line in lines[1:]])


def lidar_study(glaswave, scenes_dir, runs_dir, out_dir, mode, threads, summary):
    """The lidar measurements of each scene where they apply, NIR (RAMI's band for abstract
    canopies; CON for HET02): lidar.csv, lidar.png, and rows for rami.md."""
    rows, profiles, lines = [], {}, []
    for name in LIDAR_SCENES:
        with open(os.path.join(scenes_dir, f"{name}_lidar.json")) as f:
            document = absolute_paths(json.load(f), scenes_dir)
        document["simulation"]["rays_per_shot"] = LIDAR_RAYS[mode]
        out = run_lidar(glaswave, runs_dir, document, name, threads)
        band = "CON" if name == "het02" else "NIR"
        experiment = document["output"]["rami"]["experiment"].replace("{band}", band)
        parts = {}
        for m in ("lidar_sgl_co", "lidar_tot"):
            table = read_lidar(os.path.join(out, "rami", f"{m}_glaswave-{experiment}.mes"))
            parts[m] = table
            for z, value, sd in table:
                rows.append([name, band, m, z, value, sd])
        profiles[name] = parts
        sums = {m: (float(t[:, 1].sum()), float(math.sqrt((t[:, 2] ** 2).sum())))
                for m, t in parts.items()}
        ground = {m: float(t[0, 1]) for m, t in parts.items()}
        summary.setdefault("lidar", {})[name] = {"band": band, "sums": sums, "first_row": ground}
        lines.append(f"| {name} | {band} | {sums['lidar_sgl_co'][0]:.4f} ± "
                     f"{sums['lidar_sgl_co'][1]:.4f} | {sums['lidar_tot'][0]:.4f} ± "
                     f"{sums['lidar_tot'][1]:.4f} | {ground['lidar_sgl_co']:.4f} | "
                     f"{ground['lidar_tot']:.4f} |")
    write_csv(os.path.join(out_dir, "lidar.csv"),
              ["scene", "band", "measurement", "height_m", "signal", "signal_sd"], rows)
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.6))
    for ax, names in zip(axes, [LIDAR_SCENES[:3], LIDAR_SCENES[3:]]):
        for name in names:
            for m, style in (("lidar_tot", "-"), ("lidar_sgl_co", ":")):
                t = profiles[name][m]
                # The first row holds the ground's return: drawn beside the canopy's, not in it.
                ax.plot(t[1:, 1], t[1:, 0], style, label=f"{name} {m}")
        ax.set_xlabel("return signal per row (apparent reflectance)")
        ax.set_ylabel("height (m)")
        ax.legend(fontsize=7)
    axes[0].set_title("RAMI-IV lidar, 1 m turbid layers (0.05 m rows)")
    axes[1].set_title("RAMI-IV lidar, HET01-03 (0.5 m rows)")
    figure.tight_layout()
    figure.savefig(os.path.join(out_dir, "lidar.png"), dpi=110)
    plt.close(figure)
    header = ["", f"RAMI-IV's lidar: 10 shots of {LIDAR_RAYS[mode]} rays at the centre, a "
              "uniform 50 m footprint, a delta pulse; each row's return over E_t T A_T f_fov / "
              "(pi R^2), summed over the rows (+- from the rows' standard errors over the "
              "shots); the first row holds the ground's return.", "",
              "| scene | band | lidar_sgl_co, sum | lidar_tot, sum | sgl_co, first row | "
              "tot, first row |", "|---|---|---|---|---|---|"]
    return header + lines


def read_mes(path):
    """ROMC's BRF file: header (rows, columns, ratio), rows SZA VZA SAA-VAA BRF SD (radians)."""
    with open(path) as f:
        lines = [line.split() for line in f.read().splitlines() if line.strip()]
    return np.array([[float(v) for v in line] for line in lines[1:]])


def signed_zenith(table):
    """RAMI's signed view zenith: + toward the sun (SAA - VAA = 0), - away from it."""
    sign = np.where(np.abs(table[:, 2]) < 1e-6, 1.0, -1.0)
    return sign * np.degrees(table[:, 1])


def view_value(band, zenith, azimuth):
    for view in band["views"]:
        if view["zenith_deg"] == zenith and view["azimuth_deg"] == azimuth:
            return view["brf"], view["brf_stderr"]
    return math.nan, math.nan


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--glaswave", required=True, help="the glaswave binary")
    parser.add_argument("--quick", action="store_true", help="small runs, for a check")
    parser.add_argument("--out", default="out/studies/rami")
    parser.add_argument("--threads", type=int, default=0)
    args = parser.parse_args()
    mode = "quick" if args.quick else "full"
    start = time.monotonic()
    scenes_dir = os.path.abspath(os.path.join(args.out, "scenes"))
    runs_dir = os.path.join(args.out, "runs")
    os.makedirs(runs_dir, exist_ok=True)
    make_scenes.make_scenes(scenes_dir)

    runs = {}
    for name in SCENES + ["het03_diameter"]:
        scene = "het03" if name == "het03_diameter" else name
        with open(os.path.join(scenes_dir, scene + ".json")) as f:
            document = absolute_paths(json.load(f), scenes_dir)
        document["brf"]["photons"] = PHOTONS[mode]
        if name == "het03_diameter":  # the turbid twin with leaf_size_m the discs' diameter
            document["canopy"]["leaf_size_m"] = 2 * make_scenes.HET_DISC_M
            document["brf"]["rami"]["experiment"] = "HET03D_TUR_UNI_{band}_20"
        out = run_brf(args.glaswave, runs_dir, copy.deepcopy(document), name, args.threads)
        with open(os.path.join(out, "brf.json")) as f:
            runs[name] = (out, document, json.load(f))

    rows, planes, summary = [], [], {"mode": mode, "photons": PHOTONS[mode], "scenes": {}}
    for name, (out, document, result) in runs.items():
        soil = document["terrain"]["soil_reflectance"]
        for band in result["bands"]:
            b = band["name"]
            rho = soil[b] if isinstance(soil, dict) else soil
            closure = band["albedo"] + band["fabs"] + band["ftran"] * (1 - rho)
            closure_se = band["closure_stderr"]  # of the photons' own closures
            nadir, nadir_se = view_value(band, 1.0, 0.0)
            hot, hot_se = view_value(band, 21.0, 0.0)
            fwd, fwd_se = view_value(band, 21.0, 180.0)
            rows.append([name, b, band["albedo"], band["albedo_stderr"], band["fabs"],
                         band["fabs_stderr"], band["ftran"], band["ftran_stderr"], closure,
                         closure_se, nadir, nadir_se, hot, hot_se, fwd, fwd_se])
            log(f"{name} {b}: fabs {band['fabs']:.4f} +- {band['fabs_stderr']:.4f}, falb "
                f"{band['albedo']:.4f} +- {band['albedo_stderr']:.4f}, ftran {band['ftran']:.4f}"
                f" +- {band['ftran_stderr']:.4f}; closure {closure:.4f} +- {closure_se:.4f}")
            summary["scenes"].setdefault(name, {})[b] = {
                "fabs": band["fabs"], "falb": band["albedo"], "ftran": band["ftran"],
                "closure": closure, "closure_stderr": closure_se}
            experiment = band["rami_experiment"]
            table = read_mes(os.path.join(out, "rami", f"brfpp_glaswave-{experiment}.mes"))
            for z, row in zip(signed_zenith(table), table):
                planes.append([name, b, z, row[3], row[4]])

    header = ["scene", "band", "falb", "falb_se", "fabs", "fabs_se", "ftran", "ftran_se",
              "closure", "closure_se", "brf_1deg", "brf_1deg_se", "brf_21deg_sunward",
              "brf_21deg_sunward_se", "brf_21deg_away", "brf_21deg_away_se"]
    write_csv(os.path.join(args.out, "rami.csv"), header, rows)
    lines = [f"Photons a scene: {PHOTONS[mode]} ({mode}); sun at 20 deg. Each value +- its "
             "Monte Carlo standard error.", "",
             "| scene | band | falb | fabs | ftran | closure | BRF 1 deg | BRF 21 deg sunward |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r[0]} | {r[1]} | {r[2]:.4f} ± {r[3]:.4f} | {r[4]:.4f} ± {r[5]:.4f} | "
                     f"{r[6]:.4f} ± {r[7]:.4f} | {r[8]:.5f} ± {r[9]:.5f} | "
                     f"{r[10]:.4f} ± {r[11]:.4f} | {r[12]:.4f} ± {r[13]:.4f} |")
    lines += lidar_study(args.glaswave, scenes_dir, runs_dir, args.out, mode, args.threads,
                         summary)
    write_atomic(os.path.join(args.out, "rami.md"), "\n".join(lines) + "\n")
    write_csv(os.path.join(args.out, "brfpp.csv"), ["scene", "band", "signed_vza_deg", "brf",
                                                     "brf_se"], planes)

    figure, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, band in zip(axes, ["RED", "NIR"]):
        for name in SCENES:
            points = [p for p in planes if p[0] == name and p[1] == band]
            if points:
                ax.plot([p[2] for p in points], [p[3] for p in points], label=name,
                        linestyle="--" if "tur" in name or name in ("het02", "het03") else "-")
        ax.set_title(f"brfpp, {band}, sun at 20 deg")
        ax.set_xlabel("view zenith (deg, + toward the sun)")
        ax.set_ylabel("BRF")
    axes[1].legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(os.path.join(args.out, "brfpp.png"), dpi=110)
    plt.close(figure)

    hot_rows = [p for p in planes if p[0] in ("het01", "het03", "het03_diameter")]
    write_csv(os.path.join(args.out, "hotspot.csv"), ["scene", "band", "signed_vza_deg", "brf",
                                                       "brf_se"], hot_rows)
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    labels = {"het01": "HET01 discs (r 0.1 m)", "het03": "turbid, leaf_size_m 0.1 (r)",
              "het03_diameter": "turbid, leaf_size_m 0.2 (2r)"}
    for ax, band in zip(axes, ["RED", "NIR"]):
        for name, label in labels.items():
            points = [p for p in hot_rows if p[0] == name and p[1] == band]
            ax.errorbar([p[2] for p in points], [p[3] for p in points],
                        yerr=[p[4] for p in points], label=label, capsize=2)
        ax.set_title(f"HET01 and its turbid twins, brfpp, {band}")
        ax.set_xlabel("view zenith (deg, + toward the sun)")
        ax.set_ylabel("BRF")
        ax.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(os.path.join(args.out, "hotspot.png"), dpi=110)
    plt.close(figure)

    # The hotspot: mean of brfpp at 19 and 21 deg sunward, each twin against the discs.
    for band in ["RED", "NIR"]:
        def hotspot(name):
            values = [p for p in hot_rows if p[0] == name and p[1] == band and
                      abs(p[2] - 20.0) < 1.5]
            return (float(np.mean([p[3] for p in values])),
                    float(math.sqrt(sum(p[4] ** 2 for p in values)) / len(values)))

        discs = hotspot("het01")
        summary.setdefault("hotspot", {})[band] = {
            name: {"brf": hotspot(name)[0], "stderr": hotspot(name)[1],
                   "vs_discs_pct": 100 * (hotspot(name)[0] / discs[0] - 1)}
            for name in labels}
    summary["seconds"] = round(time.monotonic() - start, 1)
    write_atomic(os.path.join(args.out, "summary.json"), json.dumps(summary, indent=1) + "\n")
    log(f"done in {summary['seconds']} s: {args.out}")


if __name__ == "__main__":
    main()
