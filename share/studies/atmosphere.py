#!/usr/bin/python3
"""The GLAS elevation bias and canopy height error against a cloud's optical depth and height.

Usage: atmosphere.py --glaswave BINARY [--quick] [--out DIR] [--threads N]

The seed's scene (base.json: its forest, and the same plane bare) seen by GLAS (the glas preset,
1064 nm) through the `clear` atmosphere and through `clear` with a cloud added: a layer 500 m
thick whose base is H above the ground, of vertical optical depth tau, single-scattering albedo 1
and a Henyey-Greenstein phase function of the presets' asymmetry (0.85, water, below 5 km; 0.77,
ice, above: `stratus` and `cirrus`). For each (tau, H) over each scene: the mean over the valid
shots of the elevation bias (ground_elev_est - elev, the true ground under the footprint centre)
and, over the forest, of the canopy height error (canopy_height_est - canopy_height_true), each
beside the same without the cloud; the shots' atmosphere_delay_m and
atmosphere_scattered_fraction (the truth); the valid shots. Runs are cached under DIR/runs by a
hash of the configuration (share/studies/studies.py's Runner); atmosphere.csv and
atmosphere.png, summary.json. And the sun through the same clouds at 1 km: `glaswave brf` over
the forest (sun 30 degrees from the zenith in the south) through `clear` and each cloud, the
direct and diffuse light reaching the canopy, its nadir and hotspot reflectance factors under
that light and the nadir reflectance at the top of the layers: atmosphere_brf.csv.
"""
import argparse
import copy
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import studies as seed  # noqa: E402  (the seed's driver: its Runner and writers)

import numpy as np  # noqa: E402

plt = seed.plt

BAND = "1064"
TAUS = [0.0, 0.1, 0.2, 0.5, 1.0, 2.0]
HEIGHTS_KM = [1.0, 3.0, 10.0]
THICKNESS_M = 500.0
SIZES = {"quick": {"shots": 4, "rays_per_shot": 1500, "taus": [0.0, 0.5, 2.0],
                   "heights_km": [1.0, 10.0], "photons": 5000},
         "full": {"shots": 40, "rays_per_shot": 5000, "taus": TAUS, "heights_km": HEIGHTS_KM,
                  "photons": 100000}}
SUN = {"sun_zenith_deg": 30.0, "sun_azimuth_deg": 180.0, "scene_size_m": 60.0,
       "image_resolution_m": 6.0,
       "views": [{"zenith_deg": 0.0, "azimuth_deg": 0.0},
                 {"zenith_deg": 30.0, "azimuth_deg": 180.0}]}
SCENES = {"forest": {"sensor": {"preset": "glas"}},
          "bare": {"sensor": {"preset": "glas"}, "canopy": None}}


def cloud_layer(tau, height_km):
    g = 0.85 if height_km < 5.0 else 0.77
    base = 1000.0 * height_km
    return {"base_m": base, "top_m": base + THICKNESS_M, "above": "ground", "optical_depth": tau,
            "single_scattering_albedo": 1.0, "phase": {"hg_g": g}}


def clear_layers(ds):
    """`clear`'s layers as the run resolved them (the configuration shots.nc records)."""
    return seed.resolved_config(ds)["atmosphere"]["layers"]


def shot_values(ds):
    d = ds.sel(band=seed.band_value(ds, BAND))
    valid = (d.quality_flag.values == 1) & np.isfinite(d.ground_elev_est.values)
    elevation = d.ground_elev_est.values - d.elev.values
    height = d.canopy_height_est.values - d.canopy_height_true.values
    return {
        "valid": int(valid.sum()), "shots": int(d.sizes["shot"]),
        "elev_bias_m": float(np.mean(elevation[valid])) if valid.any() else float("nan"),
        "height_error_m": float(np.mean(height[valid])) if valid.any() else float("nan"),
        "delay_m": float(np.nanmean(d.atmosphere_delay_m.values)),
        "scattered": float(np.nanmean(d.atmosphere_scattered_fraction.values)),
        "transmission": float(np.nanmean(d.atmosphere_transmission.values)),
        "energy_J": float(np.nanmean(d.rx_energy.values)),
    }


def study_sun(runner, size, out, layers):
    """brf over the forest through `clear` (its `layers`) and a cloud at 1 km of each tau."""
    rows = []
    for tau in size["taus"]:
        cloud = [cloud_layer(tau, 1.0)] if tau > 0.0 else []
        sets = dict(SCENES["forest"], atmosphere={"layers": copy.deepcopy(layers) + cloud})
        folder = runner.brf("base.json", sets, size, SUN, f"forest brf tau={tau:g} H=1 km")
        with open(os.path.join(folder, "brf.json")) as f:
            band = next(b for b in json.load(f)["bands"] if b["name"] == BAND)
        rows.append([tau, band["direct_transmittance"], band["diffuse_transmittance"],
                     band["views"][0]["brf"], band["views"][1]["brf"],
                     band["views"][0]["toa_brf"], band["toa_albedo"]])
    header = ["cloud_tau", "direct_transmittance", "diffuse_transmittance", "hdrf_nadir",
              "hdrf_hotspot", "toa_brf_nadir", "toa_albedo"]
    seed.write_csv(os.path.join(out, "atmosphere_brf.csv"), header, rows)
    return [dict(zip(header, [seed.format_value(x) for x in r])) for r in rows]


