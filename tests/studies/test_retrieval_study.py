"""Unit checks of share/studies/retrieval.py's arithmetic on arrays made by hand: bias, RMSE and
the 90 % interval's coverage, NaN shots left out, and the strata's masks."""
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "share", "studies"))
import retrieval  # noqa: E402

NAN = float("nan")


def test_bias_and_rmse_by_hand():
    # Errors +1, -3, +2: bias 0, RMSE sqrt((1 + 9 + 4) / 3).
    estimate = [2.0, 0.0, 5.0]
    truth = [1.0, 3.0, 3.0]
    assert retrieval.bias(estimate, truth) == pytest.approx(0.0, abs=1e-15)
    assert retrieval.rmse(estimate, truth) == pytest.approx(math.sqrt(14.0 / 3.0), rel=1e-15)


def test_nan_shots_are_left_out_of_both():
    # Only the second and fourth pairs are finite: errors +0.5 and +1.5.
    estimate = [NAN, 1.5, 7.0, 4.5]
    truth = [1.0, 1.0, NAN, 3.0]
    assert retrieval.bias(estimate, truth) == pytest.approx(1.0)
    assert retrieval.rmse(estimate, truth) == pytest.approx(math.sqrt((0.25 + 2.25) / 2))
    assert math.isnan(retrieval.bias([NAN], [1.0]))
    assert math.isnan(retrieval.rmse([], []))


def test_coverage_counts_closed_intervals():
    low = [0.0, 1.0, 2.0, 0.0, NAN]
    high = [1.0, 2.0, 3.0, 0.5, 9.0]
    truth = [1.0, 0.5, 2.0, 0.7, 3.0]
    # In: 1 in [0, 1] (the bound counts), 2 in [2, 3]. Out: 0.5, 0.7. The NaN bound: not counted.
    assert retrieval.coverage(low, high, truth) == pytest.approx(2.0 / 4.0)
    assert math.isnan(retrieval.coverage([NAN], [NAN], [1.0]))


def test_metrics_give_coverage_for_rt_only_and_honour_a_mask():
    shots = {
        "pai_true": np.array([1.0, 2.0, 3.0, 4.0]),
        "pai_gedi_l2b": np.array([0.5, 1.0, 2.0, NAN]),
        "pai_rt": np.array([1.0, 2.5, 3.0, 3.0]),
        "pai_rt_p05": np.array([0.5, 2.2, 2.0, 3.5]),
        "pai_rt_p95": np.array([1.5, 3.0, 4.0, 4.5]),
    }
    l2b = retrieval.metrics(shots, "gedi_l2b", "pai")
    assert l2b["n"] == 3
    assert l2b["bias"] == pytest.approx((-0.5 - 1.0 - 1.0) / 3)
    assert math.isnan(l2b["coverage90"])
    rt = retrieval.metrics(shots, "rt", "pai")
    assert rt["bias"] == pytest.approx((0.0 + 0.5 + 0.0 - 1.0) / 4)
    assert rt["rmse"] == pytest.approx(math.sqrt((0.25 + 1.0) / 4))
    assert rt["coverage90"] == pytest.approx(3.0 / 4.0)  # 2.0 lies below [2.2, 3.0]
    masked = retrieval.metrics(shots, "rt", "pai", np.array([False, True, False, True]))
    assert masked["n"] == 2
    assert masked["coverage90"] == pytest.approx(0.5)
    assert retrieval.metrics(shots, "wi", "pai") is None


def test_a_stand_beyond_the_table_is_not_inside_its_ranges():
    stand = {key: 0.5 * (low + high) for key, (low, high) in retrieval.TABLE_VARY.items()}
    stand["canopy.crown_shape"] = "ellipsoid"
    stand["canopy.crown_base_m"] = [6.0, 7.5]  # inside the layers' 2-18 m
    assert retrieval.in_table_ranges(stand)
    assert retrieval.in_table_ranges({**stand, "canopy.crown_shape": "cone"})
    assert not retrieval.in_table_ranges({**stand, "canopy.crown_shape": "cylinder"})
    assert not retrieval.in_table_ranges({**stand, "canopy.pai": 6.5})  # the table's to 6
    assert not retrieval.in_table_ranges({**stand, "canopy.crown_radius_m": 1.0})
    assert not retrieval.in_table_ranges({**stand, "canopy.crown_base_m": [1.0, 3.0]})


