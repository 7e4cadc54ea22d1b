#!/usr/bin/python3
"""Run time of a short run against the number and size of stand polygons (issue 13, item 2).

Usage: tests/benchmarks/stands_scaling.py GLASWAVE [WORKDIR] [TIMEOUT_S]
Writes stands files (none, 16, 1000 and 3000 squares of about 100 m over the track, one
polygon of 10^6 vertices), runs 5 shots of 2000 rays over a plane for each, and prints the wall
time of each run and its ratio to the run without stands.

       tests/benchmarks/stands_scaling.py --per-shot GLASWAVE [WORKDIR] [SHOTS]
The cost of a shot (issue 23, item 8): a track of SHOTS (default 200) shots of 1000 rays, 10 m
apart, inside 3000 squares of alternating PAI 2 and 4 (one leaf angle distribution), against
the same track without stands. Each case runs SHOTS shots and one shot, interleaved, three
rounds; a shot's cost is the difference over SHOTS - 1 (the start, reading the stands, cancels),
the fastest round kept. Prints both costs and their ratio.
"""
import json
import math
import os
import subprocess
import sys
import time

LAT0, LON0 = 34.30, -118.20


def squares(count):
    """`count` squares of 0.0009 deg in a grid of 0.001 deg centred on the track's start."""
    side = int(math.ceil(math.sqrt(count)))
    features = []
    for k in range(count):
        lon = LON0 - 0.0005 * side + 0.001 * (k % side)
        lat = LAT0 - 0.0005 * side + 0.001 * (k // side)
        ring = [[lon, lat], [lon + 0.0009, lat], [lon + 0.0009, lat + 0.0009],
                [lon, lat + 0.0009], [lon, lat]]
        features.append(feature(ring, {"pai": 1.0 + 0.001 * k}))
    return features


def circle(vertices):
    """One ragged circle of 2 km radius about the track, `vertices` vertices."""
    ring = []
    for k in range(vertices):
        t = 2.0 * math.pi * k / vertices
        r = 0.02 * (0.9 + 0.1 * math.sin(37.0 * t))
        ring.append([LON0 + r * math.cos(t) / math.cos(math.radians(LAT0)),
                     LAT0 + r * math.sin(t)])
    ring.append(ring[0])
    return [feature(ring, {"pai": 1.5})]


def feature(ring, properties):
    return {"type": "Feature", "properties": properties,
            "geometry": {"type": "Polygon", "coordinates": [ring]}}


def alternating(count):
    """`count` squares as squares() makes them, PAI 2 and 4 alternating."""
    features = squares(count)
    for k, f in enumerate(features):
        f["properties"] = {"pai": 2.0 if k % 2 else 4.0}
    return features


def per_shot(binary, work, shots):
    os.makedirs(work, exist_ok=True)
    stands = os.path.abspath(os.path.join(work, "alternating_3000.geojson"))
    with open(stands, "w") as f:
        json.dump({"type": "FeatureCollection", "features": alternating(3000)}, f)
    best = {}
    for round_ in range(3):
        for name, path in [("none", None), ("3000 stands", stands)]:
            seconds = []
            for n in (shots, 1):
                document = config(path)
                document["simulation"]["rays_per_shot"] = 1000
                document["track"].update({"shots": n, "spacing_m": 10.0})
                conf = os.path.join(work, "config.json")
                with open(conf, "w") as f:
                    json.dump(document, f)
                out = os.path.join(work, "out")
                subprocess.run(["rm", "-rf", out], check=True)
                start = time.monotonic()
                subprocess.run([binary, "run", conf, "--out", out, "--threads", "1", "--quiet"],
                               check=True, capture_output=True)
                seconds.append(time.monotonic() - start)
            cost = (seconds[0] - seconds[1]) / (shots - 1)
            best[name] = min(best.get(name, cost), cost)
    print(f"a shot's cost over {shots} shots of 1000 rays (fastest of 3 rounds): "
          f"none {best['none'] * 1e3:.1f} ms, 3000 stands {best['3000 stands'] * 1e3:.1f} ms, "
          f"ratio {best['3000 stands'] / best['none']:.2f}", flush=True)


def config(stands):
    canopy = {"pai": 3.0, "cover": 0.6, "crown_radius_m": 6.0, "crown_half_height_m": 7.0,
              "crown_base_m": [8.0, 14.0]}
    if stands:
        canopy["stands"] = stands
    return {
        "seed": 7,
        "simulation": {"rays_per_shot": 2000, "max_order": 3},
        "terrain": {"plane": {"origin_lat_deg": LAT0, "origin_lon_deg": LON0}},
        "canopy": canopy,
        "track": {"type": "pass", "start_lat_deg": LAT0, "start_lon_deg": LON0,
                  "heading_deg": 10.0, "shots": 5, "spacing_m": 40.0},
        "output": {"netcdf": True, "footprints": False, "plots": False},
    }


def main():
    if sys.argv[1] == "--per-shot":
        per_shot(os.path.abspath(sys.argv[2]), sys.argv[3] if len(sys.argv) > 3 else "stands_per_shot",
                 int(sys.argv[4]) if len(sys.argv) > 4 else 200)
        return
    binary = os.path.abspath(sys.argv[1])
    work = sys.argv[2] if len(sys.argv) > 2 else "stands_scaling"
    limit_s = float(sys.argv[3]) if len(sys.argv) > 3 else 3600.0
    os.makedirs(work, exist_ok=True)
    cases = [("none", None), ("16 squares", squares(16)), ("1000 squares", squares(1000)),
             ("3000 squares", squares(3000)), ("10^6 vertices", circle(1000000))]
    base = None
    for name, features in cases:
        stands = None
        if features is not None:
            stands = os.path.abspath(os.path.join(work, name.replace(" ", "_") + ".geojson"))
            with open(stands, "w") as f:
                json.dump({"type": "FeatureCollection", "features": features}, f)
        path = os.path.join(work, "config.json")
        with open(path, "w") as f:
            json.dump(config(stands), f)
        out = os.path.join(work, "out_" + name.replace(" ", "_").replace("^", ""))
        start = time.monotonic()
        try:
            run = subprocess.run([binary, "run", path, "--out", out, "--threads", "1", "--quiet"],
                                 capture_output=True, text=True, timeout=limit_s)
        except subprocess.TimeoutExpired:
            print(f"{name:>14}: not done after {limit_s:.0f} s", flush=True)
            continue
        seconds = time.monotonic() - start
        if run.returncode != 0:
            print(f"{name}: exit {run.returncode}: {run.stderr.strip()[-300:]}")
            continue
        base = base or seconds
        print(f"{name:>14}: {seconds:7.2f} s  ({seconds / base:5.2f} x none)", flush=True)


if __name__ == "__main__":
    main()