def study(runner, size, out):
    rows = []
    sun = None
    for scene, sets in SCENES.items():
        clear_sets = dict(sets, atmosphere="clear")
        clear = runner.run("base.json", clear_sets, size, f"{scene} clear")
        base = shot_values(clear)
        layers = clear_layers(clear)
        if scene == "forest":
            sun = study_sun(runner, size, out, layers)
        for height_km in size["heights_km"]:
            for tau in size["taus"]:
                if tau == 0.0:
                    v = base
                else:
                    cloudy = dict(sets, atmosphere={"layers": copy.deepcopy(layers) +
                                                    [cloud_layer(tau, height_km)]})
                    v = shot_values(runner.run("base.json", cloudy, size,
                                               f"{scene} tau={tau:g} H={height_km:g} km"))
                rows.append([scene, height_km, tau, v["valid"], v["shots"], v["elev_bias_m"],
                             v["elev_bias_m"] - base["elev_bias_m"],
                             v["height_error_m"] if scene == "forest" else float("nan"),
                             (v["height_error_m"] - base["height_error_m"]) if scene == "forest"
                             else float("nan"),
                             v["delay_m"], v["scattered"], v["transmission"],
                             v["energy_J"] / base["energy_J"]])
    header = ["scene", "cloud_base_km", "cloud_tau", "valid_shots", "shots", "elev_bias_m",
              "elev_bias_change_m", "height_error_m", "height_error_change_m",
              "atmosphere_delay_m", "atmosphere_scattered_fraction", "atmosphere_transmission",
              "energy_ratio"]
    seed.write_csv(os.path.join(out, "atmosphere.csv"), header, rows)
    plot(rows, size, os.path.join(out, "atmosphere.png"))
    seed.write_atomic(os.path.join(out, "atmosphere.md"), markdown(rows, size))
    return [dict(zip(header, [seed.format_value(x) for x in r])) for r in rows], sun


def plot(rows, size, path):
    figure, axes = plt.subplots(1, 3, figsize=(13.5, 4.3))
    for k, height_km in enumerate(size["heights_km"]):
        for scene, style in (("bare", "--"), ("forest", "-")):
            mine = [r for r in rows if r[0] == scene and r[1] == height_km]
            taus = [r[2] for r in mine]
            axes[0].plot(taus, [r[6] for r in mine], style + "o", color=f"C{k}", ms=4,
                         label=f"{scene}, cloud base {height_km:g} km")
            axes[2].plot(taus, [r[9] / 2.0 for r in mine], style + "o", color=f"C{k}", ms=4)
            if scene == "forest":
                axes[1].plot(taus, [r[8] for r in mine], style + "o", color=f"C{k}", ms=4,
                             label=f"cloud base {height_km:g} km")
    axes[0].set_ylabel("change of the mean elevation bias (m)")
    axes[1].set_ylabel("change of the mean canopy height error (m)")
    axes[2].set_ylabel("half the truth's atmosphere_delay_m (m)")
    axes[2].set_yscale("symlog", linthresh=0.01)
    for ax in axes:
        ax.set_xlabel("cloud optical depth")
        ax.axhline(0.0, color="0.6", lw=0.8)
    axes[0].legend(fontsize=7)
    axes[1].legend(fontsize=7)
    figure.suptitle(f"GLAS (1064 nm) through a cloud above `clear`: {size['shots']} shots of "
                    f"{size['rays_per_shot']} rays a case, the seed's forest and bare plane",
                    fontsize=10)
    figure.tight_layout()
    seed.save_figure(figure, path)


def markdown(rows, size):
    def cell(v, digits=2):
        return "" if not math.isfinite(v) else f"{v:+.{digits}f}"

    lines = ["| cloud base (km) | τ | bare: Δ elevation bias (m) | forest: Δ elevation bias (m) "
             "| forest: Δ canopy height error (m) | forest: delay/2 (m) | forest: scattered "
             "| valid shots (bare, forest) |", "|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for height_km in size["heights_km"]:
        for tau in size["taus"]:
            bare = next(r for r in rows if r[0] == "bare" and r[1] == height_km and r[2] == tau)
            forest = next(r for r in rows
                          if r[0] == "forest" and r[1] == height_km and r[2] == tau)
            lines.append(f"| {height_km:g} | {tau:g} | {cell(bare[6])} | {cell(forest[6])} | "
                         f"{cell(forest[8])} | {forest[9] / 2.0:.3f} | {forest[10]:.3f} | "
                         f"{bare[3]}/{bare[4]}, {forest[3]}/{forest[4]} |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--glaswave", required=True, help="the glaswave binary")
    parser.add_argument("--quick", action="store_true", help="small runs, for a check")
    parser.add_argument("--out", default="out/studies/atmosphere")
    parser.add_argument("--threads", type=int, default=0)
    args = parser.parse_args()
    mode = "quick" if args.quick else "full"
    os.makedirs(args.out, exist_ok=True)
    runner = seed.Runner(args.glaswave, args.out, args.threads)
    start = time.monotonic()
    size = SIZES[mode]
    cases, sun = study(runner, size, args.out)
    summary = {"mode": mode, "band": BAND, "shots": size["shots"],
               "rays_per_shot": size["rays_per_shot"], "cases": cases, "sun": sun}
    seed.write_atomic(os.path.join(args.out, "summary.json"),
                      json.dumps(summary, indent=1) + "\n")
    seed.log(f"atmosphere {mode}: {runner.count} glaswave runs in "
             f"{time.monotonic() - start:.0f} s; products in {args.out}")
    for path in sorted(os.listdir(args.out)):
        if os.path.isfile(os.path.join(args.out, path)):
            print(os.path.join(args.out, path))


if __name__ == "__main__":
    main()