def test_a_truth_beyond_the_tables_truths_is_not_inside_them():
    # Ranges by hand: PAI 0.5-5, cover 0.1-0.9, height 5-30 m. Shot 0 inside every one; shot 1's
    # PAI 7 beyond; shot 2's cover 0.95 beyond; shot 3 on the bounds (inside); shot 4 NaN.
    ranges = {"pai": (0.5, 5.0), "cover": (0.1, 0.9), "canopy_height": (5.0, 30.0)}
    shots = {
        "shot_number": np.arange(5),
        "pai_true": np.array([2.0, 7.0, 2.0, 0.5, NAN]),
        "cover_true": np.array([0.5, 0.5, 0.95, 0.9, 0.5]),
        "canopy_height_true": np.array([20.0, 20.0, 20.0, 30.0, 20.0]),
    }
    inside = retrieval.truth_in_table(shots, ranges)
    assert inside.tolist() == [True, False, False, True, False]


def test_the_ground_energy_fit_recovers_a_known_forest():
    # Ground energies made from the closed form with Eg0 = 2e-15 J and k = 0.35 (a multiple of
    # the fit's grid step), no noise: the fit returns them.
    rng = np.random.default_rng(1)
    pai = rng.uniform(0.1, 10.0, 300)
    cover = rng.uniform(0.2, 0.95, 300)
    eg = 2e-15 * ((1.0 - cover) + cover * np.exp(-0.35 * pai / cover))
    eg0, k, residual = retrieval.fit_ground_energy(pai, cover, eg)
    assert k == pytest.approx(0.35, abs=1e-9)
    assert eg0 == pytest.approx(2e-15, rel=1e-9)
    assert residual == pytest.approx(0.0, abs=1e-24)


def test_saturation_pai_by_hand():
    # Eg0 k = 0.5, noise 0.01: exp(-0.5 P / 0.5) = 0.02 at P = ln 50 = 3.912; twice the noise
    # (changes 2): ln 25 = 3.219; below the noise already at PAI 0: 0.
    assert retrieval.saturation_pai(1.0, 0.5, 0.5, 0.01) == pytest.approx(math.log(50.0))
    assert retrieval.saturation_pai(1.0, 0.5, 0.5, 0.01, 2.0) == pytest.approx(math.log(25.0))
    assert retrieval.saturation_pai(1.0, 0.5, 0.9, 1.0) == 0.0


def test_alike_pairs_by_hand():
    # Two shots an entry, two bins. Entries 0 and 1 have the same mean waveform; 2 and 3 each
    # their own. Each first shot lies delta off its mean, so S0 - S_rest = 2 delta:
    # a = sum (2 delta)^2 / ((1 + 1) sum W) = (4 + 4 + 100 + 100) / (2 * 208) = 0.5.
    waveform = np.array([[4.0, 0.0], [4.0, 0.0], [100.0, 0.0], [0.0, 100.0]])
    delta = np.array([[1.0, 0.0], [1.0, 0.0], [5.0, 0.0], [0.0, 5.0]])
    shot0 = waveform + delta
    assert retrieval.ray_amplitude(waveform, shot0, 2) == pytest.approx(0.5)
    # d_self = (2 delta)^2 / (2 a max(W, a)) = 4 / 4 = 1 and 100 / 100 = 1: the threshold is 1.
    # d(0, 1) = 0; d(0, 2) = 96^2 / (0.5 (4 + 100) / 2) = 354: only (0, 1) is alike, at both
    # thresholds (1 and 0.5). Its covers differ by 0.3.
    result = retrieval.alike_pairs(waveform, shot0, 2, {"cover": [0.2, 0.5, 0.9, 0.1]})
    assert result["self_median"] == pytest.approx(1.0)
    assert [r["pairs"] for r in result["rows"]] == [1, 1]
    assert [r["threshold"] for r in result["rows"]] == pytest.approx([1.0, 0.5])
    assert result["rows"][0]["cover"] == pytest.approx(0.3)
    # Entry 1's mean moved 2 off entry 0's in the first bin: a = 208 / (2 * 210), the threshold
    # 4 / (2 a 4) = 1.01 (entries 0, 2 and 3), d(0, 1) = 4 / (a (4 + 6) / 2) = 1.62: no pair.
    waveform[1, 0] = 6.0
    shot0 = waveform + delta
    rows = retrieval.alike_pairs(waveform, shot0, 2, {"cover": [0.2, 0.5, 0.9, 0.1]})["rows"]
    assert [r["pairs"] for r in rows] == [0, 0]
    assert math.isnan(rows[0]["cover"])
