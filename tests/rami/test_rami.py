"""RAMI's scenes (share/rami) through `glaswave brf` against independent numbers: Beer's law with
the G of each leaf angle distribution, the mean transmittance of a turbid sphere, the energy
closure, and ROMC's files read back by a reader written from ROMC's format page."""
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "share", "rami"))
import make_scenes  # noqa: E402

GLASWAVE = os.environ.get("GLASWAVE_BINARY", os.path.join(ROOT, "build", "pipeline", "glaswave"))

# G at nadir, the mean |cos| of the leaf normals' inclination t with density f(t) on [0, pi/2]:
#   planophile  f = 2/pi (1 + cos 2t):  G = 2/pi (1 + 1/3) = 8 / (3 pi)
#   erectophile f = 2/pi (1 - cos 2t):  G = 2/pi (1 - 1/3) = 4 / (3 pi)
#   uniform on the sphere (RAMI's "uniform", glaswave's spherical): G = 1/2 in every direction
# (int_0^{pi/2} cos 2t cos t dt = [sin t - 2/3 sin^3 t] = 1/3).
G_NADIR = {"pla": 8.0 / (3.0 * math.pi), "ere": 4.0 / (3.0 * math.pi), "uni": 0.5}


def turbid_sphere_transmittance(radius_m, density_m2_m3, g=0.5):
    """Mean nadir transmittance over a turbid sphere's cross-section:
    T = 1/(pi R^2) int_0^R exp(-2 k sqrt(R^2 - p^2)) 2 pi p dp, k = G u; with s = sqrt(R^2 - p^2)
    T = 2/R^2 int_0^R s exp(-2 k s) ds = 2 (1 - exp(-x) (1 + x)) / x^2, x = 2 k R."""
    x = 2.0 * g * density_m2_m3 * radius_m
    return 2.0 * (1.0 - math.exp(-x) * (1.0 + x)) / (x * x)


def read_mes(path):
    """ROMC's measurement file: a BRF file is a header line (rows, columns, the ratio of filtered
    rays) then rows of SZA, VZA, SAA - VAA (radians), BRF, its standard deviation; a flux file is
    one line, the value and its standard deviation."""
    with open(path) as f:
        lines = [line.split() for line in f.read().splitlines() if line.strip()]
    if len(lines) == 1 and len(lines[0]) == 2:
        return tuple(float(v) for v in lines[0])
    rows, columns = int(lines[0][0]), int(lines[0][1])
    assert columns == 5 and float(lines[0][2]) == 1.0 and len(lines) == rows + 1
    table = np.array([[float(v) for v in line] for line in lines[1:]])
    assert table.shape == (rows, 5)
    return table


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    out = str(tmp_path_factory.mktemp("rami"))
    make_scenes.make_scenes(out)
    return out


def brf(scenes, name, run, *settings):
    out = os.path.join(scenes, f"{name}-{run}")
    subprocess.run([GLASWAVE, "brf", os.path.join(scenes, f"{name}.json"), "--out", out,
                    "--quiet", *[a for s in settings for a in ("--set", s)]],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "brf.json")) as f:
        return out, json.load(f)


# Black leaves and soil, the sun at the zenith: what reaches the ground is the gap fraction.
GAP = ["brf.sun_zenith_deg=0", "terrain.soil_reflectance=0", "brf.photons=40000",
       'brf.rami.measurements=["ftran", "fabs", "falb"]']


def black_leaves(name):
    if name.startswith("hom_tur") or name in ("het02", "het03"):
        return ["canopy.leaf_reflectance=0", "canopy.leaf_transmittance=0"]
    return ["canopy.facets.materials.leaf.reflectance=0",
            "canopy.facets.materials.leaf.transmittance=0"]


@pytest.mark.parametrize("kind", ["tur", "dis"])
@pytest.mark.parametrize("lad", ["pla", "ere", "uni"])
def test_hom_nadir_gap_fraction_is_beers_law(scenes, kind, lad):
    name = f"hom_{kind}_{lad}"
    _, result = brf(scenes, name, "gap", *GAP, *black_leaves(name))
    band = result["bands"][0]
    expected = math.exp(-G_NADIR[lad] * make_scenes.HOM_LAI)
    # The photons' binomial error, and for discs the draw's own: a Boolean layer of discs of
    # area a over a tile of area A leaves a gap whose variance is about P^2 G L a / A.
    a = math.pi * make_scenes.HOM_DISC_M ** 2
    draw = expected * math.sqrt(G_NADIR[lad] * make_scenes.HOM_LAI * a /
                                make_scenes.HOM_TILE_M ** 2) if kind == "dis" else 0.0
    sigma = math.hypot(band["ftran_stderr"], draw)
    assert abs(band["ftran"] - expected) < 4.0 * sigma, (band["ftran"], expected, sigma)
    assert band["albedo"] == 0.0
    assert band["fabs"] + band["ftran"] == pytest.approx(1.0, abs=1e-9)


