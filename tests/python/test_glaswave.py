"""The Python module against the command line: glaswave.run returns the bits `glaswave run`
writes, check raises the command line's errors as Python exceptions, Ctrl-C stops a run."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import xarray as xr

import glaswave
from conftest import assert_datasets_identical, glaswave_binary, run_command, small_config


def test_run_returns_the_bits_of_the_command(write_config, tmp_path):
    path = write_config(small_config())
    from_command = run_command(path, tmp_path / "cli")
    from_python = glaswave.run(path)
    assert isinstance(from_python, xr.Dataset)
    assert from_python.sizes["shot"] == 3
    assert_datasets_identical(from_python, from_command)
    # A dict is the same configuration as the file that holds it.
    assert_datasets_identical(glaswave.run(small_config()), from_command)


def test_a_range_of_shots_is_the_matching_slice(write_config):
    path = write_config(small_config())
    whole = glaswave.run(path)
    part = glaswave.run(path, shots=range(1, 3))
    assert list(part["shot_number"].values) == [1, 2]
    assert_datasets_identical(part, whole.isel(shot=slice(1, 3)), global_attributes=False)
    assert_datasets_identical(glaswave.run(path, shots=(1, 3)), part)


def test_check_raises_config_error_naming_the_json_path():
    config = small_config()
    config["canopy"] = {"pai": -1}
    with pytest.raises(glaswave.ConfigError) as raised:
        glaswave.check(config)
    assert isinstance(raised.value, ValueError)
    assert str(raised.value) == "/canopy/pai: must be >= 0, got -1"
    assert raised.value.place == "/canopy/pai"
    # The same through an override, and the same from run.
    with pytest.raises(glaswave.ConfigError, match=r"^/canopy/pai: must be >= 0"):
        glaswave.check(small_config(canopy={}), overrides={"canopy.pai": -1})
    with pytest.raises(glaswave.ConfigError, match=r"^/canopy/pai: must be >= 0"):
        glaswave.run(config)
    with pytest.raises(glaswave.ConfigError, match=r"^/simulation/rays_per_shot"):
        glaswave.check(small_config(), overrides={"simulation.rays_per_shot": 0})
    with pytest.raises(glaswave.ConfigError, match=r"unknown key \"paj\"; did you mean \"pai\""):
        glaswave.check(small_config(canopy={"paj": 2.0}))
    summary = glaswave.check(small_config())
    assert summary["shots"] == 3 and summary["shots_off_terrain"] == 0


def nested(levels, leaf=1):
    """A list `levels` deep, built without recursion."""
    value = leaf
    for _ in range(levels):
        value = [value]
    return value


def test_a_deeply_nested_dict_is_a_config_error_naming_its_path_as_a_file_gives():
    # Deeper than Python's recursion limit (json.dumps would raise RecursionError) and just over
    # the engine's limit of 64 levels (which json.dumps would pass): the engine's message, at
    # the path's outermost levels, for run, check and brf alike.
    limit = glaswave._glaswave.max_json_depth
    for levels in (100_000, limit):
        config = small_config()
        config["canopy"] = {"pai": nested(levels)}
        for call in (glaswave.check, glaswave.run, glaswave.brf):
            with pytest.raises(glaswave.ConfigError) as raised:
                call(config)
            assert str(raised.value) == (
                "/canopy/pai/0/...: nests deeper than 64 levels of objects and arrays")
            assert raised.value.place == "/canopy/pai/0/..."
        # The engine checks the JSON text it is given too (what json.dumps still writes).
        if levels == limit:
            with pytest.raises(glaswave.ConfigError, match=r"^/canopy/pai/0/\.\.\.: nests"):
                glaswave._glaswave.check(None, json.dumps(config), ".", [])
    with pytest.raises(glaswave.ConfigError, match=r"^/seed: duplicate key"):
        glaswave._glaswave.check(None, '{"seed": 1, "seed": 2}', ".", [])
    # One level less is JSON the engine reads: the error is then the key's own.
    config = small_config()
    config["canopy"] = {"pai": nested(limit - 2)}
    with pytest.raises(glaswave.ConfigError, match=r"^/canopy/pai: must be a number"):
        glaswave.check(config)
    # Nested dicts, and an override's value (placed at its key, as --set places it).
    deep_dict = {}
    inner = deep_dict
    for _ in range(5000):
        inner["a"] = {}
        inner = inner["a"]
    with pytest.raises(glaswave.ConfigError, match=r"^/track/a/a/\.\.\.: nests deeper than 64"):
        glaswave.check({**small_config(), "track": deep_dict})
    with pytest.raises(glaswave.ConfigError, match=r"^/seed/0/0/0/\.\.\.: nests deeper than 64"):
        glaswave.check(small_config(), overrides={"seed": nested(100_000)})
    # A value that holds itself is named, not followed for ever.
    loop = []
    loop.append(loop)
    with pytest.raises(glaswave.ConfigError, match=r"^/canopy/pai/0: refers to itself"):
        glaswave.check({**small_config(), "canopy": {"pai": loop}})


def test_the_contracts_example_names_the_wrong_value_before_the_missing_terrain():
    # PRODUCT.md §6, as written there: no terrain, and a negative PAI.
    with pytest.raises(glaswave.ConfigError) as raised:
        glaswave.check({"canopy": {"pai": -1}})
    assert isinstance(raised.value, ValueError)
    assert str(raised.value) == "/canopy/pai: must be >= 0, got -1"
    assert raised.value.place == "/canopy/pai"
    with pytest.raises(glaswave.ConfigError) as raised:
        glaswave.check({"canopy": {"pai": 1}})
    assert str(raised.value) == '/terrain: is required: give "dem", "plane" or "point_cloud"'


def test_unusable_input_is_an_input_error_and_relative_paths_start_in_the_current_directory(
        tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    config = small_config()
    del config["terrain"]["plane"]
    config["terrain"]["dem"] = "missing.tif"
    with pytest.raises(glaswave.InputError) as raised:
        glaswave.check(config)
    assert isinstance(raised.value, ValueError)
    assert not isinstance(raised.value, glaswave.ConfigError)
    assert str(tmp_path / "missing.tif") in str(raised.value)


def test_overrides_apply_as_set_does(write_config, tmp_path):
    path = write_config(small_config())
    overridden = glaswave.run(path, overrides={"terrain.soil_reflectance": 0.3, "seed": 5})
    edited = small_config()
    edited["terrain"]["soil_reflectance"] = 0.3
    edited["seed"] = 5
    assert_datasets_identical(overridden, glaswave.run(edited))
    from_command = run_command(path, tmp_path / "cli", "--set", "terrain.soil_reflectance=0.3",
                               "--set", "seed=5")
    assert_datasets_identical(overridden, from_command)
    # Bare Lambertian ground returns in proportion to its reflectance, to round-off.
    base = glaswave.run(path, overrides={"seed": 5})
    ratio = overridden["rx_energy"].values / base["rx_energy"].values
    np.testing.assert_allclose(ratio, 2.0, rtol=1e-12)


def test_threads_do_not_change_the_bits():
    config = small_config(shots=6, rays=300, canopy={"pai": 3.0, "cover": 0.6})
    assert_datasets_identical(glaswave.run(config, threads=1), glaswave.run(config, threads=2))


def test_ctrl_c_stops_a_run_and_leaves_nothing_behind(tmp_path):
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    # Shots enough for minutes, each one quick, so that the engine looks at signals often.
    config = small_config(shots=1000000, rays=200)
    config["track"]["spacing_m"] = 1.0
    script = (
        "import sys, glaswave\n"
        f"config = {json.dumps(config)!r}\n"
        "print('started', flush=True)\n"
        "try:\n"
        "    import json; glaswave.run(json.loads(config), threads=1)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted', flush=True)\n"
        "    sys.exit(42)\n"
        "print('finished', flush=True)\n"
    )
    process = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True,
                               env=dict(os.environ, TMPDIR=str(scratch)))
    try:
        assert process.stdout.readline().strip() == "started"
        # Wait until the run is writing its products, then give it a second more.
        deadline = time.monotonic() + 30
        while not list(scratch.glob("glaswave-*/run/shots.nc.part")):
            assert time.monotonic() < deadline, "the run never started writing"
            assert process.poll() is None, process.stderr.read()
            time.sleep(0.05)
        time.sleep(1.0)
        sent = time.monotonic()
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=30)
        stopped_s = time.monotonic() - sent
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 42, err
    assert out.strip() == "interrupted"
    assert stopped_s < 5.0, stopped_s
    print(f"stopped {stopped_s:.3f} s after SIGINT")
    assert list(scratch.iterdir()) == []


def test_a_failed_run_leaves_no_directory_behind(tmp_path, monkeypatch):
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    with pytest.raises(glaswave.ConfigError, match="selects no shot"):
        glaswave.run(small_config(), shots=range(5, 9))
    assert list(tmp_path.iterdir()) == []


def test_version_and_arguments():
    assert glaswave.__version__.count(".") == 2
    with pytest.raises(glaswave.ConfigError):
        glaswave.run(small_config(), threads=-1)
    with pytest.raises(glaswave.ConfigError):
        glaswave.run(small_config(), shots=range(0, 3, 2))
    with pytest.raises(TypeError):
        glaswave.run(42)


def test_stands_under_no_shot_are_a_python_warning(tmp_path):
    # A stands file far from the track (the wrong place or CRS) is said, as the command says it.
    stands = tmp_path / "away.geojson"
    square = [[10.0, 10.0], [10.1, 10.0], [10.1, 10.1], [10.0, 10.1], [10.0, 10.0]]
    stands.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"pai": 1},
         "geometry": {"type": "Polygon", "coordinates": [square]}}]}))
    with pytest.warns(UserWarning, match=r"^/canopy/stands: none of the 1 stands"):
        glaswave.check(small_config(canopy={"stands": str(stands)}))


def test_brf_returns_what_the_command_writes_in_brf_json(write_config, tmp_path):
    config = small_config()
    config["brf"] = {"photons": 2000, "scene_size_m": 20.0, "image_resolution_m": 2.0}
    path = write_config(config)
    out = tmp_path / "brf"
    done = subprocess.run([glaswave_binary(), "brf", str(path), "--quiet", "--out", str(out)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    from_command = json.loads((out / "brf.json").read_text())
    assert glaswave.brf(path, threads=1) == from_command
    assert [band["name"] for band in from_command["bands"]] == ["532", "1064"]
    with pytest.raises(glaswave.ConfigError, match="/brf/photons"):
        glaswave.brf(config, overrides={"brf.photons": 0})
