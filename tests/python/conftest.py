"""What the Python module's tests share: a small configuration, the built glaswave command, and
a comparison of two Datasets bit for bit."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest
import xarray as xr

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]

# Attributes that say when and how a run was made, not what it computed.
VOLATILE_ATTRIBUTES = {"history", "date_created"}


def volatile(name):
    return name in VOLATILE_ATTRIBUTES or name.startswith("stats_")


def small_config(shots=3, rays=400, canopy=None):
    """A short pass over a bare sloped plane (or a forest on it): quick to simulate."""
    return {
        "seed": 3,
        "sensor": {"preset": "glas"},
        "simulation": {"rays_per_shot": rays, "max_order": 3},
        "terrain": {
            "plane": {"origin_lat_deg": 46.0, "origin_lon_deg": 8.0, "elevation_m": 900.0,
                      "slope_deg": 8.0, "aspect_deg": 200.0},
            "soil_reflectance": 0.15,
        },
        "canopy": canopy,
        "track": {"type": "pass", "start_lat_deg": 46.0, "start_lon_deg": 8.0,
                  "heading_deg": 350.0, "shots": shots, "spacing_m": 172.0},
    }


@pytest.fixture
def write_config(tmp_path):
    def write(document, name="track.json"):
        path = tmp_path / name
        path.write_text(json.dumps(document, indent=2))
        return path
    return write


def glaswave_binary():
    binary = os.environ.get("GLASWAVE_BINARY")
    return binary if binary else str(SOURCE_DIR / "build" / "pipeline" / "glaswave")


def run_command(config_path, out_dir, *arguments):
    """`glaswave run` as a user runs it; shots.nc read as xarray reads it by default."""
    subprocess.run([glaswave_binary(), "run", str(config_path), "--out", str(out_dir), "--quiet",
                    *arguments], check=True, capture_output=True)
    return xr.load_dataset(pathlib.Path(out_dir) / "shots.nc")


def assert_values_identical(name, a, b):
    assert a.dtype == b.dtype, name
    assert a.shape == b.shape, name
    if a.dtype.kind == "O":
        assert np.array_equal(a, b), name
    else:
        # Bit for bit: NaN where NaN, and the same NaN.
        assert np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"), name
        assert np.ascontiguousarray(a).tobytes() == np.ascontiguousarray(b).tobytes(), name


def assert_attributes_identical(where, a, b, skip_volatile=False):
    keys_a = {k for k in a if not (skip_volatile and volatile(k))}
    keys_b = {k for k in b if not (skip_volatile and volatile(k))}
    assert keys_a == keys_b, where
    for key in keys_a:
        x, y = a[key], b[key]
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            assert np.array_equal(np.asarray(x), np.asarray(y)), f"{where}: {key}"
        else:
            assert x == y, f"{where}: {key}"


def assert_datasets_identical(a, b, global_attributes=True):
    """Every variable (coordinates included) with its dimensions, attributes and values, the
    dimensions, and the global attributes but those of when and how the run was made."""
    assert dict(a.dims) == dict(b.dims)
    assert set(a.variables) == set(b.variables)
    assert set(a.coords) == set(b.coords)
    for name in a.variables:
        va, vb = a.variables[name], b.variables[name]
        assert va.dims == vb.dims, name
        assert_attributes_identical(name, va.attrs, vb.attrs)
        assert_values_identical(name, va.values, vb.values)
    if global_attributes:
        assert_attributes_identical("global", a.attrs, b.attrs, skip_volatile=True)