# HET01's discs, and HET03's turbid spheres whose crowns file gives each its crown_lai.
@pytest.mark.parametrize("name", ["het01", "het03"])
def test_floating_spheres_transmit_as_turbid_spheres(scenes, name):
    _, result = brf(scenes, name, "gap", *GAP, *black_leaves(name))
    band = result["bands"][0]
    radius = make_scenes.HET_RADIUS_M
    # Leaf area over the sphere's volume: LAI 5 over pi R^2, in 4/3 pi R^3.
    density = make_scenes.HET_DISCS * math.pi * make_scenes.HET_DISC_M ** 2 / (
        4.0 / 3.0 * math.pi * radius ** 3)
    cover = make_scenes.HET_SPHERES * math.pi * radius ** 2 / make_scenes.HET_TILE_M ** 2
    expected = 1.0 - cover + cover * turbid_sphere_transmittance(radius, density)
    # By hand: x = 3.75, T = 2 (1 - 4.75 e^-3.75) / 3.75^2 = 0.12634, cover 0.47124.
    assert expected == pytest.approx(0.5883, abs=1e-4)
    assert abs(band["ftran"] - expected) < 4.0 * band["ftran_stderr"], (band["ftran"], expected)


def test_closure_planes_and_romc_files(scenes):
    out, result = brf(scenes, "hom_dis_uni", "rami", "brf.photons=3000")
    config = json.load(open(os.path.join(scenes, "hom_dis_uni.json")))
    soil = config["terrain"]["soil_reflectance"]
    sza = math.radians(config["brf"]["sun_zenith_deg"])
    for band in result["bands"]:
        name = band["name"]
        # Energy: what left through the top, what the leaves kept and what the soil kept is
        # what came in, within the error of the photons' closure (Russian roulette's draws).
        closure = band["albedo"] + band["fabs"] + band["ftran"] * (1.0 - soil[name])
        assert closure == pytest.approx(band["closure"], abs=1e-9)
        assert 0.0 < band["closure_stderr"] < 0.01
        assert abs(closure - 1.0) < 4.0 * band["closure_stderr"], (name, closure)

        def mes(measurement):
            return read_mes(os.path.join(
                out, "rami", f"{measurement}_glaswave-HOM03_DIS_UNI_{name}_20.mes"))
        pp, op = mes("brfpp"), mes("brfop")
        assert pp.shape == op.shape == (76, 5)
        assert np.allclose(pp[:, 0], sza) and np.allclose(op[:, 0], sza)
        # The views of brf.json are on RAMI's grid: the same numbers in the planes' files.
        for view in band["views"]:
            relative = math.radians((config["brf"]["sun_azimuth_deg"] - view["azimuth_deg"]) % 360)
            table = pp if relative in (0.0, math.pi) else op
            hit = table[(np.abs(table[:, 1] - math.radians(view["zenith_deg"])) < 1e-5) &
                        (np.abs(table[:, 2] - relative) < 1e-5)]
            assert len(hit) == 1, view
            assert hit[0, 3] == pytest.approx(view["brf"], abs=1e-6)
            assert hit[0, 4] == pytest.approx(view["brf_stderr"], abs=1e-6)
        # Near the zenith the two planes see the same: their four views 1 deg off nadir agree.
        near_pp = pp[np.abs(pp[:, 1] - math.radians(1.0)) < 1e-5]
        near_op = op[np.abs(op[:, 1] - math.radians(1.0)) < 1e-5]
        assert len(near_pp) == len(near_op) == 2
        assert abs(near_pp[:, 3].mean() - near_op[:, 3].mean()) < 4.0 * near_pp[:, 4].max()
        # The parts sum to the whole.
        parts = sum(mes(f"brfpp_{p}")[:, 3] for p in ("co_sgl", "uc_sgl", "mlt"))
        assert np.allclose(parts, pp[:, 3], atol=4e-6)
        for measurement, key in (("fabs", "fabs"), ("ftran", "ftran"), ("falb", "albedo")):
            value, error = mes(measurement)
            assert value == pytest.approx(band[key], abs=1e-6)
            assert error == pytest.approx(band[key + "_stderr"], abs=1e-6)
        brf1 = mes("brf1")
        assert brf1.shape == (1, 5) and brf1[0, 1] == -1.0 and brf1[0, 2] == -1.0
        assert brf1[0, 3] == pytest.approx(band["albedo"], abs=1e-6)


