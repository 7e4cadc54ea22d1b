#!/usr/bin/python3
"""How wrong is each retrieval method? `glaswave retrieve` on held-out forests (issue 37, item 5).

Usage: retrieval.py --glaswave BINARY [--quick | --size full|reduced|quick] [--out DIR]
                    [--threads N] [--sensors gedi,glas,icesat2]

For GEDI, GLAS and ICESat-2 in turn: a forward table of crowned forests (`glaswave table`, ellipsoid crowns
over the ranges in TABLE_VARY, slopes 0-30 deg), then stands the table did not see (their own
seeds and elevations, crown bases and tops off the table's three, radii and PAI partly beyond its
ranges, a fifth of them conical crowns, slopes to 30 deg in any aspect), each simulated as a pass
with the detector on (`glaswave run`) and retrieved by every method (`glaswave retrieve
--methods gedi_l2a,gedi_l2b,wi,rt`; ICESat-2's ATL03 and ATL08 by atl08, photon_ratio and rt on
the photons, one ATL08 segment a record). For every sensor, method and variable (canopy height,
cover, PAI, ground elevation, rhov/rhog) against the products' truth: bias, RMSE and, for rt's
posterior, the share of shots whose 5-95 % interval holds the truth, overall and by slope and
crown class. Writes DIR/retrieval_metrics.csv and .md, retrieval_shots.csv (every shot),
retrieval_scatter.png (estimate against truth), retrieval_slope.png (error against slope),
summary.json. Runs are cached under DIR/runs/ by a hash of their configuration, as the seed's
studies are.
"""
import argparse
import csv
import hashlib
import json
import math
import os
import resource
import shutil
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import netCDF4  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from studies import apply_set, format_value, save_figure, write_atomic  # noqa: E402

RETRIEVE_METHODS = ["gedi_l2a", "gedi_l2b", "wi", "rt"]
# ICESat-2's: ATL08's own, the photon ratio, and rt on ATL03's photons.
SEGMENT_METHODS = ["atl08", "photon_ratio", "rt"]
# gedi_l2a_a1: L2A's default group alone (retrieval.nc's canopy_height_gedi_l2a_a1 and
# ground_elevation_gedi_l2a_a1), beside the selected group's gedi_l2a.
METHODS = ["gedi_l2a", "gedi_l2a_a1", "gedi_l2b", "wi", "atl08", "photon_ratio", "rt"]
# pgap: the vertical gap probability over the footprint, the part of the beam that reaches the
# ground between and through the crowns; GEDI L2B's cover is one less it (its Pgap), where
# `cover` is the crowns' cover.
VARIABLES = ["canopy_height", "cover", "pai", "ground_elevation", "rhov_rhog", "pgap"]
UNITS = {"canopy_height": "m", "cover": "", "pai": "", "ground_elevation": "m", "rhov_rhog": "",
         "pgap": ""}
COLOURS = {"gedi_l2a": "tab:orange", "gedi_l2a_a1": "tab:purple", "gedi_l2b": "tab:blue",
           "wi": "tab:green", "atl08": "tab:cyan", "photon_ratio": "tab:olive", "rt": "tab:red"}
SLOPE_CLASSES_DEG = [(0.0, 10.0), (10.0, 20.0), (20.0, 30.0)]

# The table's forests: every range a Halton coordinate, covering the held-out stands' own ranges
# (PAI 0.3-6, radii 1.5-7 m: a posterior is a weighted mean of entries, so it cannot reach a
# truth beyond them); the crown base one of ten layers 2.5 m deep, 1.4 m apart, from 2-4.5 m to
# 14.6-17.1 m (so canopy tops from 6 to 33 m), and both crown shapes the stands have. Ten
# overlapping layers in place of four that tiled 2-18 m (as deep as 5.5 m) bring the table's
# forests nearer the stands', whose bases lie 0.5-4 m apart: on the reduced study's 1000 GEDI
# shots rt's canopy height RMSE fell from 3.10 to 2.84 m, Pgap's from 0.107 to 0.099, the
# ground's from 2.27 to 2.16 m, cover and PAI by 1.5 %, with the same 1500 entries.
TABLE_LAYERS_M = [(2.0 + 1.4 * k, 4.5 + 1.4 * k) for k in range(10)]
TABLE_VARY = {
    "canopy.pai": [0.3, 6.0],
    "canopy.cover": [0.15, 0.95],
    "canopy.crown_radius_m": [1.5, 7.0],
    "canopy.crown_half_height_m": [2.0, 8.0],
    "terrain.plane.slope_deg": [0.0, 30.0],
}
TABLE_VALUES = {"canopy.crown_base_m": ["[%.1f, %.1f]" % layer for layer in TABLE_LAYERS_M],
                "canopy.crown_shape": ["ellipsoid", "cone"]}

# The detector of the held-out shots: a background and Gaussian noise of about 1 % of these
# forests' peaks (4e-8 to 1e-7 W for GEDI, 1e-7 to 3e-7 W for GLAS at 1000 rays; a real GEDI
# shot's noise_stddev_corrected is 1-3 % of a dense forest's peak). It also keeps L2A's lowest
# threshold (a5's 2 sigma) above one Monte Carlo ray, about 0.25 % of the peak at 1000 rays.
SENSORS = {
    "gedi": {
        "sensor": {"preset": "gedi"},
        "detector": {"enabled": True, "background_W": 5.0e-10, "noise_rms_W": 5.0e-10},
        "spacing_m": 60.0,
    },
    "glas": {
        # One band (1064 nm, GLAS's waveform channel), so that every method reads the same one.
        "sensor": {"preset": "glas", "bands": [
            {"name": "1064", "wavelength_nm": 1064, "pulse_energy_mJ": 72,
             "atmos_transmission_roundtrip": 0.9}]},
        "detector": {"enabled": True, "background_W": 2.0e-9, "noise_rms_W": 2.0e-9},
        "spacing_m": 172.0,
    },
    # ATLAS's photons (its strong beam gt2l, the sun's background at 09:00 local time on the
    # equinox: the sun 45 deg up), in ATL08's 100 m segments; the table holds the same sensor's
    # expected waveforms (a waveform receiver), which rt turns into expected photons.
    "icesat2": {
        "sensor": {"preset": "atlas"},
        "table_sensor": {"preset": "atlas", "receiver": "waveform"},
        "spacing_m": 0.7,
        "start_time": "2019-03-20T09:00:00Z",
    },
}
ALTITUDE_M = {"gedi": 420000.0, "glas": 600000.0, "icesat2": 496000.0}

