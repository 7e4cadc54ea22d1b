#!/usr/bin/python3
"""The seed's figures and Table 3 from the study configurations in share/studies/ (PRODUCT.md 7).

Usage: studies.py --glaswave BINARY [--quick] [--out DIR] [--threads N]

Each study is one JSON file here (table3, brf_validation, pai_waveforms, slope, wi_vpai, scene)
over the base case base.json (the seed's Tables 1 and 2). A scene is the base configuration
with some keys overridden; it is written resolved into DIR/runs/ and simulated once with
`glaswave run` (and `glaswave brf` where a study needs the BRF), under a name that hashes the
resolved configuration and the run size, so that studies sharing a scene share its run and an
interrupted script picks up where it stopped. Every figure is written with the CSV of what it
plots; table3.csv and table3.md put glaswave's Table 3 beside the seed's.

When `glaswave brf` is refused (a build without it), the studies that need it are skipped with
one line on stderr each and listed in DIR/skipped.txt; everything else is written.
"""
import argparse
import copy
import csv
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
import xarray as xr  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SPEED_OF_LIGHT_M_S = 299792458.0


class BrfUnavailable(Exception):
    """`glaswave brf` refused to run: this build has no BRF mode."""


def log(message):
    print("studies: " + message, file=sys.stderr, flush=True)


def load_study(name):
    with open(os.path.join(HERE, name + ".json")) as f:
        return json.load(f)


def apply_set(document, key, value):
    """--set KEY=VALUE on a configuration dict: the dotted path, objects made as needed."""
    node = document
    parts = key.split(".")
    for part in parts[:-1]:
        if not isinstance(node.get(part), dict):
            node[part] = {}
        node = node[part]
    node[parts[-1]] = value


def write_atomic(path, text):
    temporary = path + ".part"
    with open(temporary, "w") as f:
        f.write(text)
    os.replace(temporary, path)


def save_figure(figure, path):
    temporary = path + ".part.png"
    figure.savefig(temporary, dpi=110)
    plt.close(figure)
    os.replace(temporary, path)