def read_lidar_mes(path):
    """ROMC's lidar file (RAMI-IV's lidar_tot page): a header line (rows, columns, the height
    interval), then rows from the ground up of the bin's mean height (m), the return signal and
    its standard deviation (-1 when not available)."""
    with open(path) as f:
        lines = [line.split() for line in f.read().splitlines() if line.strip()]
    rows, columns, interval = int(lines[0][0]), int(lines[0][1]), float(lines[0][2])
    table = np.array([[float(v) for v in line] for line in lines[1:]])
    assert columns == 3 and table.shape == (rows, 3)
    assert np.allclose(table[:, 0], (np.arange(rows) + 0.5) * interval, atol=1e-6)
    return interval, table


def test_turbid_layer_lidar_single_scattering_profile(scenes):
    """RAMI-IV's lidar_sgl_co of the 1 m turbid layer (LAI 3, spherical: G = 1/2) against
    PHYSICS.md section 3's hotspot column, the laser and the detector co-located: at depth z
    below the top the canopy returns (u rho / 3) e^(-u z / 2) per unit depth (u = L / H), the
    ground rho_s e^(-L / 2). A row's return is that integrated over the heights its window bins
    span: window bins of d = c bin_ns / 2 centred on the rows' edges, each whole in the row below
    its centre, so row j >= 1 spans [j D + d/2, (j+1) D + d/2] and the first [0, D + d/2] with
    the ground."""
    out = os.path.join(scenes, "hom_tur_uni-lidar")
    subprocess.run([GLASWAVE, "run", os.path.join(scenes, "hom_tur_uni_lidar.json"), "--out", out,
                    "--quiet", "--set", "simulation.rays_per_shot=4000"],
                   check=True, stdout=subprocess.DEVNULL)
    config = json.load(open(os.path.join(scenes, "hom_tur_uni_lidar.json")))
    d = 0.5 * 299792458.0 * config["sensor"]["bin_ns"] * 1e-9
    rho, rho_s = make_scenes.NIR["reflectance"], make_scenes.NIR["soil"]
    lai, depth = make_scenes.HOM_LAI, make_scenes.HOM_DEPTH_M
    u = lai / depth
    interval, single = read_lidar_mes(os.path.join(
        out, "rami", "lidar_sgl_co_glaswave-HOM03_TUR_UNI_NIR.mes"))
    _, total = read_lidar_mes(os.path.join(out, "rami", "lidar_tot_glaswave-HOM03_TUR_UNI_NIR.mes"))
    assert interval == pytest.approx(0.05) and len(single) == len(total) == 20

    def canopy(low_m, high_m):  # heights above the ground
        low_m, high_m = max(low_m, 0.0), min(high_m, depth)
        if high_m <= low_m:
            return 0.0
        return 2.0 * rho / 3.0 * (math.exp(-u * (depth - high_m) / 2) -
                                  math.exp(-u * (depth - low_m) / 2))

    expected = np.array([canopy(0.0 if j == 0 else j * interval + d / 2, (j + 1) * interval + d / 2)
                         for j in range(len(single))])
    expected[0] += rho_s * math.exp(-lai / 2)
    # By hand: the canopy's whole single scattering (2 rho / 3)(1 - e^-1.5) = 0.25673, the
    # ground's 0.159 e^-1.5 = 0.03548.
    assert expected.sum() == pytest.approx(0.25673 + 0.03548, abs=1e-4)
    sd = single[:, 2]
    assert np.all(sd > 0), "ten shots give each row a standard error"
    # Row by row within 4.5 of the ten shots' standard errors (themselves 25 % uncertain), the
    # whole within 4 of its own.
    z = (single[:, 1] - expected) / sd
    assert np.all(np.abs(z) < 4.5), z
    assert abs(single[:, 1].sum() - expected.sum()) < 4.0 * math.sqrt((sd ** 2).sum())
    # Multiple scattering only adds, and arrives no earlier than the single.
    assert np.all(total[:, 1] >= single[:, 1] - 1e-12)
    assert total[:, 1].sum() > single[:, 1].sum() * 1.05