SIZES = {
    # The table's cost is mostly each entry's scene (its crowns), not its rays.
    # ICESat-2: the GEDI stands, 428 ATLAS shots each (three ATL08 segments of 100 m).
    "full": {"table_entries": {"gedi": 1500, "glas": 1000, "icesat2": 1500}, "table_rays": 1000,
             "stands": {"gedi": 40, "glas": 30, "icesat2": 40},
             "shots": {"gedi": 50, "glas": 30, "icesat2": 428}, "rays": 1000},
    # GEDI alone: the full study's table and stands (the same seeds, so the same forests), half
    # the shots each; about 2-3 minutes of CPU, for comparing a change before and after.
    "reduced": {"table_entries": {"gedi": 1500, "glas": 1000, "icesat2": 1500},
                "table_rays": 1000, "stands": {"gedi": 40, "glas": 0, "icesat2": 0},
                "shots": {"gedi": 25, "glas": 30, "icesat2": 428}, "rays": 1000},
    "quick": {"table_entries": {"gedi": 96, "glas": 64, "icesat2": 64}, "table_rays": 1000,
              "stands": {"gedi": 3, "glas": 2, "icesat2": 2},
              "shots": {"gedi": 8, "glas": 6, "icesat2": 286}, "rays": 1000},
}


def log(message):
    print("retrieval: " + message, file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------------------
# The study's arithmetic (tests/studies/test_retrieval_study.py checks it by hand).


def finite_pairs(estimate, truth):
    """The shots where both the estimate and the truth are finite."""
    estimate, truth = np.asarray(estimate, float), np.asarray(truth, float)
    keep = np.isfinite(estimate) & np.isfinite(truth)
    return estimate[keep], truth[keep]


def bias(estimate, truth):
    """Mean of estimate - truth over the shots where both are finite (NaN when none)."""
    e, t = finite_pairs(estimate, truth)
    return float(np.mean(e - t)) if e.size else math.nan


def rmse(estimate, truth):
    """Root mean square of estimate - truth over the shots where both are finite."""
    e, t = finite_pairs(estimate, truth)
    return float(np.sqrt(np.mean((e - t) ** 2))) if e.size else math.nan


def coverage(low, high, truth):
    """Share of shots whose interval [low, high] holds the truth (NaN bounds: not counted)."""
    low, high, truth = (np.asarray(x, float) for x in (low, high, truth))
    keep = np.isfinite(low) & np.isfinite(high) & np.isfinite(truth)
    if not keep.any():
        return math.nan
    return float(np.mean((low[keep] <= truth[keep]) & (truth[keep] <= high[keep])))


def metrics(shots, method, variable, mask=None):
    """n, bias, RMSE and (rt only) 90 % coverage of one method's variable over the shots."""
    estimate = shots.get(f"{variable}_{method}")
    truth = shots.get(f"{variable}_true")
    if estimate is None or truth is None:
        return None
    if mask is not None:
        estimate, truth = estimate[mask], truth[mask]
    e, _ = finite_pairs(estimate, truth)
    if e.size == 0:
        return None
    row = {"n": int(e.size), "bias": bias(estimate, truth), "rmse": rmse(estimate, truth),
           "coverage90": math.nan}
    if method == "rt":
        low, high = shots[f"{variable}_rt_p05"], shots[f"{variable}_rt_p95"]
        if mask is not None:
            low, high = low[mask], high[mask]
        row["coverage90"] = coverage(low, high, truth)
    return row


# ---------------------------------------------------------------------------------------------
# The forests: the table's and the held-out stands.


def table_document(sensor, size):
    spec = SENSORS[sensor]
    document = {
        "seed": 37,
        "sensor": spec.get("table_sensor", spec["sensor"]),
        "simulation": {"rays_per_shot": size["table_rays"]},
        "terrain": {"plane": {"origin_lat_deg": 0.0, "origin_lon_deg": 0.0, "elevation_m": 0.0},
                    "soil_reflectance": 0.3},
        "canopy": {"crown_shape": "ellipsoid", "crown_base_m": [6.0, 10.0],
                   "crown_half_height_m": 5.0, "crown_radius_m": 4.0, "pai": 2.0, "cover": 0.5},
        # The entry's shots on one footprint, other rays: its waveform is that footprint's and
        # its truth the same footprint's, as a measured shot's is (two footprints 222 m apart
        # gave a mean of two forests' waveforms and truths, which no shot sees).
        "track": {"type": "points", "altitude_m": ALTITUDE_M[sensor],
                  "points": [{"lat_deg": 0.0, "lon_deg": 0.0},
                             {"lat_deg": 0.0, "lon_deg": 0.0}]},
        "output": {"footprints": False},
        "table": {"vary": TABLE_VARY, "values": TABLE_VALUES,
                  "entries": size["table_entries"][sensor]},
    }
    if sensor == "icesat2":
        # An ATL08 segment sums the photons of 143 footprints over 100 m of one forest: its
        # entry is the mean of 16 footprints along 100 m (each on its own ground, its truths
        # their means), where a waveform's is one footprint's.
        document["track"] = {"type": "pass", "start_lat_deg": 0.0, "start_lon_deg": 0.0,
                             "heading_deg": 0.0, "shots": 16, "spacing_m": 6.25,
                             "altitude_m": ALTITUDE_M[sensor]}
        document["table"]["shots_per_entry"] = 16
    return document


def held_out_stands(sensor, count):
    """The stands the table did not see, drawn from their own generator: seeds from 1000,
    crown bases anywhere in 2-16 m (the table's are three fixed layers), radii 1.5-7 m and PAI
    0.3-6 (beyond the table's 2-6 m and 0.3-5 in part), a fifth conical (the table's are
    ellipsoids), slope 0-30 deg in any aspect, the ground 0-800 m up."""
    rng = np.random.default_rng(20260 + (1 if sensor == "glas" else 0))  # ICESat-2: GEDI's
    stands = []
    for i in range(count):
        base_low = float(rng.uniform(2.0, 14.0))
        stands.append({
            "seed": 1000 + i,
            "canopy.pai": round(float(rng.uniform(0.3, 6.0)), 3),
            "canopy.cover": round(float(rng.uniform(0.15, 0.95)), 3),
            "canopy.crown_radius_m": round(float(rng.uniform(1.5, 7.0)), 2),
            "canopy.crown_half_height_m": round(float(rng.uniform(2.0, 8.0)), 2),
            "canopy.crown_base_m": [round(base_low, 2),
                                    round(base_low + float(rng.uniform(0.5, 4.0)), 2)],
            "canopy.crown_shape": "cone" if rng.uniform() < 0.2 else "ellipsoid",
            "terrain.plane.slope_deg": round(float(rng.uniform(0.0, 30.0)), 2),
            "terrain.plane.aspect_deg": round(float(rng.uniform(0.0, 360.0)), 1),
            "terrain.plane.elevation_m": round(float(rng.uniform(0.0, 800.0)), 1),
        })
    return stands


def stand_document(sensor, stand, size):
    spec = SENSORS[sensor]
    document = table_document(sensor, size)
    del document["table"]
    document["simulation"]["rays_per_shot"] = size["rays"]
    document["sensor"] = spec["sensor"]
    if "detector" in spec:
        document["detector"] = spec["detector"]
    document["track"] = {"type": "pass", "start_lat_deg": 0.0, "start_lon_deg": 0.0,
                         "heading_deg": 0.0, "shots": size["shots"][sensor],
                         "spacing_m": spec["spacing_m"],
                         "altitude_m": document["track"]["altitude_m"]}
    if "start_time" in spec:
        document["track"]["start_time"] = spec["start_time"]
    for key, value in stand.items():
        if key == "seed":
            document["seed"] = value
        else:
            apply_set(document, key, value)
    return document


# ---------------------------------------------------------------------------------------------
# glaswave, each run once under DIR/runs/.


class Runs:
    def __init__(self, glaswave, out_dir, threads):
        self.glaswave = glaswave
        self.dir = os.path.join(out_dir, "runs")
        self.threads = threads
        self.seconds = {"table": 0.0, "run": 0.0, "retrieve": 0.0}
        os.makedirs(self.dir, exist_ok=True)

    def _stem(self, command, document):
        text = json.dumps(document, sort_keys=True, indent=1)
        digest = hashlib.sha1((command + text).encode()).hexdigest()[:10]
        stem = os.path.join(self.dir, f"{command}-{digest}")
        if not os.path.exists(stem + ".json"):
            write_atomic(stem + ".json", text)
        return stem

    def _call(self, command, args, label):
        """glaswave's stdout; self.last_cpu_s the command's CPU seconds (user and system), a
        measure of speed that a busy machine does not stretch as it does the wall time."""
        start = time.monotonic()
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        result = subprocess.run([self.glaswave, command] + args + ["--quiet", "--threads",
                                                                    str(self.threads)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if result.returncode != 0:
            lines = result.stderr.strip().splitlines()
            raise RuntimeError(f"glaswave {command} {label} failed ({result.returncode}): "
                               f"{lines[-1] if lines else ''}")
        seconds = time.monotonic() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        self.last_cpu_s = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        self.seconds[command] += seconds
        log(f"{command} {label}: {seconds:.1f} s ({self.last_cpu_s:.1f} s of CPU)")
        return result.stdout

    def table(self, document, label):
        stem = self._stem("table", document)
        path = stem + ".nc"
        if not os.path.exists(path):
            partial = stem + ".part.nc"
            if os.path.exists(partial):
                os.remove(partial)
            self._call("table", [stem + ".json", "--out", partial], label)
            os.replace(partial, path)
        return path

    def run(self, document, label):
        stem = self._stem("run", document)
        out = stem + ".out"
        if not os.path.exists(os.path.join(out, "shots.nc")):
            shutil.rmtree(out, ignore_errors=True)
            self._call("run", [stem + ".json", "--out", out], label)
        return os.path.join(out, "shots.nc")

    def retrieve(self, shots_files, table_nc, label, methods=RETRIEVE_METHODS):
        """DIR/retrieval.nc of every input retrieved at once (the table's emulator and its
        tempering are made once a command), and the command's JSON summary with its whole wall
        time (command_wall_s) beside the methods' (wall_s)."""
        key = {"shots": [os.path.relpath(f, self.dir) for f in shots_files],
               "table": os.path.relpath(table_nc, self.dir), "methods": methods}
        stem = self._stem("retrieve", key)
        out = stem + ".out"
        if not os.path.exists(os.path.join(out, "retrieve.json")):
            shutil.rmtree(out, ignore_errors=True)
            start = time.monotonic()
            text = self._call("retrieve", shots_files + ["--table", table_nc, "--out", out,
                                                         "--methods", ",".join(methods),
                                                         "--json"], label)
            summary = json.loads(text.strip().splitlines()[-1])
            summary["command_wall_s"] = time.monotonic() - start
            summary["command_cpu_s"] = self.last_cpu_s
            write_atomic(os.path.join(out, "retrieve.json"), json.dumps(summary) + "\n")
        with open(os.path.join(out, "retrieve.json")) as f:
            return os.path.join(out, "retrieval.nc"), json.load(f)


# ---------------------------------------------------------------------------------------------
# Reading and summarising.


def read_retrieval(path, shots_files, stands, sensor):
    """Every shot of one sensor as a dict of arrays: each method's estimates, rt's bounds, the
    truth, and its stand's index, slope and crown shape (retrieval.nc holds the shots of
    shots_files in their order)."""
    columns = {}
    with netCDF4.Dataset(path) as nc:
        for name, variable in nc.variables.items():
            if variable.dimensions == ("shot",):
                columns[name] = np.ma.filled(variable[:].astype(float), np.nan)
    slope, stand_index, energy_ground, energy_canopy = [], [], [], []
    for i, shots_nc in enumerate(shots_files):
        with netCDF4.Dataset(shots_nc) as nc:
            slope.append(np.ma.filled(nc["slope_deg"][:].astype(float), np.nan))
            energy_ground.append(np.ma.filled(nc["rx_energy_ground"][:, 0].astype(float), np.nan))
            energy_canopy.append(np.ma.filled(nc["rx_energy_canopy"][:, 0].astype(float), np.nan))
        stand_index.append(np.full(slope[-1].size, i))
    columns["slope_deg"] = np.concatenate(slope)
    columns["energy_ground_J"] = np.concatenate(energy_ground)
    columns["energy_canopy_J"] = np.concatenate(energy_canopy)
    columns["stand"] = np.concatenate(stand_index)
    n = len(columns["shot_number"])
    if columns["slope_deg"].size != n:
        raise RuntimeError(f"{path}: {n} shots, its inputs {columns['slope_deg'].size}")
    columns["sensor"] = np.array([sensor] * n)
    columns["crown_shape"] = np.array([stands[i]["canopy.crown_shape"] for i in columns["stand"]])
    columns["in_table_ranges"] = np.array([in_table_ranges(stands[i]) for i in columns["stand"]])
    return columns


def read_segments(runs, table, stands, size):
    """ICESat-2: each stand's ATL03 and ATL08 retrieved (one pair a command: segment numbers
    are a granule's own), every ATL08 segment a record, with its stand's index, slope and crown
    shape; the summed speed of the commands."""
    parts, speed = [], {"shots": 0, "wall_s": 0.0, "command_wall_s": 0.0, "command_cpu_s": 0.0}
    for i, stand in enumerate(stands):
        shots_nc = runs.run(stand_document("icesat2", stand, size), f"icesat2 stand {i}")
        out = os.path.dirname(shots_nc)
        product, summary = runs.retrieve([os.path.join(out, "atl03.h5"),
                                          os.path.join(out, "atl08.h5")], table,
                                         f"icesat2 stand {i}", SEGMENT_METHODS)
        columns = {}
        with netCDF4.Dataset(product) as nc:
            for name, variable in nc.variables.items():
                if variable.dimensions == ("shot",):
                    columns[name] = np.ma.filled(variable[:].astype(float), np.nan)
        n = len(columns["shot_number"])
        columns["slope_deg"] = np.full(n, stand["terrain.plane.slope_deg"])
        columns["energy_ground_J"] = columns["energy_canopy_J"] = np.full(n, np.nan)
        columns["stand"] = np.full(n, i)
        parts.append(columns)
        for key in speed:
            speed[key] += summary.get(key, math.nan)
    shots = concatenate(parts)
    n = len(shots["shot_number"])
    shots["sensor"] = np.array(["icesat2"] * n)
    shots["crown_shape"] = np.array([stands[i]["canopy.crown_shape"] for i in shots["stand"]])
    shots["in_table_ranges"] = np.array([in_table_ranges(stands[i]) for i in shots["stand"]])
    speed["shots_per_s"] = speed["shots"] / speed["wall_s"] if speed["wall_s"] > 0 else math.nan
    return shots, speed


def in_table_ranges(stand):
    """Whether the stand's varied keys lie inside the table's ranges, its crowns are one of the
    table's shapes and its crown bases within the table's layers' span (its bases are never
    exactly one of the table's layers)."""
    if stand["canopy.crown_shape"] not in TABLE_VALUES.get("canopy.crown_shape", ["ellipsoid"]):
        return False
    layers = [json.loads(v) for v in TABLE_VALUES["canopy.crown_base_m"]]
    base = stand["canopy.crown_base_m"]
    if not min(a for a, _ in layers) <= base[0] <= base[1] <= max(b for _, b in layers):
        return False
    return all(low <= stand[key] <= high for key, (low, high) in TABLE_VARY.items())


def truth_in_table(shots, truth_ranges):
    """Whether each shot's true canopy height, cover and PAI lie within the ranges
    (variable: (low, high)) of the table's entries' truths."""
    inside = np.ones(len(shots["shot_number"]), bool)
    for variable, (low, high) in truth_ranges.items():
        truth = shots[f"{variable}_true"]
        inside &= (truth >= low) & (truth <= high)
    return inside


def table_truth_ranges(table_nc):
    """The table's entries' truths, (min, max) per variable."""
    names = {"canopy_height": "canopy_height_true", "cover": "cover_true", "pai": "pai_true"}
    with netCDF4.Dataset(table_nc) as nc:
        return {v: (float(np.nanmin(nc[n][:])), float(np.nanmax(nc[n][:])))
                for v, n in names.items()}


# ---------------------------------------------------------------------------------------------
# What a waveform can tell of PAI: its ground return against the noise.


def fit_ground_energy(pai, cover, energy_ground):
    """Fits the ground return of clumped crowns, Eg = Eg0 ((1 - C) + C exp(-k PAI / C)) (the
    gaps between crowns, and a crown's own gap at its plant area PAI / C), to the shots' true
    PAI, cover and ground energy: k on a grid of 0.001 over (0, 2], Eg0 by least squares at
    each k. Returns (Eg0, k, residual sd)."""
    pai, cover, eg = (np.asarray(x, float) for x in (pai, cover, energy_ground))
    keep = np.isfinite(pai) & np.isfinite(cover) & np.isfinite(eg) & (cover > 0.02)
    pai, cover, eg = pai[keep], cover[keep], eg[keep]
    best = (math.inf, math.nan, math.nan)
    for k in np.arange(0.001, 2.0005, 0.001):
        shape = (1.0 - cover) + cover * np.exp(-k * pai / cover)
        eg0 = float(np.dot(shape, eg) / np.dot(shape, shape))
        sse = float(np.sum((eg - eg0 * shape) ** 2))
        if sse < best[0]:
            best = (sse, eg0, float(k))
    sse, eg0, k = best
    return eg0, k, math.sqrt(sse / max(1, pai.size))


def saturation_pai(eg0, k, cover, noise_J, changes=1.0):
    """The PAI above which one unit of PAI changes the ground return by less than `changes`
    noise sds at this cover: |dEg/dPAI| = Eg0 k exp(-k PAI / C) = changes noise_J."""
    ratio = eg0 * k / (changes * noise_J)
    return cover / k * math.log(ratio) if ratio > 1.0 else 0.0


def saturation_rows(shots, sensor, bin_ns, pulse_sigma_ns, rays):
    """The fit and, per cover, the PAI where the ground return's change per unit PAI falls to
    one noise sd and where it falls to 1 / 0.6 sd (a posterior sd of 0.6 from the ground return
    alone): for the detector's noise summed over the ground return's bins (+-2 pulse sigma), and
    for a shot's Monte Carlo noise at `rays` rays (one ray's energy, the median shot's total over
    the rays, times the square root of the ground return's rays)."""
    eg0, k, residual = fit_ground_energy(shots["pai_true"], shots["cover_true"],
                                         shots["energy_ground_J"])
    bins = 4.0 * pulse_sigma_ns / bin_ns
    detector_J = SENSORS[sensor]["detector"]["noise_rms_W"] * bin_ns * 1e-9 * math.sqrt(bins)
    total = float(np.nanmedian(shots["energy_ground_J"] + shots["energy_canopy_J"]))
    rows = []
    for cover in (0.5, 0.7, 0.9):
        # The Monte Carlo sd at the saturating PAI itself: the ground's rays there, about
        # (1 - C) of the bare ground's (the crowns opaque).
        monte_carlo_J = math.sqrt(eg0 * (1.0 - cover) * total / rays)
        rows.append({"cover": cover,
                     "detector_1sd": saturation_pai(eg0, k, cover, detector_J),
                     "detector_rmse06": saturation_pai(eg0, k, cover, detector_J, 1.0 / 0.6),
                     "monte_carlo_1sd": saturation_pai(eg0, k, cover, monte_carlo_J),
                     "monte_carlo_rmse06": saturation_pai(eg0, k, cover, monte_carlo_J,
                                                          1.0 / 0.6)})
    return {"eg0_J": eg0, "k": k, "residual_J": residual, "detector_J": detector_J,
            "rays": rays, "rows": rows}


def markdown_saturation(saturation):
    lines = []
    for sensor, s in saturation.items():
        lines.append(f"{sensor.upper()}: Eg = Eg0 ((1 - C) + C exp(-k PAI / C)) fitted, Eg0 "
                     f"{s['eg0_J']:.3g} J, k {s['k']:.3f}, residual sd {s['residual_J']:.3g} J; "
                     f"noise of the ground energy: detector {s['detector_J']:.3g} J, Monte Carlo "
                     f"at {s['rays']} rays as below.\n")
        lines.append("| cover | PAI where dEg/dPAI = 1 detector sd | = 1/0.6 detector sd | "
                     "= 1 Monte Carlo sd | = 1/0.6 Monte Carlo sd |")
        lines.append("|---|---|---|---|---|")
        for r in s["rows"]:
            lines.append(f"| {r['cover']:.1f} | {r['detector_1sd']:.1f} | "
                         f"{r['detector_rmse06']:.1f} | {r['monte_carlo_1sd']:.1f} | "
                         f"{r['monte_carlo_rmse06']:.1f} |")
        lines.append("")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# What a waveform can tell at all: forests of the table whose waveforms a shot cannot tell apart.


def ray_amplitude(waveform, shot0, shots_per_entry):
    """One ray's amplitude a, from the scatter of each entry's first shot about its other shots'
    mean: a shot's Monte Carlo variance is a T (T the expected waveform), and S0 - S_rest has
    variance a T (1 + 1 / (K - 1)), pooled over every entry and bin."""
    w, s0 = np.asarray(waveform, float), np.asarray(shot0, float)
    k = float(shots_per_entry)
    rest = (k * w - s0) / (k - 1.0)
    return float(np.sum((s0 - rest) ** 2) / ((1.0 + 1.0 / (k - 1.0)) * np.sum(w)))


def alike_pairs(waveform, shot0, shots_per_entry, truths, fractions=(1.0, 0.5), quantile=0.9):
    """Pairs of the table's entries whose mean waveforms differ by no more than two shots of one
    forest do, and how far apart their truths lie.

    A shot's noise is its rays' (variance a T, `ray_amplitude`, floored at one ray). Two shots of
    one forest, an entry's first and the mean of its others, lie d_self = sum (S0 - S_rest)^2 /
    ((1 + 1 / (K - 1)) a max(T, a)) apart; two entries' means d = sum (W_i - W_j)^2 / (a (max(W_i,
    a) + max(W_j, a)) / K). Pairs with d at most `fraction` times d_self's `quantile` are as alike
    as two shots of one forest at 1 / fraction times the table's rays (a fixed difference's d
    grows with the rays; the means' own noise makes the rows past 1 undercount: at 4 times none
    are left). `truths`: name -> [entry] values. Returns rows of the threshold, the pairs and
    each truth's RMS difference over them: sqrt(2) times the sd of that truth among forests a
    shot cannot tell apart, which is the RMSE an inversion that knew the forests' waveforms
    exactly would still have."""
    w, s0 = np.asarray(waveform, float), np.asarray(shot0, float)
    k = float(shots_per_entry)
    a = ray_amplitude(w, s0, k)
    floor = np.maximum(w, a)
    rest = (k * w - s0) / (k - 1.0)
    d_self = np.sum((s0 - rest) ** 2 / ((1.0 + 1.0 / (k - 1.0)) * a * floor), axis=1)
    threshold = float(np.quantile(d_self, quantile))
    values = {name: np.asarray(v, float) for name, v in truths.items()}
    distance = np.full((len(w), len(w)), np.inf)
    for i in range(len(w)):
        distance[i, i + 1:] = np.sum((w[i] - w[i + 1:]) ** 2 / (a * (floor[i] + floor[i + 1:]) / k),
                                     axis=1)
    rows = []
    for fraction in fractions:
        first, second = np.nonzero(distance <= threshold * fraction)
        row = {"rays_factor": 1.0 / fraction, "threshold": threshold * fraction,
               "pairs": int(first.size), "entries": int(len(w))}
        for name, v in values.items():
            d = v[first] - v[second]
            d = d[np.isfinite(d)]
            row[name] = float(np.sqrt(np.mean(d ** 2))) if d.size else math.nan
        rows.append(row)
    return {"ray_amplitude_W": a, "self_median": float(np.median(d_self)), "rows": rows}


def table_alike_pairs(table_nc):
    """alike_pairs of a table's first band, for its truths (pgap NaN in a table without it) and
    its ground-return cover 1 - Eg/Eg0 (Eg0 fitted to the entries as fit_ground_energy does);
    None with one shot an entry."""
    with netCDF4.Dataset(table_nc) as nc:
        k = int(nc.getncattr("shots_per_entry"))
        if k < 2 or "waveform_shot0" not in nc.variables:
            return None
        w = np.asarray(nc["waveform"][:, 0, :], float)
        s0 = np.asarray(nc["waveform_shot0"][:, 0, :], float)
        pai, cover = np.asarray(nc["pai_true"][:], float), np.asarray(nc["cover_true"][:], float)
        height = np.asarray(nc["canopy_height_true"][:], float)
        eg = np.asarray(nc["energy_ground"][:, 0], float)
        pgap = (np.asarray(nc["pgap_true"][:], float) if "pgap_true" in nc.variables
                else np.full(len(pai), np.nan))
    eg0, _, _ = fit_ground_energy(pai, cover, eg)
    return alike_pairs(w, s0, k, {"cover": cover, "pai": pai, "canopy_height": height,
                                  "pgap": pgap, "ground_return_cover": 1.0 - eg / eg0})


def markdown_alike(alike):
    lines = ["Pairs of different entries whose mean waveforms differ by no more than two shots "
             "of one forest do (the 90th percentile of the entries' own two shots' distance), at "
             "the table's rays and as if shots had twice as many; each truth's RMS difference "
             "over the pairs over sqrt(2): its sd among forests a shot cannot tell apart, the "
             "RMSE left to an inversion that knew every forest's waveform exactly. The "
             "ground-return cover is 1 - Eg/Eg0.\n",
             "| sensor | rays (x table's) | pairs | cover | PAI | canopy height (m) | Pgap | "
             "ground-return cover |", "|---|---|---|---|---|---|---|---|"]
    for sensor, a in alike.items():
        if a is None:
            continue
        for r in a["rows"]:
            sd = {name: r[name] / math.sqrt(2.0) for name in
                  ("cover", "pai", "canopy_height", "pgap", "ground_return_cover")}
            lines.append(f"| {sensor.upper()} | {r['rays_factor']:.0f} | {r['pairs']} of "
                         f"{r['entries'] * (r['entries'] - 1) // 2} | {sd['cover']:.3f} | "
                         f"{sd['pai']:.2f} | {sd['canopy_height']:.2f} | {sd['pgap']:.3f} | "
                         f"{sd['ground_return_cover']:.3f} |")
    return "\n".join(lines) + "\n"


def concatenate(parts):
    """The parts' columns end to end; a column some part lacks (another sensor's method) is NaN
    in its rows."""
    keys = set.union(*(set(p) for p in parts))
    length = [len(p["shot_number"]) for p in parts]
    return {k: np.concatenate([p[k] if k in p else np.full(n, np.nan)
                               for p, n in zip(parts, length)]) for k in keys}


def metric_rows(shots, sensors):
    rows = []
    strata = [("all", None)]
    for low, high in SLOPE_CLASSES_DEG:
        strata.append((f"slope {low:g}-{high:g}",
                       lambda s, lo=low, hi=high: (s["slope_deg"] >= lo) & (s["slope_deg"] < hi)))
    strata.append(("slope 0-20", lambda s: s["slope_deg"] < 20.0))
    strata.append(("true PAI below 5", lambda s: s["pai_true"] < 5.0))
    strata.append(("true PAI 5-8", lambda s: (s["pai_true"] >= 5.0) & (s["pai_true"] < 8.0)))
    strata.append(("true PAI 8 and above", lambda s: s["pai_true"] >= 8.0))
    strata.append(("cone crowns", lambda s: s["crown_shape"] == "cone"))
    strata.append(("ellipsoid crowns", lambda s: s["crown_shape"] == "ellipsoid"))
    strata.append(("inside the table's ranges", lambda s: s["in_table_ranges"]))
    # The shot's own truths (height, cover, PAI) within those of the table's entries: what the
    # posterior, a weighted mean of the entries' truths, can reach at all.
    strata.append(("truth inside the table's truths", lambda s: s["truth_in_table"]))
    strata.append(("truth beyond the table's truths", lambda s: ~s["truth_in_table"]))
    strata.append(("rt flagged", lambda s: s["rt_flag"] != 0))
    strata.append(("rt not flagged", lambda s: s["rt_flag"] == 0))
    strata.append(("slope 0-20, rt not flagged",
                   lambda s: (s["slope_deg"] < 20.0) & (s["rt_flag"] == 0)))
    for sensor in sensors:
        one = {k: v[shots["sensor"] == sensor] for k, v in shots.items()}
        if len(one["shot_number"]) == 0:
            continue
        for stratum, select in strata:
            mask = None if select is None else np.asarray(select(one), bool)
            for method in METHODS:
                for variable in VARIABLES:
                    m = metrics(one, method, variable, mask)
                    if m is None:
                        continue
                    rows.append({"sensor": sensor, "stratum": stratum, "method": method,
                                 "variable": variable, **m})
    return rows


def write_metrics_csv(path, rows):
    header = ["sensor", "stratum", "method", "variable", "n", "bias", "rmse", "coverage90"]
    temporary = path + ".part"
    with open(temporary, "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(header)
        for row in rows:
            writer.writerow([format_value(row[h]) for h in header])
    os.replace(temporary, path)


def write_shots_csv(path, shots):
    names = ["sensor", "stand", "shot_number", "crown_shape", "in_table_ranges", "truth_in_table",
             "slope_deg", "rt_flag"]
    names += [f"{v}_true" for v in VARIABLES if f"{v}_true" in shots]
    names += [f"{v}_{m}" for m in METHODS for v in VARIABLES if f"{v}_{m}" in shots]
    names += [f"{v}_rt_{p}" for v in VARIABLES for p in ("p05", "p95") if f"{v}_rt_{p}" in shots]
    temporary = path + ".part"
    with open(temporary, "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(names)
        for i in range(len(shots["shot_number"])):
            row = []
            for n in names:
                value = shots[n][i]
                if isinstance(value, (np.floating, float)):
                    value = float(value)
                elif isinstance(value, (np.integer,)):
                    value = int(value)
                elif isinstance(value, np.bool_):
                    value = int(bool(value))
                row.append(format_value(value))
            writer.writerow(row)
    os.replace(temporary, path)


def markdown(rows, stratum="all"):
    lines = ["| sensor | method | variable | n | bias | RMSE | 90 % coverage |",
             "|---|---|---|---|---|---|---|"]
    for row in rows:
        if row["stratum"] != stratum:
            continue
        unit = UNITS[row["variable"]]
        cov = row["coverage90"]
        lines.append(
            f"| {row['sensor'].upper()} | {row['method']} | {row['variable']}"
            f"{' (' + unit + ')' if unit else ''} | {row['n']} | {row['bias']:+.3f} | "
            f"{row['rmse']:.3f} | {'—' if not math.isfinite(cov) else f'{cov:.2f}'} |")
    return "\n".join(lines) + "\n"


def markdown_strata(rows, variables=("canopy_height", "cover", "pai", "ground_elevation", "pgap")):
    """RMSE (and rt's coverage) by stratum: where each method fails."""
    strata = []
    for row in rows:
        if row["stratum"] != "all" and row["stratum"] not in strata:
            strata.append(row["stratum"])
    lines = ["| sensor | stratum | method | " + " | ".join(
        f"{v} bias / RMSE" for v in variables) + " |", "|---|---|---|" + "---|" * len(variables)]
    index = {(r["sensor"], r["stratum"], r["method"], r["variable"]): r for r in rows}
    sensors = sorted({r["sensor"] for r in rows})
    for sensor in sensors:
        for stratum in strata:
            for method in METHODS:
                cells = []
                for v in variables:
                    r = index.get((sensor, stratum, method, v))
                    if r is None:
                        cells.append("")
                        continue
                    text = f"{r['bias']:+.2f} / {r['rmse']:.2f}"
                    if math.isfinite(r["coverage90"]):
                        text += f" ({r['coverage90']:.2f})"
                    cells.append(text)
                if any(cells):
                    n = max(index[(sensor, stratum, method, v)]["n"] for v in variables
                            if (sensor, stratum, method, v) in index)
                    lines.append(f"| {sensor.upper()} | {stratum} (n {n}) | {method} | "
                                 + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# Figures.


def plot_scatter(shots, sensors, path):
    variables = [v for v in ("canopy_height", "cover", "pai", "ground_elevation", "pgap")
                 if f"{v}_true" in shots]
    figure, axes = plt.subplots(len(sensors), len(variables),
                                figsize=(4.0 * len(variables), 3.8 * len(sensors)), squeeze=False)
    for r, sensor in enumerate(sensors):
        one = {k: v[shots["sensor"] == sensor] for k, v in shots.items()}
        for c, variable in enumerate(variables):
            ax = axes[r][c]
            truth = one[f"{variable}_true"]
            if variable == "ground_elevation":
                # Elevations span the stands' 0-800 m: the error is what shows.
                ax.set_ylabel("estimate − truth (m)")
            else:
                ax.set_ylabel("estimate")
            low, high = np.nanmin(truth), np.nanmax(truth)
            for method in METHODS:
                estimate = one.get(f"{variable}_{method}")
                if estimate is None or not np.isfinite(estimate).any():
                    continue
                y = estimate - truth if variable == "ground_elevation" else estimate
                # ICESat-2's hundred segments drawn larger than the waveforms' thousands of shots.
                ax.scatter(truth, y, s=4 if truth.size > 500 else 14, alpha=0.35,
                           color=COLOURS[method], label=method, linewidths=0)
            if variable == "ground_elevation":
                ax.axhline(0.0, color="k", lw=0.8)
                ax.set_ylim(-15, 15)
            else:
                ax.plot([low, high], [low, high], "k-", lw=0.8)
                if variable in ("cover", "pgap"):
                    ax.set_ylim(-0.05, 1.05)
                if variable == "pai":
                    ax.set_ylim(-0.2, 12)
            unit = UNITS[variable]
            ax.set_xlabel(f"true {variable}" + (f" ({unit})" if unit else ""))
            ax.set_title(f"{sensor.upper()}: {variable}")
            # A legend on the first row, and on a row of other methods (ICESat-2's).
            if (r == 0 or sensor == "icesat2") and ax.get_legend_handles_labels()[0]:
                ax.legend(markerscale=3 if truth.size > 500 else 1.5, fontsize=8)
    figure.tight_layout()
    save_figure(figure, path)


def plot_slope(shots, sensors, path):
    variables = [v for v in ("canopy_height", "cover", "pai", "ground_elevation", "pgap")
                 if f"{v}_true" in shots]
    edges = np.arange(0.0, 30.1, 5.0)
    centres = 0.5 * (edges[1:] + edges[:-1])
    figure, axes = plt.subplots(len(sensors), len(variables),
                                figsize=(4.0 * len(variables), 3.5 * len(sensors)), squeeze=False)
    for r, sensor in enumerate(sensors):
        one = {k: v[shots["sensor"] == sensor] for k, v in shots.items()}
        for c, variable in enumerate(variables):
            ax = axes[r][c]
            for method in METHODS:
                estimate = one.get(f"{variable}_{method}")
                if estimate is None or not np.isfinite(estimate).any():
                    continue
                truth = one[f"{variable}_true"]
                b, e = [], []
                for lo, hi in zip(edges[:-1], edges[1:]):
                    mask = (one["slope_deg"] >= lo) & (one["slope_deg"] < hi)
                    b.append(bias(estimate[mask], truth[mask]))
                    e.append(rmse(estimate[mask], truth[mask]))
                ax.plot(centres, b, "o-", color=COLOURS[method], label=f"{method} bias", ms=3)
                ax.plot(centres, e, "s--", color=COLOURS[method], label=f"{method} RMSE", ms=3,
                        alpha=0.7)
            ax.axhline(0.0, color="k", lw=0.6)
            ax.set_xlabel("slope (deg)")
            unit = UNITS[variable]
            ax.set_ylabel("error" + (f" ({unit})" if unit else ""))
            ax.set_title(f"{sensor.upper()}: {variable}")
    # One legend for every panel: the colour is the method, the line bias (solid) or RMSE.
    handles = [Line2D([], [], color=COLOURS[m], label=m) for m in METHODS]
    handles += [Line2D([], [], color="0.3", ls="-", marker="o", ms=3, label="bias"),
                Line2D([], [], color="0.3", ls="--", marker="s", ms=3, label="RMSE")]
    figure.legend(handles=handles, loc="upper center", ncol=len(handles), fontsize=8,
                  frameon=False)
    figure.tight_layout(rect=(0, 0, 1, 0.95))
    save_figure(figure, path)


# ---------------------------------------------------------------------------------------------


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--glaswave", required=True, help="the glaswave binary")
    parser.add_argument("--quick", action="store_true", help="small runs, for a check")
    parser.add_argument("--size", choices=sorted(SIZES), default=None,
                        help="the study's size (--quick is --size quick)")
    parser.add_argument("--out", default="out/studies/retrieval")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--sensors", default=None,
                        help="comma-separated, among gedi, glas, icesat2 (default: every one the "
                             "size has stands for)")
    args = parser.parse_args()
    size_name = args.size or ("quick" if args.quick else "full")
    size = SIZES[size_name]
    os.makedirs(args.out, exist_ok=True)
    runs = Runs(args.glaswave, args.out, args.threads)
    started = time.monotonic()
    sensors = [s for s in SENSORS if size["stands"][s] > 0]
    if args.sensors:
        chosen = args.sensors.split(",")
        unknown = [s for s in chosen if s not in SENSORS]
        if unknown:
            parser.error(f"--sensors: unknown {', '.join(unknown)}; choose among "
                         f"{', '.join(SENSORS)}")
        sensors = [s for s in sensors if s in chosen]
    parts, speeds, tables, saturation, alike = [], {}, {}, {}, {}
    for sensor in sensors:
        table = runs.table(table_document(sensor, size), f"{sensor} table")
        with netCDF4.Dataset(table) as nc:
            tables[sensor] = {"entries": len(nc.dimensions["entry"]),
                              "rays_per_shot": int(nc.getncattr("rays_per_shot")),
                              "shots_per_entry": int(nc.getncattr("shots_per_entry"))}
        stands = held_out_stands(sensor, size["stands"][sensor])
        if sensor == "icesat2":
            part, summary = read_segments(runs, table, stands, size)
        else:
            shots_files = [runs.run(stand_document(sensor, stand, size), f"{sensor} stand {i}")
                           for i, stand in enumerate(stands)]
            product, summary = runs.retrieve(shots_files, table,
                                             f"{sensor}: {len(stands)} stands")
            part = read_retrieval(product, shots_files, stands, sensor)
        tables[sensor]["truth_ranges"] = table_truth_ranges(table)
        part["truth_in_table"] = truth_in_table(part, tables[sensor]["truth_ranges"])
        if sensor != "icesat2":  # a waveform's: its detector's noise against its ground return
            with netCDF4.Dataset(table) as nc:
                saturation[sensor] = saturation_rows(part, sensor, float(nc.getncattr("bin_ns")),
                                                     float(nc.getncattr("pulse_sigma_ns")),
                                                     size["rays"])
        alike[sensor] = table_alike_pairs(table)
        parts.append(part)
        speeds[sensor] = {"shots": summary["shots"], "methods_wall_s": summary["wall_s"],
                          "shots_per_s": summary["shots_per_s"],
                          "command_wall_s": summary["command_wall_s"],
                          "command_cpu_s": summary.get("command_cpu_s", math.nan),
                          "shots_per_cpu_s": summary["shots"] / summary.get("command_cpu_s",
                                                                            math.nan)}
    shots = concatenate(parts)
    rows = metric_rows(shots, sensors)
    write_metrics_csv(os.path.join(args.out, "retrieval_metrics.csv"), rows)
    write_shots_csv(os.path.join(args.out, "retrieval_shots.csv"), shots)
    text = ("# Retrieval study: every method against the truth\n\n"
            f"{size_name} size: {json.dumps(size)}\n\n"
            "## All shots\n\n" + markdown(rows) +
            "\n## By stratum (bias / RMSE, rt's 90 % coverage in brackets)\n\n" +
            markdown_strata(rows) +
            "\n## The ground return's change per unit PAI against the noise\n\n" +
            markdown_saturation(saturation) +
            "\n## Forests a waveform cannot tell apart\n\n" + markdown_alike(alike))
    write_atomic(os.path.join(args.out, "retrieval_metrics.md"), text)
    plot_scatter(shots, sensors, os.path.join(args.out, "retrieval_scatter.png"))
    plot_slope(shots, sensors, os.path.join(args.out, "retrieval_slope.png"))
    summary = {
        "size": size_name,
        "tables": tables,
        "speed": speeds,
        "glaswave_seconds": runs.seconds,
        "wall_s": time.monotonic() - started,
        "metrics": [r for r in rows if r["stratum"] == "all"],
        "saturation": saturation,
        "alike_pairs": alike,
    }
    write_atomic(os.path.join(args.out, "summary.json"),
                 json.dumps(summary, indent=1, default=float) + "\n")
    log(f"{len(shots['shot_number'])} shots in {summary['wall_s']:.0f} s; "
        f"{os.path.join(args.out, 'retrieval_metrics.md')}")


if __name__ == "__main__":
    main()
