#!/usr/bin/python3
"""Bad and hostile inputs tried on the built glaswave (issue 13), as a markdown table.

    /usr/bin/python3 tests/reliability/inputs_tried.py [--glaswave build/pipeline/glaswave]
        [--out inputs_tried.md] [--only SUBSTRING]

Each case runs in a scratch directory with 20 s of CPU (`prlimit --cpu=20`) and 120 s of wall
time (`timeout -s KILL 120`, for what blocks without spending CPU), and is recorded with its exit
status, the first line of stderr and a verdict. The limit is CPU time so that a loaded machine
does not make a fast case look hung. A case is a bug when it crashes (a signal: exit >= 128),
hangs (spends its CPU, or blocks until the wall limit), echoes a file's content (every hostile file holds the
marker below), leaves a product under its final name after a failure, or fails with more (or
less) than one `glaswave: error:` line. Cases marked `ok` are meant to succeed. A full disk is a
small tmpfs when this runs as root (else `ulimit -f`). ctest runs it on the built command (the
test inputs_tried, label reliability); by hand, a tool for trying new inputs.
"""

import argparse
import json
import math
import os
import pathlib
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time

from osgeo import osr

MARKER = "SECRET-MARKER-7f3a"
PRODUCTS = {"shots.nc", "footprints.geojson", "footprints.gpkg", "brf.json", "scene.tif",
            "sensitivity.csv", "sensitivity.md", "waveforms.png", "track_map.png"}
CPU_LIMIT_S = 20
WALL_LIMIT_S = 120
MAX_LINE = 1000  # a one-line message quotes input as a bounded excerpt (issue 28)


# WGS 84 latitude, longitude and height to Earth-fixed x, y, z (m), through PROJ.
GEODETIC, GEOCENTRIC = osr.SpatialReference(), osr.SpatialReference()
GEODETIC.ImportFromEPSG(4979)
GEOCENTRIC.ImportFromEPSG(4978)
ecef = osr.CoordinateTransformation(GEODETIC, GEOCENTRIC).TransformPoint


class Trial:
    def __init__(self, glaswave, scratch):
        self.glaswave = glaswave
        self.dir = pathlib.Path(scratch)
        self.rows = []
        self.count = 0

    # ---- files ---------------------------------------------------------------------------
    def path(self, name):
        return self.dir / name

    def write(self, name, text, mode="w"):
        p = self.path(name)
        p.parent.mkdir(parents=True, exist_ok=True)
        with open(p, mode) as f:
            f.write(text)
        return str(p)

    def base(self, **changes):
        config = {
            "seed": 1,
            "sensor": {"preset": "glas"},
            "simulation": {"rays_per_shot": 200, "max_order": 3},
            "terrain": {"plane": {"origin_lat_deg": 46.0, "origin_lon_deg": 8.0}},
            "canopy": None,
            "track": {"start_lat_deg": 46.0, "start_lon_deg": 8.0, "shots": 2},
        }
        for key, value in changes.items():
            section, _, leaf = key.partition("__")
            if leaf:
                config.setdefault(section, {})
                if config[section] is None:
                    config[section] = {}
                config[section][leaf] = value
            else:
                config[section] = value
        return config

    def config(self, name="config.json", **changes):
        return self.write(name, json.dumps(self.base(**changes), indent=1))

    # ---- running ---------------------------------------------------------------------------
    def run(self, description, args, expect="error", out=None, shell_prefix="", env=None,
            cwd=None, says=None, command=None):
        """Runs glaswave ARGS (or `command`, a program of its own); `out` is the output directory
        whose products are checked; `says`, text that stderr must hold (the cause named, a
        warning given)."""
        self.count += 1
        if out is not None:
            shutil.rmtree(out, ignore_errors=True)
        command = ["timeout", "-s", "KILL", str(WALL_LIMIT_S), "prlimit", f"--cpu={CPU_LIMIT_S}",
                   *(command or [self.glaswave, *args])]
        started = time.monotonic()
        cpu_before = _children_cpu_s()
        if shell_prefix:
            line = shell_prefix + " " + " ".join(_quote(a) for a in command)
            done = subprocess.run(["bash", "-c", line], capture_output=True, env=env, cwd=cwd)
        else:
            done = subprocess.run(command, capture_output=True, env=env, cwd=cwd)
        wall_s = time.monotonic() - started
        cpu_s = _children_cpu_s() - cpu_before
        status = done.returncode if done.returncode >= 0 else 128 - done.returncode
        stderr = done.stderr.decode("utf-8", "replace")
        lines = [l for l in stderr.splitlines() if l.strip()]
        first = lines[0] if lines else ""
        problems = []
        if status == 137 and wall_s >= WALL_LIMIT_S - 0.5:
            problems.append(f"HANG (blocked: killed after {WALL_LIMIT_S} s of wall time)")
        elif status == 128 + signal.SIGXCPU:
            problems.append(f"HANG (spent its {CPU_LIMIT_S} s of CPU)")
        elif status >= 128:
            problems.append(f"CRASH (signal {status - 128})")
        if MARKER in stderr or MARKER in done.stdout.decode("utf-8", "replace"):
            problems.append("ECHOES A FILE")
        if "\x1b" in stderr:
            problems.append("RAW ESCAPE CODE")
        if out is not None and status != 0 and os.path.isdir(out):
            left = sorted(p.name for p in pathlib.Path(out).rglob("*") if p.name in PRODUCTS)
            if left:
                problems.append("PRODUCT LEFT: " + ", ".join(left))
        errors = [l for l in lines if l.startswith("glaswave: error:")]
        if expect == "ok" and status != 0:
            problems.append("FAILED")
        if expect != "ok" and status == 0:
            problems.append("ACCEPTED")
        if expect != "ok" and status not in (0, 124) and status < 128 and len(errors) != 1:
            problems.append(f"{len(errors)} error lines, {len(lines)} lines")
        if len(first) > MAX_LINE:
            problems.append(f"OVERSIZED MESSAGE ({len(first)} characters)")
        if says is not None and says not in stderr:
            problems.append(f"DOES NOT SAY {says!r}")
        if expect not in ("ok", "error") and status != expect and not problems:
            problems.append(f"exit {status}, expected {expect}")
        verdict = "; ".join(problems) if problems else ("works" if status == 0 else "clear error")
        self.rows.append((self.count, description, status, first, verdict, wall_s, cpu_s))
        print(f"{self.count:3d} {status:3d} {verdict[:30]:30s} {description[:60]}", flush=True)
        return done

    def table(self):
        bugs = [r for r in self.rows if is_bug(r[4])]
        text = [
            "# Inputs tried on glaswave (issue 13)", "",
            f"{len(self.rows)} inputs, each run as `timeout -s KILL {WALL_LIMIT_S} prlimit "
            f"--cpu={CPU_LIMIT_S} glaswave ...` by "
            "`tests/reliability/inputs_tried.py`; exit status, the first line of stderr, and the "
            "verdict (a crash, a hang, an echoed file, a product left after a failure or more "
            "than one error line would be named). "
            f"{len(bugs)} found wanting.", "",
            "| # | input | exit | first line of stderr | verdict | wall s | CPU s |",
            "|---|---|---|---|---|---|---|",
        ]
        for n, description, status, first, verdict, wall_s, cpu_s in self.rows:
            first = first.replace(str(self.dir) + "/", "").replace("|", "\\|")
            if len(first) > 200:
                first = first[:197] + "..."
            description = description.replace("|", "\\|").replace("`", "'")
            first = "`" + first.replace("`", "'") + "`" if first else ""
            text.append(f"| {n} | {description} | {status} | {first} | {verdict} | {wall_s:.1f} | "
                        f"{cpu_s:.1f} |")
        return "\n".join(text) + "\n"


def is_bug(verdict):
    return verdict not in ("works", "clear error") and not verdict.startswith("works;")


def _children_cpu_s():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _quote(text):
    return "'" + text.replace("'", "'\\''") + "'"


# ---- the cases -------------------------------------------------------------------------------

