"""share/vegetation's examples (issue 24): the four configurations of one forest run through
`glaswave run` (plot_waveforms.py, which also checks crowns.json's PAI against the trees) and
`glaswave brf`, on small inputs made by the example's own scripts in a copy of the folder.
GLASWAVE_BINARY names the built command."""
import json
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
CONFIGURATIONS = ["facets", "point_cloud", "voxels", "crowns"]


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    """A copy of share/vegetation beside out/vegetation/ holding a small tree model (2000
    leaves), a sparse cloud of the forest (0.25 pulses/m2) and its voxel grid."""
    root = tmp_path_factory.mktemp("vegetation")
    here = root / "share" / "vegetation"
    shutil.copytree(SOURCE_DIR / "share" / "vegetation", here,
                    ignore=shutil.ignore_patterns("__pycache__"))
    data = root / "out" / "vegetation"
    data.mkdir(parents=True)
    binary = os.environ["GLASWAVE_BINARY"]
    for command in (
            [sys.executable, here / "make_facet_tree.py", data / "tree.obj", "--leaves", "2000"],
            [sys.executable, here / "make_als_cloud.py", data / "forest.las", "--density", "0.25",
             "--trees", here / "facet_trees.csv"],
            [binary, "voxelize", data / "forest.las", "--out", data / "forest_pad.nc",
             "--voxel-size-m", "2"]):
        subprocess.run([str(c) for c in command], check=True, capture_output=True)
    # The four runs and the figure; the crowns file crowns.json reads is written on the way.
    plotted = subprocess.run([sys.executable, str(here / "plot_waveforms.py"), "--glaswave",
                              binary, "--rays", "300"], capture_output=True, text=True)
    return here, binary, plotted


def test_the_four_sources_run_and_are_plotted(example):
    here, _, plotted = example
    assert plotted.returncode == 0, plotted.stderr
    data = here.parent.parent / "out" / "vegetation"
    assert (data / "waveforms.png").stat().st_size > 10000
    for name in CONFIGURATIONS:
        assert (data / "runs" / name / "shots.nc").exists(), name


@pytest.mark.parametrize("name", CONFIGURATIONS)
def test_brf_runs_through_each_configuration(example, name, tmp_path):
    here, binary, _ = example
    out = tmp_path / "brf"
    done = subprocess.run([binary, "brf", str(here / f"{name}.json"), "--out", str(out), "--quiet",
                           "--set", "brf.photons=5000", "--set", "brf.scene_size_m=40",
                           "--set", "brf.image_resolution_m=4"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    albedo = json.loads((out / "brf.json").read_text())["bands"][0]["albedo"]
    # Soil of 0.25 under leaves of 0.45 + 0.45: between the two (0.26-0.29 measured).
    assert 0.2 < albedo < 0.45
    assert (out / "scene.tif").exists()