def write_csv(path, header, rows):
    temporary = path + ".part"
    with open(temporary, "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(header)
        for row in rows:
            writer.writerow([format_value(v) for v in row])
    os.replace(temporary, path)


def format_value(v):
    if isinstance(v, float):
        return "" if not math.isfinite(v) else f"{v:.6g}"
    return v


class Runner:
    """Runs glaswave on resolved configurations, each once, under DIR/runs/."""

    def __init__(self, glaswave, out_dir, threads):
        self.glaswave = glaswave
        self.runs_dir = os.path.join(out_dir, "runs")
        self.threads = threads
        self.count = 0
        os.makedirs(self.runs_dir, exist_ok=True)

    def resolve(self, config, sets, size):
        with open(os.path.join(HERE, config)) as f:
            document = json.load(f)
        for key, value in sets.items():
            apply_set(document, key, copy.deepcopy(value))
        if "shots" in size:
            apply_set(document, "track.shots", size["shots"])
        if "rays_per_shot" in size:
            apply_set(document, "simulation.rays_per_shot", size["rays_per_shot"])
        return document

    def _prepare(self, command, document):
        text = json.dumps(document, sort_keys=True, indent=1)
        digest = hashlib.sha1((command + text).encode()).hexdigest()[:10]
        # Named by content alone, so that every study asking for this scene finds the same run.
        stem = os.path.join(self.runs_dir, f"{command}-{digest}")
        if not os.path.exists(stem + ".json"):
            write_atomic(stem + ".json", text)
        return stem

    def _glaswave(self, command, stem, label, product):
        out = stem + ".out"
        if os.path.exists(os.path.join(out, product)):
            return out
        shutil.rmtree(out, ignore_errors=True)  # an interrupted run: start it again
        self.count += 1
        start = time.monotonic()
        args = [self.glaswave, command, stem + ".json", "--out", out, "--quiet",
                "--threads", str(self.threads)]
        result = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if result.returncode != 0:
            message = result.stderr.strip().splitlines()[-1] if result.stderr.strip() else ""
            if command == "brf" and result.returncode == 2 and "not available" in message:
                raise BrfUnavailable(message)
            raise RuntimeError(f"glaswave {command} {label} failed ({result.returncode}): "
                               f"{message}")
        log(f"{command} {label}: {time.monotonic() - start:.1f} s")
        return out

    def run(self, config, sets, size, label):
        """The scene's shots (xarray Dataset of shots.nc)."""
        stem = self._prepare("run", self.resolve(config, sets, size))
        out = self._glaswave("run", stem, label, "shots.nc")
        return xr.load_dataset(os.path.join(out, "shots.nc"))

    def brf(self, config, sets, size, brf_settings, label):
        """The scene's brf output folder (brf.json, scene.tif)."""
        document = self.resolve(config, sets, {})
        settings = dict(brf_settings)
        if "photons" in size:
            settings["photons"] = size["photons"]
        document["brf"] = settings
        stem = self._prepare("brf", document)
        return self._glaswave("brf", stem, label, "brf.json")


# ---------------------------------------------------------------------------------------------
# What a run gives: per-band means and per-shot values.


def good_shots(ds, band):
    one = ds.sel(band=band)
    keep = (one.quality_flag == 1) & np.isfinite(one.energy_cr) & np.isfinite(one.energy_gr)
    return one.where(keep, drop=True)


def band_names(ds):
    return [str(b) for b in ds.band_name.values]


def band_value(ds, name):
    """The band coordinate's value of band `name` (glaswave's band coordinate is nm)."""
    return ds.band.values[band_names(ds).index(name)]


def returns(ds, band_name):
    """Mean TR, CR, GR over the good shots (as `glaswave sweep`), by position and by truth."""
    d = good_shots(ds, band_value(ds, band_name))
    return {
        "tr": float(d.energy_tr.mean()), "cr": float(d.energy_cr.mean()),
        "gr": float(d.energy_gr.mean()),
        "cr_truth": float(d.rx_energy_canopy.mean()), "gr_truth": float(d.rx_energy_ground.mean()),
        "tr_truth": float(d.rx_energy.mean()),
    }


def resolved_config(ds):
    return json.loads(ds.attrs["config"])


def fov_fraction(ds):
    """Part of a nadir Gaussian beam inside the detector's field of view (PHYSICS.md 1)."""
    sensor = resolved_config(ds)["sensor"]
    ifov, sigma = sensor["ifov_rad"], sensor["divergence_sigma_rad"]
    return 1.0 - math.exp(-ifov * ifov / (8.0 * sigma * sigma))


def pct(value, base):
    return 100.0 * (value / base - 1.0)


# ---------------------------------------------------------------------------------------------
# Table 3


def read_seed_table(path):
    rows = {}
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    for row in csv.DictReader(lines):
        rows[(row["parameter"], row["value"])] = row
    return rows


def table3_scenes(study):
    scenes = [("base", {})]
    for row in study["rows"]:
        scenes.append((f"{row['parameter']}={row['value']}", row["set"]))
    return scenes


def study_table3(runner, size, out):
    study = load_study("table3")
    band = study["band"]
    seed = read_seed_table(os.path.join(HERE, study["seed_table"]))
    base = returns(runner.run(study["config"], {}, size, "base"), band)
    header = ["parameter", "value", "tr_pct", "cr_pct", "gr_pct", "seed_tr_pct", "seed_cr_pct",
              "seed_gr_pct", "cr_truth_pct", "gr_truth_pct", "canopy_share", "note"]
    rows = []

    def row_of(parameter, value, sets, note, base_sets=None):
        # An explaining row may have a base of its own: its sets are then applied over it.
        reference = base
        if base_sets:
            reference = returns(runner.run(study["config"], base_sets, size, "base of " + value),
                                band)
            sets = {**base_sets, **sets}
        r = returns(runner.run(study["config"], sets, size, f"{parameter}={value}"), band)
        s = seed.get((parameter, value), {})
        seed_values = [float(s[k]) if s.get(k) else float("nan")
                       for k in ("tr_pct", "cr_pct", "gr_pct")]
        return [parameter, value, pct(r["tr"], reference["tr"]), pct(r["cr"], reference["cr"]),
                pct(r["gr"], reference["gr"])] + seed_values + [
                    pct(r["cr_truth"], reference["cr_truth"]),
                    pct(r["gr_truth"], reference["gr_truth"]), r["cr"] / r["tr"], note]

    for row in study["rows"]:
        rows.append(row_of(row["parameter"], row["value"], row["set"], "seed's row"))
    explained = [row_of(e["parameter"], e["value"], e["set"], e["note"], e.get("base"))
                 for e in study.get("explain", [])]
    write_csv(os.path.join(out, "table3.csv"), header, rows + explained)
    share = base["cr"] / base["tr"]
    write_atomic(os.path.join(out, "table3.md"),
                 table3_markdown(rows, explained, share, size, band))
    return rows


def table3_markdown(rows, explained, canopy_share, size, band):
    def cell(v):
        return "" if not math.isfinite(v) else (f"{v:+.1f}" if abs(v) >= 0.05 else "0")

    lines = [
        f"Table 3 at {band} nm: % change of the mean return over {size['shots']} footprints "
        f"({size['rays_per_shot']} rays each) from the base case (Tables 1-2), partitioned by "
        "position in the waveform; the seed's numbers beside. Base case: canopy return "
        f"{100 * canopy_share:.1f} % of the total (the seed's rows imply 67.7 %: see "
        "docs/guide/studies.md).",
        "",
        "| parameter | value | TR | CR | GR | seed TR | seed CR | seed GR |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(f"| {r[0]} | {r[1]} | " + " | ".join(cell(v) for v in r[2:8]) + " |")
    if explained:
        lines += ["", "Other readings of the rows that differ (see docs/guide/studies.md):", "",
                  "| parameter | value | TR | CR | GR | what |", "|---|---|---:|---:|---:|---|"]
        for r in explained:
            lines.append(f"| {r[0]} | {r[1]} | " + " | ".join(cell(v) for v in r[2:5]) +
                         f" | {r[11]} |")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# Figs. 2-3: BRF against the waveform's reflectance


def study_brf_validation(runner, size, out):
    study = load_study("brf_validation")
    scenes = table3_scenes(load_study(study["scenes"].removesuffix(".json")))
    scenes += [(s["name"], s["set"]) for s in study.get("extra_scenes", [])]
    rows = []
    for name, sets in scenes:
        ds = runner.run(study["config"], sets, size, name)
        brf_dir = runner.brf(study["config"], sets, size, study["brf"], name)
        with open(os.path.join(brf_dir, "brf.json")) as f:
            brf = {b["name"]: b for b in json.load(f)["bands"]}
        f_fov = fov_fraction(ds)
        for band in band_names(ds):
            d = good_shots(ds, band_value(ds, band))
            rho = d.reflectance.values / f_fov
            view = brf[band]["views"][0]
            rows.append([name, band, float(view["brf"]), float(view["brf_stderr"]),
                         float(np.mean(rho)), float(np.std(rho, ddof=1))])
    header = ["scene", "band", "brf", "brf_stderr", "waveform_reflectance",
              "waveform_reflectance_sd"]
    write_csv(os.path.join(out, "brf_validation.csv"), header, rows)
    summary = {}
    for band in sorted({r[1] for r in rows}):
        mine = [r for r in rows if r[1] == band]
        summary[band] = plot_brf_validation(mine, band, os.path.join(
            out, f"brf_validation_{band}.png"))
    return summary


def plot_brf_validation(rows, band, path):
    brf = np.array([r[2] for r in rows])
    brf_err = np.array([r[3] for r in rows])
    rho = np.array([r[4] for r in rows])
    rho_sd = np.array([r[5] for r in rows])
    bias = float(np.mean(rho - brf))
    relative = 100.0 * bias / float(np.mean(brf))
    figure, ax = plt.subplots(figsize=(5.2, 5.0))
    ax.errorbar(brf, rho, xerr=brf_err, yerr=rho_sd, fmt="o", ms=4, capsize=2, color="C0",
                ecolor="0.6", label="scenes (bars: footprint-scale sd)")
    low = 0.9 * min(brf.min(), rho.min())
    high = 1.1 * max(brf.max(), rho.max())
    ax.plot([low, high], [low, high], "k--", lw=1, label="1:1")
    ax.set_xlim(low, high)
    ax.set_ylim(low, high)
    ax.set_xlabel("BRF, glaswave brf (retro direction, nadir)")
    ax.set_ylabel("reflectance of the integrated waveform (eq. 1)")
    ax.set_title(f"{band} nm, {len(rows)} scenes\nmean difference {bias:+.4f} "
                 f"({relative:+.1f} % of the mean BRF)", fontsize=9)
    ax.legend(fontsize=8, loc="upper left")
    figure.tight_layout()
    save_figure(figure, path)
    return {"bias": bias, "relative_pct": relative}


# ---------------------------------------------------------------------------------------------
# Figs. 4-5: waveforms against PAI and slope


def mean_waveform_by_height(ds, band, heights_m):
    """Mean received power over the good shots on a grid of heights above the footprint."""
    d = good_shots(ds, band_value(ds, band))
    bins = d.rx_waveform.shape[-1]
    total = np.zeros_like(heights_m)
    for i in range(d.sizes["shot"]):
        h = np.linspace(float(d.elev_bin0[i]), float(d.elev_lastbin[i]), bins) - float(d.elev[i])
        total += np.interp(heights_m, h[::-1], d.rx_waveform.values[i][::-1], left=0, right=0)
    return total / max(d.sizes["shot"], 1)


def study_pai_waveforms(runner, size, out):
    study = load_study("pai_waveforms")
    heights = np.arange(-10.0, 50.0, 0.15)
    curves = []
    for pai in study["pai"]:
        sets = {} if pai == 3 else {"canopy.pai": pai}
        name = "base" if pai == 3 else f"PAI={pai}"
        ds = runner.run(study["config"], sets, size, name)
        for band in band_names(ds):
            curves.append((pai, band, mean_waveform_by_height(ds, band, heights)))
    bands = sorted({c[1] for c in curves}, key=float)
    figure, axes = plt.subplots(1, len(bands), figsize=(4.2 * len(bands), 5.0), sharey=True)
    axes = np.atleast_1d(axes)
    rows = []
    for ax, band in zip(axes, bands):
        for pai, b, power in curves:
            if b != band:
                continue
            ax.plot(power * 1e9, heights, label=f"PAI {pai:g}")
            rows += [[pai, band, float(h), float(p)] for h, p in zip(heights, power)]
        ax.set_xlabel("mean received power (nW)")
        ax.set_title(f"{band} nm")
    axes[0].set_ylabel("height above the ground (m)")
    axes[0].legend(fontsize=8)
    figure.suptitle(f"Waveform against PAI (mean of {size['shots']} footprints)", fontsize=10)
    figure.tight_layout()
    save_figure(figure, os.path.join(out, "pai_waveforms.png"))
    write_csv(os.path.join(out, "pai_waveforms.csv"), ["pai", "band", "height_m", "power_W"],
              rows)


def rms_width_ns(time_ns, power):
    total = power.sum()
    if not total > 0:
        return float("nan")
    mean = (time_ns * power).sum() / total
    return float(math.sqrt(max(((time_ns - mean) ** 2 * power).sum() / total, 0.0)))


def ground_gaussian_sigma_ns(d):
    """Mean over the shots of the width of the Gaussian the products call the ground (the one
    centred on ground_elev_est)."""
    sigmas = []
    for i in range(d.sizes["shot"]):
        centres = d.gauss_center_m.values[i]
        if not np.isfinite(d.ground_elev_est.values[i]) or not np.isfinite(centres).any():
            continue
        k = int(np.nanargmin(np.abs(centres - d.ground_elev_est.values[i])))
        sigmas.append(float(d.gauss_sigma_ns.values[i][k]))
    return float(np.mean(sigmas)) if sigmas else float("nan")


def study_slope(runner, size, out):
    study = load_study("slope")
    rows, curves = [], []
    for slope in study["slopes_deg"]:
        sets = dict(study.get("set", {}))
        sets["terrain.plane.slope_deg"] = slope
        ds = runner.run(study["config"], sets, size, f"slope={slope}")
        t = ds.bin_time_ns.values
        for band in band_names(ds):
            d = good_shots(ds, band_value(ds, band))
            ground = [rms_width_ns(t, w) for w in d.rx_waveform_ground.values]
            total = [rms_width_ns(t, w) for w in d.rx_waveform.values]
            rows.append([slope, band, float(np.nanmean(ground)), float(np.nanmean(total)),
                         ground_gaussian_sigma_ns(d)])
            curves.append((slope, band, t, d.rx_waveform.values.mean(axis=0)))
    write_csv(os.path.join(out, "slope.csv"),
              ["slope_deg", "band", "rms_width_ns", "rms_width_total_ns",
               "ground_gauss_sigma_ns"], rows)
    bands = sorted({c[1] for c in curves}, key=float)
    figure, axes = plt.subplots(1, len(bands), figsize=(4.6 * len(bands), 4.6), sharey=True)
    axes = np.atleast_1d(axes)
    wave_rows = []
    for ax, band in zip(axes, bands):
        for slope, b, t, power in curves:
            if b != band:
                continue
            width = next(r[2] for r in rows if r[0] == slope and r[1] == band)
            # Two-way time to height above the footprint centre.
            height_m = -t * 1e-9 * SPEED_OF_LIGHT_M_S / 2.0
            ax.plot(power * 1e9, height_m, label=f"{slope:g}°: ground RMS {width:.1f} ns")
            wave_rows += [[slope, band, float(x), float(p)] for x, p in zip(t, power)]
        ax.set_ylim(-60, 60)
        ax.set_xlabel("mean received power (nW)")
        ax.set_title(f"{band} nm")
        ax.legend(fontsize=7)
    axes[0].set_ylabel("height above the footprint centre (m)")
    figure.suptitle(f"Waveform against slope (mean of {size['shots']} footprints)", fontsize=10)
    figure.tight_layout()
    save_figure(figure, os.path.join(out, "slope_waveforms.png"))
    write_csv(os.path.join(out, "slope_waveforms.csv"), ["slope_deg", "band", "time_ns",
                                                         "power_W"], wave_rows)
    return rows


# ---------------------------------------------------------------------------------------------
# Fig. 6: WI against VPAI


def leaf_inclination_density(lad, t):
    """de Wit's distributions and Campbell's ellipsoidal, g(t) over leaf inclination t."""
    c2, c4 = np.cos(2 * t), np.cos(4 * t)
    named = {"spherical": np.sin(t), "planophile": 2 / np.pi * (1 + c2),
             "erectophile": 2 / np.pi * (1 - c2), "plagiophile": 2 / np.pi * (1 - c4),
             "extremophile": 2 / np.pi * (1 + c4), "uniform": np.full_like(t, 2 / np.pi)}
    if isinstance(lad, dict):
        chi = -3.0 + (math.radians(lad["ellipsoidal_mean_deg"]) / 9.65) ** -0.6061
        return chi ** 3 * np.sin(t) / (np.cos(t) ** 2 + chi ** 2 * np.sin(t) ** 2) ** 2
    return named[lad]


def g_nadir(lad):
    """G(0): the plant area seen from straight above per unit plant area, the mean |cos| of
    the leaf normals' inclination (leaves and bark share the LAD)."""
    t = (np.arange(20000) + 0.5) * (np.pi / 2) / 20000
    g = leaf_inclination_density(lad, t)
    return float((g * np.cos(t)).sum() / g.sum())


def study_wi_vpai(runner, size, out, quick):
    study = load_study("wi_vpai")
    band = study["band"]
    pais = study["quick_pai"] if quick else study["pai"]
    points = []
    for perturbation in study["perturbations"]:
        for pai in pais:
            sets = dict(perturbation["set"])
            if pai != 3:
                sets["canopy.pai"] = pai
            label = perturbation["name"] + ("" if pai == 3 else f",PAI={pai}")
            if perturbation["name"] == "base":
                label = "base" if pai == 3 else f"PAI={pai}"
            ds = runner.run(study["config"], sets, size, label)
            g0 = g_nadir(resolved_config(ds)["canopy"]["lad"])
            d = good_shots(ds, band_value(ds, band))
            for vpai_shot, wi in zip(g0 * d.pai_true.values, d.waveform_index.values):
                if math.isfinite(wi):
                    points.append((perturbation["name"], pai, float(vpai_shot), float(wi)))
    write_csv(os.path.join(out, "wi_vpai.csv"), ["vpai", "wi", "scene", "pai"],
              [[p[2], p[3], p[0], p[1]] for p in points])
    return plot_wi_vpai(points, band, os.path.join(out, "wi_vpai.png"))


def r_squared(x, y, slope, intercept):
    residual = y - (slope * x + intercept)
    return float(1.0 - (residual ** 2).sum() / ((y - y.mean()) ** 2).sum())


def plot_wi_vpai(points, band, path):
    """WI against ln VPAI by least squares: the index saturates as the crowns close (GR falls
    as exp(-k VPAI) and WI tends to 1), so the fit is on the logarithm; the straight-line R²
    is given beside it."""
    x = np.array([p[2] for p in points])
    y = np.array([p[3] for p in points])
    slope, intercept = np.polyfit(np.log(x), y, 1)
    r2 = r_squared(np.log(x), y, slope, intercept)
    r2_linear = r_squared(x, y, *np.polyfit(x, y, 1))
    figure, ax = plt.subplots(figsize=(6.0, 4.8))
    names = list(dict.fromkeys(p[0] for p in points))
    for k, name in enumerate(names):
        sel = [i for i, p in enumerate(points) if p[0] == name]
        ax.plot(x[sel], y[sel], "o", ms=3, alpha=0.7, color=f"C{k % 10}", label=name)
    grid = np.linspace(x.min(), x.max(), 100)
    ax.plot(grid, slope * np.log(grid) + intercept, "k-", lw=1.2)
    ax.text(0.03, 0.95, f"WI = {slope:.3f} ln(VPAI) {intercept:+.3f}\nR² = {r2:.3f} "
            f"({len(points)} footprints)\nstraight line: R² = {r2_linear:.3f}",
            transform=ax.transAxes, va="top", fontsize=9, bbox={"fc": "white", "ec": "0.7"})
    ax.set_xlabel("VPAI = G(0) × footprint PAI (m²/m²)")
    ax.set_ylabel(f"waveform index (CR − GR)/(CR + GR), {band} nm")
    ax.legend(fontsize=7, loc="lower right", ncol=2)
    figure.tight_layout()
    save_figure(figure, path)
    return {"fit": "wi = slope * ln(vpai) + intercept", "slope": float(slope),
            "intercept": float(intercept), "r2": r2, "r2_linear": r2_linear, "n": len(points)}


# ---------------------------------------------------------------------------------------------
# Fig. 1


def study_scene(runner, size, out):
    from osgeo import gdal  # Debian's python3-gdal; only this study needs it

    gdal.UseExceptions()
    study = load_study("scene")
    brf_dir = runner.brf(study["config"], {}, size, study["brf"], "scene")
    raster = gdal.Open(os.path.join(brf_dir, "scene.tif"))
    count = raster.RasterCount
    figure, axes = plt.subplots(1, count, figsize=(4.6 * count, 4.6))
    axes = np.atleast_1d(axes)
    x0, dx, _, y0, _, dy = raster.GetGeoTransform()
    extent = [0, raster.RasterXSize * abs(dx), 0, raster.RasterYSize * abs(dy)]
    for k, ax in enumerate(axes):
        band = raster.GetRasterBand(k + 1)
        image = band.ReadAsArray().astype(float)
        nodata = band.GetNoDataValue()
        if nodata is not None:
            image[image == nodata] = np.nan
        shown = ax.imshow(image, cmap="gray", extent=extent,
                          vmin=0, vmax=np.nanpercentile(image, 99.5))
        ax.set_title(band.GetDescription() or f"band {k + 1}", fontsize=9)
        ax.set_xlabel("m")
        figure.colorbar(shown, ax=ax, shrink=0.8, label="reflectance")
    sun = study["brf"]
    figure.suptitle(f"The base scene under the sun (zenith {sun['sun_zenith_deg']:g}°, "
                    f"azimuth {sun['sun_azimuth_deg']:g}°), seen from above", fontsize=10)
    figure.tight_layout()
    save_figure(figure, os.path.join(out, "scene.png"))


# ---------------------------------------------------------------------------------------------


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--glaswave", required=True, help="the glaswave binary")
    parser.add_argument("--quick", action="store_true", help="small runs, for a check")
    parser.add_argument("--out", default="out/studies")
    parser.add_argument("--threads", type=int, default=0)
    args = parser.parse_args()
    mode = "quick" if args.quick else "full"
    os.makedirs(args.out, exist_ok=True)
    runner = Runner(args.glaswave, args.out, args.threads)
    start = time.monotonic()
    skipped = []

    rows = study_table3(runner, load_study("table3")[mode], args.out)
    summary = {"table3_rows": len(rows)}
    summary["slope"] = study_slope(runner, load_study("slope")[mode], args.out)
    study_pai_waveforms(runner, load_study("pai_waveforms")[mode], args.out)
    summary["wi_vpai"] = study_wi_vpai(runner, load_study("wi_vpai")[mode], args.out, args.quick)
    for name, study in (("brf_validation", study_brf_validation), ("scene", study_scene)):
        try:
            summary[name] = study(runner, load_study(name)[mode], args.out)
        except BrfUnavailable as e:
            log(f"skipped {name}: glaswave brf refused ({e})")
            skipped.append(name)
    write_atomic(os.path.join(args.out, "skipped.txt"),
                 "".join(f"{name}: glaswave brf is not available in this build\n"
                         for name in skipped))
    if not skipped:
        os.remove(os.path.join(args.out, "skipped.txt"))
    write_atomic(os.path.join(args.out, "summary.json"), json.dumps(summary, indent=1) + "\n")
    log(f"{mode}: {runner.count} glaswave runs in {time.monotonic() - start:.0f} s; "
        f"products in {args.out}")
    for path in sorted(os.listdir(args.out)):
        if os.path.isfile(os.path.join(args.out, path)):
            print(os.path.join(args.out, path))


if __name__ == "__main__":
    main()
