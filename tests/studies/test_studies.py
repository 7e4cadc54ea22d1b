"""Unit checks of share/studies/studies.py's own arithmetic, against closed forms worked by hand:
G(0) of each leaf angle distribution (VPAI's projection), the RMS width of a sampled Gaussian,
the part of the beam in the field of view (PHYSICS.md 1), and --set on a configuration dict."""
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "share", "studies"))
import studies  # noqa: E402


# G(0) = integral of g(t) cos t over [0, pi/2]; for de Wit's g = 2/pi (1 +- cos 2t) or
# 2/pi (1 +- cos 4t) the integrals of cos 2t cos t and cos 4t cos t are 1/3 and -1/15.
@pytest.mark.parametrize("lad, expected", [
    ("spherical", 0.5),
    ("planophile", 2 / math.pi * (1 + 1 / 3)),
    ("erectophile", 2 / math.pi * (1 - 1 / 3)),
    ("plagiophile", 2 / math.pi * (1 + 1 / 15)),
    ("extremophile", 2 / math.pi * (1 - 1 / 15)),
    ("uniform", 2 / math.pi),
])
def test_g_nadir_matches_closed_forms(lad, expected):
    assert studies.g_nadir(lad) == pytest.approx(expected, abs=1e-6)


def test_ellipsoidal_g_nadir_falls_as_leaves_stand_up():
    # Campbell's distribution: flatter leaves (a smaller mean inclination) project more.
    values = [studies.g_nadir({"ellipsoidal_mean_deg": m}) for m in (20, 40, 57.3, 70)]
    assert values == sorted(values, reverse=True)
    assert values[2] == pytest.approx(0.5, abs=0.02)  # mean 57.3 deg is about spherical


def test_rms_width_of_a_sampled_gaussian():
    t = np.arange(-200.0, 200.0, 1.0)
    power = np.exp(-0.5 * ((t - 12.0) / 7.5) ** 2)
    assert studies.rms_width_ns(t, power) == pytest.approx(7.5, rel=1e-6)


def test_fov_fraction_of_the_seeds_sensor():
    # PHYSICS.md 1: 1 - exp(-ifov^2 / (8 sigma^2)) = 0.808 for Table 2.
    config = '{"sensor": {"ifov_rad": 0.0004, "divergence_sigma_rad": 0.00011}}'

    class Shots:
        attrs = {"config": config}

    assert studies.fov_fraction(Shots()) == pytest.approx(1 - math.exp(-1.6 / 0.968), abs=1e-12)
    assert studies.fov_fraction(Shots()) == pytest.approx(0.808, abs=1e-3)  # as quoted, 3 places


def test_apply_set_makes_the_path():
    document = {"canopy": {"pai": 3}}
    studies.apply_set(document, "canopy.pai", 5)
    studies.apply_set(document, "terrain.plane.slope_deg", 10)
    assert document == {"canopy": {"pai": 5}, "terrain": {"plane": {"slope_deg": 10}}}