def issue_items(t):
    out = str(t.path("out"))
    # 1. A full disk: a 300 KiB filesystem of its own (as root), else a file size limit.
    disk = t.path("small_disk")
    disk.mkdir(exist_ok=True)
    mounted = os.geteuid() == 0 and subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=300k", "tmpfs", str(disk)],
        capture_output=True).returncode == 0
    full = t.config("full.json", track__shots=40, output={"per_order": True})
    try:
        if mounted:
            t.run("1. full disk: run into a 300 KiB tmpfs", ["run", full, "--quiet", "--out",
                  str(disk / "run")], out=str(disk / "run"))
        t.run("1. full disk: run under `ulimit -f 64` (EFBIG)", ["run", full, "--quiet", "--out",
              out], out=out, shell_prefix="ulimit -f 64;")
    finally:
        if mounted:
            subprocess.run(["umount", str(disk)])
    # 2. Stands: 3000 polygons over the track.
    features = []
    for i in range(3000):
        w = 7.9 + (i % 60) * 0.003
        s = 45.95 + (i // 60) * 0.002
        features.append({"type": "Feature", "properties": {"pai": 1 + i % 3},
                         "geometry": {"type": "Polygon", "coordinates": [[
                             [w, s], [w + 0.0025, s], [w + 0.0025, s + 0.0015], [w, s + 0.0015],
                             [w, s]]]}})
    stands = t.write("stands3000.geojson", json.dumps(
        {"type": "FeatureCollection", "features": features}))
    t.run("2. 3000 stand polygons, 20 shots", ["run", t.config(
        "stands.json", canopy={"stands": stands}, track__shots=20), "--quiet", "--out", out],
        expect="ok", out=out)
    ring = [[8.0 + 0.01 * math.cos(2 * math.pi * k / 1_000_000),
             46.0 + 0.01 * math.sin(2 * math.pi * k / 1_000_000)] for k in range(1_000_000)]
    ring.append(ring[0])
    big = t.write("stand_1e6.geojson", json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"pai": 2},
         "geometry": {"type": "Polygon", "coordinates": [ring]}}]}))
    t.run("2. one stand polygon of 1 000 000 vertices, 5 shots", ["run", t.config(
        "stand_big.json", canopy={"stands": big}, track__shots=5), "--quiet", "--out", out],
        expect="ok", out=out)
    # 3. Run sizes.
    for description, changes in [
            ("3. sensor.bins 100000000", {"sensor__bins": 100000000}),
            ("3. sensor.ifov_rad 3", {"sensor__ifov_rad": 3}),
            ("3. track.altitude_m 1e10", {"track__altitude_m": 1e10}),
            ("3. simulation.rays_per_shot 1e12", {"simulation__rays_per_shot": 10**12}),
            ("3. canopy.crown_radius_m 0.01 (1e9 trees a shot)",
             {"canopy": {"crown_radius_m": 0.01}}),
            ("3. output with everything off", {"output": {"netcdf": False, "footprints": False}}),
            ("3. sensor.bins 16777216 x per_order x max_order 1000",
             {"sensor__bins": 16777216, "output": {"per_order": True},
              "simulation": {"max_order": 1000}}),
            ("3. orbit with apogee beyond 40 000 km",
             {"track": {"type": "orbit", "semi_major_axis_m": 4e7, "eccentricity": 0.5}})]:
        config = t.config("size.json", **changes)
        t.run(description + " (check)", ["check", config])
        t.run(description + " (run)", ["run", config, "--quiet", "--out", out], out=out)
    # 4. A file of another kind as the ephemeris: no line of it echoed.
    shadow = t.write("shadow", f"root:$6${MARKER}$Zk3Hq0:19000:0:99999:7:::\n")
    for name, path in [("a password-hash file", shadow), ("/etc/passwd", "/etc/passwd")]:
        t.run(f"4. ephemeris pointed at {name}", ["run", t.config(
            "eph.json", track={"type": "ephemeris", "ephemeris": path}), "--quiet", "--out", out],
            out=out)
    # 5. 100 000 levels under a known key.
    deep = "[" * 100000 + "]" * 100000
    for key, text in [("seed", '{"seed": %s}' % deep), ("canopy", '{"canopy": %s}' % deep),
                      ("track.points", '{"track": {"type": "points", "points": %s}}' % deep)]:
        config = t.write("deep.json", text)
        t.run(f"5. {key} nested 100 000 levels (check)", ["check", config])
        t.run(f"5. {key} nested 100 000 levels (run)", ["run", config, "--quiet", "--out", out],
              out=out)
    t.run("5. --set seed= nested 60 000 levels", ["check", t.config(), "--set",
          "seed=" + "[" * 60000 + "]" * 60000])
    # 6. An interrupted run: killed half way, then the same command, then --resume.
    long = t.config("long.json", track__shots=1500, simulation__rays_per_shot=500)
    shutil.rmtree(out, ignore_errors=True)
    process = subprocess.Popen([t.glaswave, "run", long, "--quiet", "--threads", "1", "--out",
                                out], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    journal = pathlib.Path(out) / "glaswave.journal"
    deadline = time.monotonic() + WALL_LIMIT_S
    while time.monotonic() < deadline and process.poll() is None and not (
            journal.exists() and journal.stat().st_size > 0):
        time.sleep(0.05)
    time.sleep(0.3)  # a few batches into the journal
    process.send_signal(signal.SIGKILL)
    process.wait()
    t.run("6. the same command after a SIGKILL half way", ["run", long, "--quiet", "--out", out])
    t.run("6. the same command with --resume", ["run", long, "--quiet", "--out", out, "--resume"],
          expect="ok")
    shutil.rmtree(out, ignore_errors=True)
    # 7. The rest of the list.
    config = t.config()
    t.run("7. --seed 18446744073709551616 (2^64)", ["run", config, "--seed",
          "18446744073709551616", "--quiet", "--out", out], out=out)
    t.run("7. duplicate JSON key", ["check", t.write(
        "dup.json", '{"seed": 1, "canopy": {"pai": 1, "pai": 2}}')])
    for key in ("crowns_file", "stands"):
        stand = t.write("stand.geojson", json.dumps({"type": "FeatureCollection", "features": [{
            "type": "Feature", "properties": {key: "other"}, "geometry": {
                "type": "Polygon", "coordinates": [[[7.99, 45.99], [8.01, 45.99], [8.01, 46.01],
                                                    [7.99, 46.01], [7.99, 45.99]]]}}]}))
        t.run(f"7. stand property {key}", ["check", t.config(canopy={"stands": stand})])
    t.run("7. track point with an unknown key", ["check", t.config(track={
        "type": "points", "points": [{"lat_deg": 46, "lon_deg": 8, "name": "a"}]})])
    crowns = t.write("crowns.csv", "x,y,base_m,radius_m,half_height_m\n1e308,0,10,5,5\n")
    t.run("7. crowns at x = 1e308", ["check", t.config(canopy={"crowns_file": crowns})])
    t.run("7. seed written 0x10 in JSON", ["check", t.write("hex.json", '{"seed": 0x10}')])
    t.run("7. --set seed=0x10", ["check", config, "--set", "seed=0x10"])
    t.run("7. --seed 0x10", ["run", config, "--seed", "0x10", "--quiet", "--out", out], out=out)
    stand = t.write("stand500.geojson", json.dumps({"type": "FeatureCollection", "features": [{
        "type": "Feature", "properties": {"pai": 1}, "geometry": {
            "type": "Polygon", "coordinates": [[[500, 45.99], [500.02, 45.99], [500.02, 46.01],
                                                [500, 46.01], [500, 45.99]]]}}]}))
    t.run("7. stand at longitude 500", ["check", t.config(canopy={"stands": stand})])
    t.run("7. crowns file /dev/zero", ["check", t.config(canopy={"crowns_file": "/dev/zero"})])
    t.run('7. --out ""', ["run", config, "--quiet", "--out", ""], cwd=str(t.dir))
    t.run('7. --seed ""', ["run", config, "--seed", "", "--quiet", "--out", out], out=out)
    t.run('7. --shots ""', ["run", config, "--shots", "", "--quiet", "--out", out], out=out)
    share = t.path("share")
    (share / "plots").mkdir(parents=True, exist_ok=True)
    (share / "plots" / "plot_products.py").write_text(
        "import sys\nprint('Traceback (most recent call last):', file=sys.stderr)\n"
        "print('  File \"x.py\", line 1', file=sys.stderr)\n"
        "print('ValueError: no plot today', file=sys.stderr)\nsys.exit(1)\n")
    env = dict(os.environ, GLASWAVE_SHARE=str(share))
    t.run("7. a plot script that fails with a traceback (a warning: the products are complete)",
          ["run", t.config("plots.json", output={"plots": True}), "--quiet", "--out", out],
          env=env, expect="ok", says="warning: plots: ")
    t.run("7. an escape code in a key", ["check", t.config(canopy={"p\x1b[31mai": 1})])
    # 8. Roughness at 0.5 m correlation under the glas footprint: represented, or refused.
    t.run("8. roughness 0.45 m RMS at 0.5 m correlation (glas)", ["run", t.config(
        "rough.json", terrain={"plane": {"origin_lat_deg": 46.0, "origin_lon_deg": 8.0},
                               "roughness": {"rms_m": 0.45, "correlation_m": 0.5}}),
        "--quiet", "--out", out], expect="ok", out=out)
    t.run("8. roughness at 0.05 m correlation (glas)", ["check", t.config(
        "rough.json", terrain={"plane": {"origin_lat_deg": 46.0, "origin_lon_deg": 8.0},
                               "roughness": {"rms_m": 0.45, "correlation_m": 0.05}})])
    # 9. Bare ground at 500 rays a shot: a run (the product's canopy reading is below).
    done = t.run("9. bare ground at 500 rays a shot", ["run", t.config(
        "bare.json", simulation__rays_per_shot=500, track__shots=10), "--quiet", "--out", out],
        expect="ok", out=out)
    if done.returncode == 0:
        row = list(t.rows[-1])
        row[4] += "; " + bare_ground_reading(out)
        t.rows[-1] = tuple(row)


def bare_ground_reading(out):
    """What the product says of canopy on bare ground (issue 13 item 9): the estimated canopy
    height and the ground estimate's error, worst over shots and bands."""
    try:
        import netCDF4
        import numpy as np
        with netCDF4.Dataset(os.path.join(out, "shots.nc")) as ds:
            height = np.ma.filled(ds["canopy_height_est"][:].astype(float), np.nan)
            ground = np.ma.filled(ds["ground_elev_est"][:].astype(float), np.nan)
            elev = np.ma.filled(ds["elev"][:].astype(float), np.nan)
            error = ground - elev.reshape(elev.shape + (1,) * (ground.ndim - elev.ndim))
            return (f"canopy_height_est at most {np.nanmax(height):.2f} m, ground_elev_est "
                    f"within {np.nanmax(np.abs(error)):.2f} m")
    except Exception as error:  # a reading for the table, not a verdict
        return f"not read: {error}"


def configuration_cases(t):
    out = str(t.path("out"))
    config = t.config()
    t.run("config file missing", ["check", str(t.path("missing.json"))])
    t.run("config is a directory", ["check", str(t.dir)])
    t.run("config empty file", ["check", t.write("empty.json", "")])
    t.run("config `null`", ["check", t.write("null.json", "null")])
    t.run("config a top-level array", ["check", t.write("array.json", "[1, 2]")])
    t.run("config binary garbage (with the marker)", ["check", t.write(
        "garbage.json", b"\x00\xff\xfe" + MARKER.encode() + b"\x01" * 50, "wb")])
    t.run("config with a UTF-8 BOM", ["check", t.write(
        "bom.json", b"\xef\xbb\xbf" + json.dumps(t.base()).encode(), "wb")], expect="ok")
    t.run("config with CRLF line ends", ["check", t.write(
        "crlf.json", json.dumps(t.base(), indent=1).replace("\n", "\r\n"), "w")], expect="ok")
    t.run("config with NaN literal", ["check", t.write("nan.json", '{"seed": 1, "canopy": '
                                                       '{"pai": NaN}}')])
    t.run("config with 1e999 (infinity)", ["check", t.write("inf.json", '{"canopy": '
                                                            '{"pai": 1e999}}')])
    t.run("config truncated mid-object", ["check", t.write("cut.json", '{"canopy": {"pai": 2')])
    t.run("config invalid UTF-8 in a key", ["check", t.write(
        "utf8.json", b'{"can\xffopy": {}}', "wb")])
    sparse = t.path("huge.json")
    with open(sparse, "wb") as f:
        f.truncate(300 * 1024 * 1024)
    t.run("config a 300 MiB (sparse) file", ["check", str(sparse)])
    sparse.unlink()
    t.run("config /dev/zero", ["check", "/dev/zero"])
    t.run("config /dev/null", ["check", "/dev/null"])
    fifo = t.path("fifo.json")
    os.mkfifo(fifo)
    t.run("config a FIFO nobody writes", ["check", str(fifo)])
    fifo.unlink()
    unreadable = t.config("unreadable.json")
    os.chmod(unreadable, 0)
    t.run("config mode 000" + (" (root reads it anyway)" if os.geteuid() == 0 else ""),
          ["check", unreadable], expect="ok" if os.geteuid() == 0 else "error")
    for description, changes in [
            ("seed a string", {"seed": "abc"}),
            ("seed -1", {"seed": -1}),
            ("seed 1.5", {"seed": 1.5}),
            ("canopy.pai a string", {"canopy": {"pai": "2"}}),
            ("canopy.pai true", {"canopy": {"pai": True}}),
            ("canopy.cover 1.0", {"canopy": {"cover": 1.0}}),
            ("canopy.cover -0.1", {"canopy": {"cover": -0.1}}),
            ("canopy a list", {"canopy": [1, 2]}),
            ("sensor.bins 0", {"sensor__bins": 0}),
            ("sensor.bins -5", {"sensor__bins": -5}),
            ("track.shots -1", {"track__shots": -1}),
            ("track.shots 0", {"track__shots": 0}),
            ("track.shots 1e12", {"track__shots": 10**12}),
            ("simulation.rays_per_shot 0", {"simulation__rays_per_shot": 0}),
            ("simulation.max_order -1", {"simulation__max_order": -1}),
            ("unknown top-level key (typo)", {"canpoy": {}}),
            ("unknown preset", {"sensor": {"preset": "glass"}}),
            ("empty band list", {"sensor": {"bands": []}}),
            ("two bands of the same name", {"sensor": {"bands": [
                {"name": "a", "wavelength_nm": 532, "pulse_energy_mJ": 1,
                 "atmos_transmission_roundtrip": 0.9}] * 2}}),
            ("leaf reflectance + transmittance > 1",
             {"canopy": {"leaf_reflectance": 0.7, "leaf_transmittance": 0.7}}),
            ("per-band value for an unknown band", {"canopy": {"leaf_reflectance": {"999": 0.1}}}),
            ("track.points empty", {"track": {"type": "points", "points": []}}),
            ("track.points latitude 91", {"track": {"type": "points", "points": [
                {"lat_deg": 91, "lon_deg": 8}]}}),
            ("orbit eccentricity 1.5", {"track": {"type": "orbit", "eccentricity": 1.5}}),
            ("start_time not a date", {"track__start_time": "yesterday"}),
            ("start_time 2005-02-30", {"track__start_time": "2005-02-30T00:00:00Z"}),
            ("brf.scene_size_m 1e9", {"brf": {"scene_size_m": 1e9}}),
            ("brf 1e6 pixels a side", {"brf": {"scene_size_m": 10000,
                                               "image_resolution_m": 0.01}}),
            ("brf.photons 1e12", {"brf": {"photons": 10**12}}),
            ("brf with no views", {"brf": {"views": []}}),
            ("detector bits 8 without saturation", {"detector": {"enabled": True, "bits": 8}}),
            ("$schema a number", {"$schema": 5})]:
        t.run("config: " + description, ["check", t.config("bad.json", **changes)])
    t.run("brf: 5 cm crowns over a 10 km tile (memory)", ["brf", t.config(
        "brf.json", canopy={"crown_radius_m": 0.05, "cover": 0.9},
        brf={"scene_size_m": 10000, "image_resolution_m": 10}), "--quiet", "--out", out],
        out=out)
    # The command line.
    for description, args in [
            ("no arguments", []),
            ("unknown command", ["simulate", config]),
            ("unknown option", ["run", config, "--fast"]),
            ("--set without =", ["check", config, "--set", "canopy.pai"]),
            ("--set =1", ["check", config, "--set", "=1"]),
            ("--set unknown.key=1", ["check", config, "--set", "unknown.key=1"]),
            ("--set canopy.pai=NaN", ["check", config, "--set", "canopy={}", "--set",
                                      "canopy.pai=NaN"]),
            ("--set canopy.pai=-inf", ["check", config, "--set", "canopy={}", "--set",
                                       "canopy.pai=-inf"]),
            ("--set seed.x=1 (a key under a number)", ["check", config, "--set", "seed.x=1"]),
            ("--threads -1", ["run", config, "--threads", "-1", "--quiet", "--out", out]),
            ("--threads abc", ["run", config, "--threads", "abc", "--quiet", "--out", out]),
            ("--threads 1e9", ["run", config, "--threads", "1000000000", "--quiet", "--out",
                               out]),
            ("--shots 5:2", ["run", config, "--shots", "5:2", "--quiet", "--out", out]),
            ("--shots 100:200 beyond a 2-shot track", ["run", config, "--shots", "100:200",
                                                        "--quiet", "--out", out]),
            ("--shots -1:2", ["run", config, "--shots", "-1:2", "--quiet", "--out", out]),
            ("--seed -1", ["run", config, "--seed", "-1", "--quiet", "--out", out]),
            ("--debug-ray 9:0 (no shot 9)", ["run", config, "--debug-ray", "9:0", "--quiet",
                                             "--out", out]),
            ("sweep --vary with no values", ["sweep", config, "--vary", "canopy.pai=",
                                             "--quiet", "--out", out]),
            ("sweep --vary unknown key", ["sweep", config, "--vary", "canopy.paj=1,2", "--quiet",
                                          "--out", out]),
            ("--out an existing file", ["run", config, "--quiet", "--out", config]),
            ("--out /dev/null", ["run", config, "--quiet", "--out", "/dev/null"]),
            ("--out /proc/x (not writable)", ["run", config, "--quiet", "--out", "/proc/x"])]:
        t.run("command line: " + description, args, out=out if out in args else None)
    t.run("command line: --out under a missing parent (made, as mkdir -p)", [
        "run", config, "--quiet", "--out", str(t.path("no/such/dir/out"))], expect="ok")
    t.run("config: a plane reaches the poles (start_lat_deg 89.9)", [
        "check", t.config("bad.json", track__start_lat_deg=89.9)], expect="ok")


def data_cases(t):
    from osgeo import gdal, osr
    gdal.UseExceptions()
    out = str(t.path("out"))

    def dem(name, values=None, nodata=None, size=60):
        path = str(t.path(name))
        ds = gdal.GetDriverByName("GTiff").Create(path, size, size, 1, gdal.GDT_Float32)
        ds.SetGeoTransform([7.97, 0.001, 0, 46.03, 0, -0.001])
        srs = osr.SpatialReference()
        srs.ImportFromEPSG(4326)
        ds.SetProjection(srs.ExportToWkt())
        band = ds.GetRasterBand(1)
        if nodata is not None:
            band.SetNoDataValue(nodata)
        band.Fill(500.0 if values is None else values)
        ds = None
        return path

    def dem_config(path, name="dem.json"):
        return t.config(name, terrain={"dem": path})

    t.run("DEM: a good one (60 x 60, 0.001 deg)", ["check", dem_config(dem("good.tif"))],
          expect="ok")
    t.run("DEM: missing file", ["check", dem_config(str(t.path("nodem.tif")))])
    t.run("DEM: a directory", ["check", dem_config(str(t.dir))])
    t.run("DEM: an empty file", ["check", dem_config(t.write("empty.tif", ""))])
    t.run("DEM: a text file (the marker)", ["check", dem_config(t.write(
        "text.tif", MARKER + "\n"))])
    t.run("DEM: every value nodata", ["run", dem_config(dem("nodata.tif", -9999, -9999)),
                                      "--quiet", "--out", out], out=out)
    t.run("DEM: NaN values", ["run", dem_config(dem("nan.tif", float("nan"))), "--quiet",
                              "--out", out], out=out)
    t.run("DEM: 1 x 1 pixel", ["run", dem_config(dem("one.tif", size=1)), "--quiet", "--out",
                               out], out=out)
    t.run("DEM: heights 1e30", ["run", dem_config(dem("high.tif", 1e30)), "--quiet", "--out",
                                out], out=out)
    vrt = t.write("huge.vrt", """<VRTDataset rasterXSize="2000000000" rasterYSize="2000000000">
  <SRS>EPSG:4326</SRS><GeoTransform>7.9, 1e-9, 0, 46.1, 0, -1e-9</GeoTransform>
  <VRTRasterBand dataType="Float32" band="1"><NoDataValue>-9999</NoDataValue></VRTRasterBand>
</VRTDataset>
""")
    t.run("DEM: header of 2e9 x 2e9 pixels (VRT)", ["run", dem_config(vrt), "--quiet", "--out",
                                                    out], out=out)
    asc = t.write("huge.asc", "ncols 1000000000\nnrows 1000000000\nxllcorner 7.9\n"
                  "yllcorner 45.9\ncellsize 0.0000001\nNODATA_value -9999\n1 2 3\n")
    t.run("DEM: ASCII grid header of 1e9 x 1e9, 3 values", ["run", dem_config(asc), "--quiet",
                                                            "--out", out], out=out)
    nocrs = str(t.path("nocrs.tif"))
    ds = gdal.GetDriverByName("GTiff").Create(nocrs, 10, 10, 1, gdal.GDT_Float32)
    ds = None
    t.run("DEM: no CRS, no geotransform", ["check", dem_config(nocrs)])
    t.run("DEM: the track off the DEM", ["check", t.config(
        "off.json", terrain={"dem": dem("good.tif")},
        track={"start_lat_deg": 10.0, "start_lon_deg": 10.0, "shots": 2})])

    # Ephemeris CSVs.
    def rows(count=3, step_s=0.025, start=1000.0):
        lines = []
        for i in range(count):
            x, y, z = ecef(46.0 + i * 0.0015, 8.0, 600000.0)
            lines.append(f"{start + i * step_s},{x:.3f},{y:.3f},{z:.3f}")
        return lines

    def eph(name, text):
        return t.config("eph.json", track={"type": "ephemeris",
                                           "ephemeris": t.write(name, text)})

    header = "time,x_m,y_m,z_m"
    t.run("ephemeris: good", ["check", eph("good.csv", "\n".join([header] + rows()) + "\n")],
          expect="ok")
    t.run("ephemeris: UTF-8 BOM", ["check", eph("bom.csv", "\ufeff" + "\n".join(
        [header] + rows()) + "\n")], expect="ok")
    t.run("ephemeris: CRLF", ["check", eph("crlf.csv", "\r\n".join([header] + rows()) + "\r\n")],
          expect="ok")
    good = rows()
    # Rows are shots in the file's order: beams fire at one time, a file may list beam after beam.
    t.run("ephemeris: times out of order (rows are shots, in file order)", ["check", eph(
        "order.csv", "\n".join([header, good[1], good[0], good[2]]) + "\n")], expect="ok")
    t.run("ephemeris: a time twice (two beams at once)", ["check", eph("twice.csv", "\n".join(
        [header, good[0], good[0]]) + "\n")], expect="ok")
    t.run("ephemeris: empty", ["check", eph("empty.csv", "")])
    t.run("ephemeris: header only", ["check", eph("header.csv", header + "\n")])
    t.run("ephemeris: a column missing", ["check", eph("cols.csv", "time,x_m,y_m\n1,2,3\n")])
    t.run("ephemeris: NaN position", ["check", eph("nan.csv", header + "\n1000,nan,0,0\n")])
    t.run("ephemeris: position at the Earth's centre", ["check", eph(
        "centre.csv", header + "\n1000,0,0,0\n")])
    t.run("ephemeris: a 10 000-byte line", ["check", eph(
        "long.csv", header + "\n" + "1" * 10000 + ",1,1,1\n")])
    t.run("ephemeris: missing file", ["check", t.config("eph.json", track={
        "type": "ephemeris", "ephemeris": str(t.path("noeph.csv"))})])
    t.run("ephemeris: a directory", ["check", t.config("eph.json", track={
        "type": "ephemeris", "ephemeris": str(t.dir)})])
    # Crowns CSVs.
    crowns_header = "x,y,base_m,radius_m,half_height_m"
    for description, text, expect in [
            ("good", crowns_header + "\n0,0,5,3,3\n", "ok"),
            ("UTF-8 BOM and CRLF", "\ufeff" + crowns_header + "\r\n0,0,5,3,3\r\n", "ok"),
            ("negative radius", crowns_header + "\n0,0,5,-3,3\n", "error"),
            ("header only", crowns_header + "\n", "error"),
            ("a field of a password-hash line (the marker)",
             crowns_header + f"\n0,root:$6${MARKER}$Zk3,5,3,3\n", "error"),
            ("a plain word for a number", crowns_header + "\n0,four,5,3,3\n", "error"),
            ("an unknown column", crowns_header + ",species\n0,0,5,3,3,oak\n", "error"),
            ("inf height", crowns_header + "\n0,0,5,3,inf\n", "error")]:
        t.run("crowns: " + description, ["check", t.config(
            "crowns.json", canopy={"crowns_file": t.write("crowns.csv", text)})], expect=expect)
    # Stands.
    square = [[[7.99, 45.99], [8.01, 45.99], [8.01, 46.01], [7.99, 46.01], [7.99, 45.99]]]
    for description, document in [
            ("empty collection", {"type": "FeatureCollection", "features": []}),
            ("a point, not a polygon", {"type": "FeatureCollection", "features": [{
                "type": "Feature", "properties": {"pai": 1},
                "geometry": {"type": "Point", "coordinates": [8, 46]}}]}),
            ("a self-intersecting (bow-tie) polygon", {"type": "FeatureCollection", "features": [{
                "type": "Feature", "properties": {"pai": 1}, "geometry": {
                    "type": "Polygon", "coordinates": [[[7.99, 45.99], [8.01, 46.01],
                                                        [8.01, 45.99], [7.99, 46.01],
                                                        [7.99, 45.99]]]}}]}),
            ("a property that is no canopy key", {"type": "FeatureCollection", "features": [{
                "type": "Feature", "properties": {"species": "oak"},
                "geometry": {"type": "Polygon", "coordinates": square}}]}),
            ("pai a string", {"type": "FeatureCollection", "features": [{
                "type": "Feature", "properties": {"pai": "much"},
                "geometry": {"type": "Polygon", "coordinates": square}}]}),
            ("NaN coordinates", {"type": "FeatureCollection", "features": [{
                "type": "Feature", "properties": {"pai": 1},
                "geometry": {"type": "Polygon", "coordinates": [[[float("nan"), 46]] * 4]}}]})]:
        text = json.dumps(document)
        # A ring that crosses itself is read by the even-odd rule (the bow-tie's two triangles).
        expect = "ok" if "bow-tie" in description else "error"
        t.run("stands: " + description, ["check", t.config(
            "stands.json", canopy={"stands": t.write("stands.geojson", text)})], expect=expect)
    t.run("stands: a text file (the marker)", ["check", t.config(
        "stands.json", canopy={"stands": t.write("stands.txt", MARKER + "\n")})])
    # A FIFO nobody writes, for every file a configuration names: refused, not waited for.
    fifo = t.path("fifo")
    os.mkfifo(fifo)
    for description, changes in [
            ("DEM", {"terrain": {"dem": str(fifo)}}),
            ("ephemeris", {"track": {"type": "ephemeris", "ephemeris": str(fifo)}}),
            ("crowns file", {"canopy": {"crowns_file": str(fifo)}}),
            ("stands file", {"canopy": {"stands": str(fifo)}}),
            ("granule", {"track": {"type": "granule", "file": str(fifo)}})]:
        t.run(f"{description}: a FIFO nobody writes", ["check", t.config("fifo.json", **changes)])
    fifo.unlink()
    # A granule that is not HDF5.
    t.run("granule: a text file (the marker)", ["check", t.config(
        "granule.json", track={"type": "granule", "file": t.write("g.h5", MARKER + "\n")})])


def granule_cases(t):
    """Issue 28's granules (tests/fuzz/corpus/granule, made by tests/fuzz/make_corpus.py): each
    is refused naming its path, or (a fill latitude) read with a warning."""
    corpus = pathlib.Path(__file__).resolve().parents[1] / "fuzz" / "corpus" / "granule"
    for name, expect in [("broken-gedi-huge-number.h5", "error"),  # uint64 above 2^63
                         ("broken-gedi-float-number.h5", "error"),  # not truncated
                         ("broken-glah14-overflow.h5", "error"),  # i_rec_ndx * 40
                         ("broken-glah14-count.h5", "error"),  # i_shot_count outside 1..40
                         ("broken-gedi-truncated.h5", "error"),
                         ("broken-glah14-truncated.h5", "error"),
                         ("broken-declared-1e11.h5", "error"),  # at once, with its path
                         ("broken-gedi-fill.h5", "ok")]:  # a warning names the skipped shots
        t.run("granule: " + name, ["check", t.config("granule.json", track={
            "type": "granule", "file": str(corpus / name)})], expect=expect)
    t.run("granule: beams named twice", ["check", t.config("granule.json", track={
        "type": "granule", "file": str(corpus / "gedi.h5"),
        "beams": ["BEAM0101", "BEAM0101"]})])
    import h5py  # python3-h5py
    with h5py.File(t.path("declared-1e7.h5"), "w") as f:
        f["BEAM0000/shot_number"] = [1]
        f.create_dataset("BEAM0000/lat_lowestmode", shape=(10**7,), dtype="f8", chunks=(1024,))
    t.run("granule: 10^7 shots declared", ["check", t.config("granule.json", track={
        "type": "granule", "file": str(t.path("declared-1e7.h5"))})])


def round_three_config(t):
    """Issue 28, the configuration's causes: each refused at its root, check and run alike."""
    out = str(t.path("out"))
    # One bounded-excerpt quoting rule.
    t.run("28. a 200 000-character key", ["check", t.config("bigkey.json", canopy={"k" * 200000: 1})])
    t.run("28. a 1 MB string (crown_shape)", ["check", t.config(
        "bigstr.json", canopy={"crown_shape": "s" * 1000000})])
    t.run("28. a 1 MB string as the DEM's path", ["check", t.config(
        "bigpath.json", terrain={"dem": "d" * 1000000})])
    t.run("28. a 100 KB --set value", ["check", t.config(), "--set",
                                       "canopy.crown_shape=" + "v" * 100000])
    # Stands: a zero-area polygon, a GeoJSON CRS GDAL does not know, a Shapefile's cut names.
    square = [[[7.99, 45.99], [8.01, 45.99], [8.01, 46.01], [7.99, 46.01], [7.99, 45.99]]]

    def stands(name, rings, **members):
        document = {"type": "FeatureCollection", **members, "features": [{
            "type": "Feature", "properties": {"pai": 1},
            "geometry": {"type": "Polygon", "coordinates": rings}}]}
        return t.write(name, json.dumps(document))

    line = stands("line.geojson", [[[7.99, 45.99], [8.0, 46.0], [8.01, 46.01], [7.99, 45.99]]])
    t.run("28. a stand of zero area", ["check", t.config("zero.json", canopy={"stands": line})],
          expect=3)
    unknown = stands("crs.geojson", square,
                     crs={"type": "name", "properties": {"name": "EPSG:999999"}})
    t.run("28. a GeoJSON crs GDAL does not know (EPSG:999999)", ["check", t.config(
        "crs.json", canopy={"stands": unknown})], expect=3)
    from osgeo import ogr, osr
    shapefile = str(t.path("shp/stands.shp"))
    t.path("shp").mkdir(exist_ok=True)
    dataset = ogr.GetDriverByName("ESRI Shapefile").CreateDataSource(shapefile)
    wgs84 = osr.SpatialReference()
    wgs84.ImportFromEPSG(4326)
    layer = dataset.CreateLayer("stands", wgs84, ogr.wkbPolygon)
    layer.CreateField(ogr.FieldDefn("leaf_reflectance", ogr.OFTReal))  # cut to leaf_refle
    feature = ogr.Feature(layer.GetLayerDefn())
    feature.SetField(0, 0.3)
    feature.SetGeometry(ogr.CreateGeometryFromJson(json.dumps(
        {"type": "Polygon", "coordinates": square})))
    layer.CreateFeature(feature)
    dataset = None
    t.run("28. a Shapefile stand with leaf_reflectance (cut to leaf_refle)", ["check", t.config(
        "shp.json", canopy={"stands": shapefile})], expect=3, says="a Shapefile cuts field names")
    # Crowns 900 km from the track: a warning, and the run goes on.
    far = t.write("far.csv", "lon,lat,base_m,radius_m,half_height_m\n8,54.1,5,3,3\n")
    t.run("28. crowns 900 km from the track (a warning)", ["run", t.config(
        "far.json", canopy={"crowns_file": far}), "--quiet", "--out", out], expect="ok", out=out,
        says="warning: /canopy/crowns_file")
    # Times outside the years a track may have.
    t.run("28. track.start_time 2999-01-01", ["check", t.config(
        "t.json", track__start_time="2999-01-01T00:00:00Z")], expect=2)
    t.run("28. track.rate_hz 1e-300 (shots 1e300 s apart)", ["check", t.config(
        "rate.json", track__rate_hz=1e-300)], expect=2)
    x, y, z = ecef(46.0, 8.0, 600000.0)
    for text in ("1e300", "-1e300"):
        ephemeris = t.write("eph.csv", f"time,x_m,y_m,z_m\n{text},{x},{y},{z}\n")
        t.run(f"28. an ephemeris time of {text} s", ["check", t.config(
            "eph.json", track={"type": "ephemeris", "ephemeris": ephemeris})], expect=3)


def round_three_inputs(t):
    """Issue 28's other causes, one case (or more) each: 1 threads, 2 a journal's frames twice,
    3 hangs, 4 silent reinterpretation, 5 check accepting what run fails on, 6 unclear messages,
    7 two runs on one --out, 8 plots, 9 brf's orders."""
    from osgeo import gdal
    gdal.UseExceptions()
    out = str(t.path("out"))
    python_dir = pathlib.Path(t.glaswave).resolve().parents[1] / "python"

    # 1. Two Python threads calling glaswave.run at once, 20 rounds (tests/python: 100).
    script = t.write("threads.py", f"""
import json, sys, threading
sys.path.insert(0, {str(python_dir)!r})
import glaswave
config = json.load(open({t.config("threads.json", track__shots=1,
                                  simulation__rays_per_shot=20)!r}))
reference = glaswave.run(config, threads=1)["rx_waveform"].values
failures = []
def runs():
    for _ in range(20):
        if (glaswave.run(config, threads=1)["rx_waveform"].values != reference).any():
            failures.append("other products")
threads = [threading.Thread(target=runs) for _ in range(2)]
[thread.start() for thread in threads]
[thread.join() for thread in threads]
sys.exit(f"glaswave: error: {{failures[0]}}" if failures else 0)
""")
    t.run("28/1. two Python threads run glaswave.run together, 20 rounds", [], expect="ok",
          command=["/usr/bin/python3", script])

    # 2 and 3. A killed run's journal: a frame written twice; a FIFO in its place.
    long = t.config("long.json", track__shots=20000, simulation__rays_per_shot=500)

    def killed_run():
        shutil.rmtree(out, ignore_errors=True)
        process = subprocess.Popen([t.glaswave, "run", long, "--quiet", "--threads", "1",
                                    "--out", out], stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL)
        journal = pathlib.Path(out) / "glaswave.journal"
        deadline = time.monotonic() + WALL_LIMIT_S
        while time.monotonic() < deadline and process.poll() is None and len(
                journal_frames(journal)) < 3:
            time.sleep(0.05)
        process.send_signal(signal.SIGKILL)
        process.wait()
        return journal

    journal = killed_run()
    frames = journal_frames(journal)
    data = journal.read_bytes() if journal.exists() else b""
    if len(frames) >= 2:
        first, second = frames[0], frames[1]
        journal.write_bytes(data[:second[1]] + data[first[0]:first[1]] + data[second[0]:])
    t.run("28/2. a journal whose first frame appears twice (valid checksums)", [
        "run", long, "--quiet", "--threads", "1", "--out", out, "--resume"],
        says="frames repeated, missing or out of order")
    journal = killed_run()
    journal.parent.mkdir(parents=True, exist_ok=True)
    if journal.exists():
        journal.unlink()
    os.mkfifo(journal)
    t.run("28/3. the journal replaced by a FIFO", [
        "run", long, "--quiet", "--out", out, "--resume"])
    fifo = t.path("source.fifo")
    if fifo.exists():
        fifo.unlink()
    os.mkfifo(fifo)
    vrt = t.write("fifo.vrt", f"""<VRTDataset rasterXSize="10" rasterYSize="10">
  <SRS>EPSG:4326</SRS><GeoTransform>7.99, 0.002, 0, 46.01, 0, -0.002</GeoTransform>
  <VRTRasterBand dataType="Float32" band="1"><SimpleSource>
    <SourceFilename relativeToVRT="0">{fifo}</SourceFilename><SourceBand>1</SourceBand>
  </SimpleSource></VRTRasterBand></VRTDataset>""")

    def dem_config(path, **terrain):
        return t.config("dem.json", terrain={"dem": path, **terrain})

    t.run("28/3. a VRT DEM whose source is a FIFO", ["check", dem_config(vrt)])
    t.run('28/3. "dem": "/vsistdin/"', ["check", dem_config("/vsistdin/")])
    t.run("28/3. canopy.crown_radius_m 1e6", ["check", t.config(
        canopy={"crown_radius_m": 1e6})], expect=2)

    # 4. Silent truncation and reinterpretation.
    def dem(name, dtype=gdal.GDT_Float32, crs="EPSG:4326", unit=None, scale=None,
            palette=False, value=500.0):
        path = str(t.path(name))
        dataset = gdal.GetDriverByName("GTiff").Create(path, 60, 60, 1, dtype)
        dataset.SetGeoTransform([7.97, 0.001, 0, 46.03, 0, -0.001])
        srs = osr.SpatialReference()
        srs.SetFromUserInput(crs)
        dataset.SetSpatialRef(srs)
        band = dataset.GetRasterBand(1)
        band.Fill(value)
        if unit:
            band.SetUnitType(unit)
        if scale:
            band.SetScale(scale)
        if palette:
            table = gdal.ColorTable()
            table.SetColorEntry(0, (0, 0, 0, 255))
            band.SetColorTable(table)
            band.SetColorInterpretation(gdal.GCI_PaletteIndex)
        dataset = None
        return path

    good = dem("good.tif")
    t.run("28/4. a NUL inside the DEM's path", ["check", dem_config(good + "\0.ignored")],
          expect=2, says="NUL byte")
    t.run("28/4. a DEM band whose unit is cm", ["check", dem_config(dem("cm.tif", unit="cm",
                                                                        value=50000.0))],
          expect="ok")
    t.run("28/4. a DEM band whose unit is furlong", ["check", dem_config(
        dem("furlong.tif", unit="furlong"))], expect=3, says="furlong")
    t.run("28/4. terrain.vertical_datum ellipsoid, the DEM's own EGM96", ["check", dem_config(
        dem("egm.tif", crs="EPSG:4326+5773"), vertical_datum="ellipsoid")], expect=2)
    t.run("28/4. a complex DEM band", ["check", dem_config(dem("complex.tif", gdal.GDT_CFloat32))],
          expect=3)
    t.run("28/4. a paletted DEM band", ["check", dem_config(dem("palette.tif", gdal.GDT_Byte,
                                                                palette=True, value=0))],
          expect=3)
    points = [{"lat_deg": 46.0, "lon_deg": 8.0}]
    t.run("28/4. track.points with a pass", ["check", t.config(track__points=points)], expect=2,
          says="/track/points")
    t.run("28/4. start_lat_deg with an orbit", ["check", t.config(track__type="orbit")], expect=2,
          says="/track/start_lat_deg")
    t.run("28/4. start_lat_deg with a granule", ["check", t.config(
        track__type="granule", track__file=good)], expect=2, says="/track/start_lat_deg")
    band = {"wavelength_nm": 1064, "pulse_energy_mJ": 70, "atmos_transmission_roundtrip": 0.9}
    t.run("28/4. two bands with one wavelength", ["check", t.config(sensor={"bands": [
        dict(band, name="a"), dict(band, name="b")]})], expect=2, says="wavelength_nm")

    # 5. check accepted and run failed after simulating, with a NetCDF variable's name.
    for description, changes in [
            ("sensor.telescope_area_m2 1e308", {"sensor__telescope_area_m2": 1e308}),
            ("sensor.bands[0].pulse_energy_mJ 1e308", {"sensor": {"preset": "glas", "bands": [
                dict(band, name="1064", pulse_energy_mJ=1e308)]}}),
            ("sensor.pulse_sigma_ns 1e-300", {"sensor__pulse_sigma_ns": 1e-300}),
            ("detector.gain 1e300", {"detector": {"enabled": True, "gain": 1e300}}),
            ("detector.noise_rms_W 1e300", {"detector": {"enabled": True, "noise_rms_W": 1e300}})]:
        t.run(f"28/5. {description} (run)", ["run", t.config("bound.json", **changes), "--quiet",
                                             "--out", out], out=out, expect=2)

    # 6. Unclear messages.
    t.run("28/6. seed 2^64 in the configuration", ["check", t.write(
        "seed.json", json.dumps(t.base()).replace('"seed": 1', '"seed": 18446744073709551616'))],
        expect=2, says="too large")
    t.run("28/6. --set seed=2^64", ["check", t.config(), "--set", "seed=18446744073709551616"],
          expect=2, says="too large")
    t.run("28/6. /proc/self/mem as the DEM", ["check", dem_config("/proc/self/mem")], expect=3)
    big = str(t.path("big.tif"))
    dataset = gdal.GetDriverByName("GTiff").Create(big, 200, 200, 1, gdal.GDT_Float32,
                                                   options=["BIGTIFF=YES"])
    dataset.SetGeoTransform([7.9, 0.001, 0, 46.1, 0, -0.001])
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(4326)
    dataset.SetSpatialRef(srs)
    dataset.GetRasterBand(1).Fill(900.0)
    dataset = None
    cut = t.write("cut.tif", pathlib.Path(big).read_bytes()[:360], mode="wb")
    t.run("28/6. a BigTIFF DEM cut at 360 bytes", ["check", dem_config(cut)], expect=3,
          says="truncated or corrupt")
    t.run("28/6. a DEM scale of 1e308", ["check", dem_config(dem("scale.tif", scale=1e308))],
          expect=3)
    t.run("28/6. GPKG footprints with bands x and X", ["check", t.config(
        sensor={"bands": [dict(band, name="x"), dict(band, name="X", wavelength_nm=532)]},
        output={"footprints_format": "GPKG"})], expect=2, says="differ only in case")
    script = t.write("shots.py", f"""
import sys
sys.path.insert(0, {str(python_dir)!r})
import glaswave
try:
    glaswave.run({t.config("py.json")!r}, shots=(0, 2**64))
except ValueError as error:
    sys.exit(f"glaswave: error: {{error}}")
""")
    t.run("28/6. Python shots=(0, 2**64)", [], command=["/usr/bin/python3", script],
          says="too large")

    # 7. Two runs on one --out, started together.
    shutil.rmtree(out, ignore_errors=True)
    first = subprocess.Popen([t.glaswave, "run", long, "--quiet", "--threads", "1", "--out", out],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    lock = pathlib.Path(out) / ".glaswave.lock"
    deadline = time.monotonic() + WALL_LIMIT_S
    while time.monotonic() < deadline and not (lock.exists() and lock.read_text().strip()):
        time.sleep(0.01)
    t.run("28/7. a second run on the --out of a running one", [
        "run", long, "--quiet", "--threads", "1", "--out", out], expect=2,
        says="another glaswave run is writing into this output directory")
    first.kill()
    first.wait()

    # 8. Plot text from the user's data: mathtext and 5,000 characters in band names.
    for description, name in [("$\\frac{1}{$", "$\\frac{1}{$"), ("of 5,000 characters", "b" * 5000)]:
        t.run(f"28/8. plots with a band named {description}", ["run", t.config(
            "plot.json", sensor={"preset": "glas", "bands": [dict(band, name=name)]},
            output={"plots": True}), "--quiet", "--out", out], expect="ok", out=out)
        row = list(t.rows[-1])
        if "warning" in row[3]:
            row[4] = "PLOT FAILED: " + row[3]
        t.rows[-1] = tuple(row)

    # 9. brf over a conservative scene: albedo 1 (0.709 when cut at 8 orders).
    done = t.run("28/9. brf over leaves and soil that absorb nothing", ["brf", t.config(
        "white.json", canopy={"crown_shape": "layer", "pai": 5, "leaf_reflectance": 0.6,
                              "leaf_transmittance": 0.4, "crown_base_m": [0, 0],
                              "crown_half_height_m": 5, "green_fraction": 1.0,
                              "bark_fraction": 0.0, "dbh_m": 0.0},
        terrain={"plane": {"origin_lat_deg": 46.0, "origin_lon_deg": 8.0},
                 "soil_reflectance": 1.0},
        brf={"photons": 4000, "scene_size_m": 40.0, "image_resolution_m": 4.0}),
        "--quiet", "--out", out], expect="ok", out=out)
    if done.returncode == 0:
        albedos = [b["albedo"] for b in json.loads(
            (pathlib.Path(out) / "brf.json").read_text())["bands"]]
        row = list(t.rows[-1])
        row[4] += "; albedo " + ", ".join(f"{a:.4f}" for a in albedos)
        if any(abs(a - 1.0) > 0.005 for a in albedos):
            row[4] = "ENERGY LOST; " + row[4]
        t.rows[-1] = tuple(row)


def write_las(path, points, scale=0.01, scan_deg=0):
    """A LAS 1.2 cloud of point format 0 (no CRS: give --crs), points (x, y, z, class), each a
    pulse's single return at the scan angle scan_deg."""
    import struct
    xs, ys, zs = ([p[i] for p in points] for i in range(3))
    header = struct.pack(
        "<4sHH16sBB32s32sHHHIIBHI5I12d", b"LASF", 0, 0, b"\0" * 16, 1, 2, b"inputs_tried",
        b"inputs_tried", 1, 2026, 227, 227, 0, 0, 20, len(points), len(points), 0, 0, 0, 0,
        scale, scale, scale, 0.0, 0.0, 0.0, max(xs), min(xs), max(ys), min(ys), max(zs), min(zs))
    assert len(header) == 227
    body = b"".join(struct.pack("<iiiHBBbBH", round(x / scale), round(y / scale),
                                round(z / scale), 0, 9, c, scan_deg, 0, 0)
                    for x, y, z, c in points)
    pathlib.Path(path).write_bytes(header + body)
    return str(path)


def round_four_inputs(t):
    """Issue 42's classes: meshes Assimp reads (indices, declared sizes, files it opens itself),
    voxel grids of other shapes and heights, voxelize's --out, grids as netCDF4-python writes
    them, sizes check accepts."""
    from osgeo import gdal
    import netCDF4
    import numpy
    gdal.UseExceptions()
    out = str(t.path("out"))
    # Facet models.
    trees = t.write("trees.csv", "x,y,model,rotation_deg,scale\n0,0,oak,0,1\n")

    def facets(model):
        return t.config("facets.json", canopy={"facets": {
            "trees_file": trees, "models": {"oak": model},
            "materials": {"DefaultMaterial": {"reflectance": 0.3}}}})

    def ply(count, faces):
        return ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                f"property float z\nelement face {count}\nproperty list uchar int vertex_indices\n"
                f"end_header\n0 0 0\n1 0 0\n0 1 0\n{faces}")

    for name, faces in [("vertex 10^8 of 3", "3 0 1 100000000\n"), ("vertex -5", "3 0 1 -5\n")]:
        model = t.write("bad.ply", ply(1, faces))
        t.run(f"42/1. a PLY face naming {name} (check)", ["check", facets(model)], expect=3,
              says="bad.ply")
        t.run(f"42/1. a PLY face naming {name} (run)", ["run", facets(model), "--quiet", "--out",
                                                        out], out=out, expect=3)
    # Round six: Assimp 5.2's triangulation aborted on a face of no corner (mesh_fuzzer).
    model = t.write("empty-face.ply", ply(2, "3 0 1 2\n0\n"))
    t.run("42/1. a PLY face naming no vertex (check)", ["check", facets(model)], expect=3,
          says="names no vertex")
    t.run("42/1. a PLY face naming no vertex (run)", ["run", facets(model), "--quiet", "--out", out],
          out=out, expect=3, says="names no vertex")
    model = t.write("big.ply", ply(10**9, "3 0 1 2\n"))
    t.run(f"42/1. a {os.path.getsize(model)}-byte PLY declaring 10^9 faces", [
        "check", facets(model)], expect=3, says="declares 1000000000 face elements")
    fifo = t.path("model.fifo")
    if fifo.exists():
        fifo.unlink()
    os.mkfifo(fifo)
    model = t.write("plate.obj", f"mtllib {fifo.name}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    t.run("42/1. an OBJ whose mtllib is a FIFO", ["check", facets(model)], expect=3, says="FIFO")
    model = t.write("plate.gltf", json.dumps({
        "asset": {"version": "2.0"}, "buffers": [{"uri": fifo.name, "byteLength": 36}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0}))
    t.run("42/1. a glTF whose buffer's URI is a FIFO", ["check", facets(model)], expect=3,
          says="FIFO")
    model = t.write("deep.gltf", '{"asset": {"version": "2.0"}, "extras": ' + "[" * 200000 +
                    "]" * 200000 + "}")
    t.run("42/1. a glTF of 200 000 nested arrays", ["check", facets(model)], expect=3,
          says="nests its JSON deeper than 256")

    # Voxel grids, written as netCDF4-python writes them: under the track (UTM 32N).
    utm = osr.SpatialReference()
    utm.ImportFromEPSG(32632)
    wkt = utm.ExportToWkt(["FORMAT=WKT2_2019"])  # its AREA says "6°E": an NC_STRING
    to_utm = osr.CoordinateTransformation(GEODETIC, utm)
    x_c, y_c, _ = to_utm.TransformPoint(46.0, 8.0, 0.0)

    def grid(name, order=("z", "y", "x"), bounds_rows=None, x_2d=False, write_pad=True,
             z=(1.0, 3.0, 5.0), packed=False):
        path = str(t.path(name))
        with netCDF4.Dataset(path, "w") as nc:
            sizes = {"z": 3, "y": 40, "x": 40}
            for d, n in sizes.items():
                nc.createDimension(d, n)
            nc.createDimension("nv", 2)
            x = nc.createVariable("x", "f8", ("y", "x") if x_2d else ("x",))
            y = nc.createVariable("y", "f8", ("y",))
            zv = nc.createVariable("z", "f8", ("z",))
            xs = x_c - 40 + 2 * numpy.arange(40) + 1
            x[:] = numpy.tile(xs, (40, 1)) if x_2d else xs
            y[:] = y_c - 40 + 2 * numpy.arange(40) + 1
            zv[:] = z
            if bounds_rows:
                nc.createDimension("zb", bounds_rows)
                zv.bounds = "z_bounds"
                zb = nc.createVariable("z_bounds", "f8", ("zb", "nv"))
                zb[:] = [[2 * k, 2 * k + 2] for k in range(bounds_rows)]
            crs = nc.createVariable("crs", "i4")
            crs.crs_wkt = wkt
            pad = nc.createVariable("pad", "i2" if packed else "f4", order,
                                    fill_value=-1 if packed else None)
            pad.grid_mapping = "crs"
            if packed:
                pad.scale_factor, pad.add_offset = 0.001, 0.0
            if write_pad:
                pad[:] = numpy.full([sizes[d] for d in order], 0.2)
            else:
                pad[0] = numpy.full((40, 40), 0.2)
        return path

    def voxels(path):
        return t.config("voxels.json", canopy={"voxels": {"file": path}})

    t.run("42/3. a grid by netCDF4-python, its crs_wkt an NC_STRING (holding °)", [
        "check", voxels(grid("string.nc"))], expect="ok")
    t.run("42/3. a grid by netCDF4-python, packed (short, scale_factor 0.001)", [
        "run", voxels(grid("packed.nc", packed=True)), "--quiet", "--out", out], out=out,
        expect="ok")
    t.run("42/1. z bounds of 5 rows over a z of 3", ["check", voxels(grid(
        "rows.nc", bounds_rows=5))], expect=3, says="z bounds are not (z, 2)")
    t.run("42/1. x a 2-D variable x(y, x)", ["check", voxels(grid("x2d.nc", x_2d=True))],
          expect=3, says="not one-dimensional")
    high = voxels(grid("high.nc", z=(1e307, 5e307, 1.7e308)))
    t.run("42/1. z centres near 1e308 (check)", ["check", high], expect=3, says="within 10000 m")
    t.run("42/1. z centres near 1e308 (run)", ["run", high, "--quiet", "--out", out], out=out,
          expect=3, says="within 10000 m")
    t.run("42/3. pad(x, y, z)", ["check", voxels(grid("xyz.nc", order=("x", "y", "z")))],
          expect=3, says="ordered (z, y, x)")
    t.run("42/3. pad written in its first layer only (NetCDF's fill in the others)", [
        "run", voxels(grid("unwritten.nc", write_pad=False)), "--quiet", "--out", out],
        out=out, expect=3, says="missing")
    # voxel_fuzzer's findings (tests/fuzz/corpus/voxel: the first byte picks the format, the
    # rest is the file): HDF5 crashed on the NetCDF-4 one, nc_open asked for 9 GB on the other.
    corpus = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fuzz", "corpus",
                          "voxel")
    for name, says in (("regression-netcdf4-hdf5-global-heap", "HDF5 failed reading"),
                       ("regression-netcdf3-declares-9-gb", "declares 1128547850 dimensions")):
        path = str(t.path(name + ".nc"))
        with open(os.path.join(corpus, name), "rb") as found, open(path, "wb") as grid_file:
            grid_file.write(found.read()[1:])
        t.run(f"42/fuzz. the voxel grid {name}", ["check", voxels(path)], expect=3, says=says)
    for top in ("ten", "10 ft", "1e400"):
        path = str(t.path("top.tif"))
        dataset = gdal.GetDriverByName("GTiff").Create(path, 40, 40, 1, gdal.GDT_Float32)
        dataset.SetGeoTransform([x_c - 40, 2, 0, y_c + 40, 0, -2])
        dataset.SetSpatialRef(utm)
        band = dataset.GetRasterBand(1)
        band.SetMetadataItem("z_bottom_m", "0")
        band.SetMetadataItem("z_top_m", top)
        band.Fill(0.2)
        dataset = None
        t.run(f"42/3. a GeoTIFF band's z_top_m {top!r}", ["check", voxels(path)], expect=3,
              says="not a number of metres")

    # voxelize --out.
    points = [(500000.0 + 0.5 * i, 4000000.0 + 0.5 * j, 100.0 + (9.0 if (i + j) % 2 else 0.0),
               5 if (i + j) % 2 else 2) for i in range(20) for j in range(20)]
    cloud = write_las(t.path("plot.las"), points)
    grid_out = t.path("grid.nc")
    if grid_out.exists():
        grid_out.unlink()
    voxelize = ["voxelize", cloud, "--crs", "EPSG:32633", "--voxel-size-m", "2", "--out"]
    t.run("42/2. voxelize into a new file", voxelize + [str(grid_out)], expect="ok")
    t.run("42/2. voxelize onto an existing file", voxelize + [str(grid_out)], expect=2,
          says="--force")
    t.run("42/2. voxelize onto an existing file, --force", voxelize + [str(grid_out), "--force"],
          expect="ok")
    t.run("42/2. voxelize --out the cloud itself, --force", voxelize + [cloud, "--force"],
          expect=2, says="the point cloud itself")
    t.run("42/2. voxelize into a missing folder", voxelize + [str(t.path("none/grid.nc"))],
          expect=2, says="does not exist")
    t.run("42/2. voxelize onto a directory", voxelize + [str(t.dir)], expect=2,
          says="is a directory")
    t.run("42/2. voxelize onto /dev/null, --force", voxelize + ["/dev/null", "--force"], expect=2,
          says="not a regular file")

    # One class-2 point 800 m (1.45 km) from an 80 m plot.
    plot = [(500000.5 + i, 4000000.5 + j, 100.0 + (10.0 if (i + j) % 2 else 0.0),
             5 if (i + j) % 2 else 2) for i in range(80) for j in range(80)]
    for far in (800, 1450):
        stray = write_las(t.path("stray.las"), plot + [(500000.0 + far, 4000040.0, 100.0, 2)])
        t.run(f"42/4. voxelize a plot with one ground point {far} m away", [
            "voxelize", stray, "--crs", "EPSG:32633", "--out", str(t.path("stray.nc")),
            "--force"], expect=3, says="separate patches")
        t.run(f"42/4. a point cloud run, one ground point {far} m away", ["check", t.config(
            "stray.json", terrain={"point_cloud": True},
            canopy={"point_cloud": {"file": stray, "crs": "EPSG:32633"}})], expect=3,
            says="separate patches")

    # Sizes check accepted and run then spent minutes on.
    t.run("42/4. background rate_MHz 1e6 (run)", ["run", t.config(
        "background.json", sensor={"preset": "atlas"},
        simulation={"rays_per_shot": 20, "background": {"rate_MHz": 1e6}}), "--quiet", "--out",
        out], out=out, expect=2, says="/simulation/background/rate_MHz")
    t.run("42/4. the sun through a filter of 10^4 nm", ["check", t.config(
        "sun.json", sensor={"preset": "atlas", "filter_bandwidth_nm": 1e4})], expect=2,
        says="/sensor/filter_bandwidth_nm")
    done = t.run("42/4. a pass of 10^9 shots (check)", ["check", t.config(
        "many.json", track__shots=10**9)], expect="ok")
    if b"1000000 of them located" not in done.stdout:
        row = list(t.rows[-1])
        row[4] = "DOES NOT SAY it located a sample"
        t.rows[-1] = tuple(row)
    plate = t.write("plate.obj", "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nf 1 2 3\n")
    materials = {f"m{i}": {"reflectance": 0.3} for i in range(65536)}
    materials["DefaultMaterial"] = {"reflectance": 0.3}
    t.run("42/4. 65,537 facet materials (check)", ["check", t.config("materials.json", canopy={
        "facets": {"trees_file": trees, "models": {"oak": plate}, "materials": materials}})],
        expect="ok")
    row = list(t.rows[-1])
    if row[5] > 5.0:
        row[4] = f"SLOW ({row[5]:.1f} s)"
    t.rows[-1] = tuple(row)


def journal_frames(journal):
    """The (start, end) byte offsets of a run journal's whole frames (pipeline/engine/journal.cpp:
    a header of three 64-bit words, the third the length of the input files' stamps after it, then
    frames of six 64-bit words, the payload and a checksum)."""
    import struct
    try:
        data = journal.read_bytes()
    except OSError:
        return []
    if len(data) < 24:
        return []
    frames, at = [], 24 + struct.unpack_from("<3Q", data)[2]
    while at + 48 <= len(data):
        words = struct.unpack_from("<6Q", data, at)
        end = at + 48 + words[4] + 8
        if end > len(data):
            break
        frames.append((at, end))
        at = end
    return frames


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    source = pathlib.Path(__file__).resolve().parents[2]
    parser.add_argument("--glaswave", default=str(source / "build" / "pipeline" / "glaswave"))
    parser.add_argument("--out", default="inputs_tried.md")
    parser.add_argument("--only", default="", help="only the groups whose name holds this")
    arguments = parser.parse_args()
    glaswave = os.path.abspath(arguments.glaswave)
    with tempfile.TemporaryDirectory(prefix="glaswave_inputs_") as scratch:
        t = Trial(glaswave, scratch)
        from inputs_round_five import round_five_inputs  # beside this file
        for group in (issue_items, configuration_cases, data_cases, granule_cases,
                      round_three_config, round_three_inputs, round_four_inputs,
                      round_five_inputs):
            if arguments.only in group.__name__:
                group(t)
        pathlib.Path(arguments.out).write_text(t.table())
    bugs = [r for r in t.rows if is_bug(r[4])]
    for n, description, status, first, verdict, *_ in bugs:  # in full, for ctest's log
        print(f"wanting: {n}. {description}: exit {status}, {verdict}; {first[:200]}")
    print(f"{len(t.rows)} inputs, {len(bugs)} found wanting: {arguments.out}")
    return 1 if bugs else 0


if __name__ == "__main__":
    sys.exit(main())
