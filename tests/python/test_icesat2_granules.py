"""atl03.h5 and atl08.h5 (PRODUCT.md section 9) opened exactly as ICESat-2's readers open them,
with h5py: the same paths, the same type expectations and the same index arithmetic, each
checked against numbers computed here from the photons. The code paths followed, read (never
copied) from:

- SpaceLiDAR.jl, evetion/SpaceLiDAR.jl src/ICESat-2/ATL03.jl points(): heights/lon_ph, lat_ph
  (Float64), h_ph (Float32), delta_time (Float64) + ancillary_data/atlas_sdp_gps_epoch[1]
  (Float64) + gps_offset 315964800 as Unix time, signal_conf_ph[1, :] (Int8, the land column),
  quality_ph (Int8); each photon's segment by count2index(geolocation/segment_ph_cnt (Int32))
  into segment_id (Int32), solar_elevation and sigma_h (Float32), geophys_corr/dem_h (Float32);
  the group attributes atlas_spot_number (parsed as Int8) and atlas_beam_type ("strong").
  ATL08.jl points(): land_segments/longitude, latitude (Float32), terrain/h_te_mean and
  h_te_uncertainty, canopy/h_mean_canopy_abs and h_canopy_uncertainty (Float32), delta_time
  (Float64), snr (Float32), layer_flag, msw_flag, sat_flag, ph_removal_flag (Int8), terrain_flg
  (Int32), dem_h (Float32), Bool.() of terrain_flg, ph_removal_flag and layer_flag (0 or 1 only);
  lines(): terrain/h_te_median; orbit_info/sc_orient[1] (Int8) and track_power (0: the left beams
  strong); classify(): signal_photons/classed_pc_flag (Int8), classed_pc_indx and ph_segment_id
  (Int32), a photon found as the first photon of its segment (searchsortedfirst) plus
  classed_pc_indx - 1.
- ICESat2VegR, carlos-alberto-silva/ICESat2VegR R/ATL03_ATL08_photons_attributes_dt_join.R:
  ATL03 photons' ph_segment_id = rep(geolocation/segment_id, segment_ph_cnt), classed_pc_indx =
  seq_len within a segment, dist_ph_along + cumsum(segment_length) from 0, dist_ph_across,
  quality_ph, solar_elevation per segment; joined on (ph_segment_id, classed_pc_indx) to ATL08's
  signal_photons {ph_segment_id, classed_pc_indx, classed_pc_flag, ph_h, d_flag, delta_time};
  R/ATL08_seg_attributes_dt.R's defaults h_canopy, canopy_openness, h_te_mean, terrain_slope,
  and canopy_h_metrics (segments x 18), h_median_canopy, h_te_median among the metrics it maps.
- icepyx, icesat2py/icepyx icepyx/core/read.py: the root attribute identifier_product_type, the
  variables it always adds (orbit_info/sc_orient, rgt, cycle_number; ancillary_data/
  atlas_sdp_gps_epoch, data_start_utc and data_end_utc as numpy datetime64).
"""
import json
import subprocess
from datetime import datetime, timedelta, timezone

import h5py
import numpy as np
import pytest

from conftest import glaswave_binary

START = "2019-06-21T19:30:00Z"  # the sun high over the plane (local noon about 19:52 UTC)
ELEVATION_M = 300.0
SLOPE_DEG = 4.0
BEAMS = ["gt1l", "gt1r"]
# The preset's ground tracks (footprints/atlas_beams.hpp): the gt1 pair 3300 m left of the
# reference ground track, its beams 45 m either side; the left beam strong.
ACROSS_M = {"gt1l": -3345.0, "gt1r": -3255.0}
STRONG = {"gt1l": True, "gt1r": False}
AHEAD_M = {"gt1l": 0.0, "gt1r": 2500.0}  # the weak beam 2.5 km ahead of its strong one
GPS_EPOCH = datetime(1980, 1, 6, tzinfo=timezone.utc)
GPS_MINUS_UTC_S = 18  # leap seconds since 2017


def run_pass(tmp_path):
    """400 shots (280 m) of a strong and a weak beam over a forest on a 4 degree slope, by day."""
    config = {
        "seed": 11,
        "sensor": {"preset": "atlas", "beams": BEAMS},
        "simulation": {"rays_per_shot": 30, "max_order": 3, "background": "sun"},
        "terrain": {"plane": {"origin_lat_deg": 34.3, "origin_lon_deg": -118.2,
                              "elevation_m": ELEVATION_M, "slope_deg": SLOPE_DEG,
                              "aspect_deg": 180.0},
                    "soil_reflectance": 0.25},
        "canopy": {"pai": 2.5, "cover": 0.5, "crown_radius_m": 4.0, "crown_half_height_m": 5.0,
                   "crown_base_m": [6.0, 10.0]},
        "track": {"type": "pass", "start_lat_deg": 34.3, "start_lon_deg": -118.2,
                  "heading_deg": 0.0, "shots": 400, "spacing_m": 0.7, "rate_hz": 10000.0,
                  "altitude_m": 496000.0,
                  "start_time": START},
        "output": {"netcdf": False, "footprints": False},
    }
    path = tmp_path / "atlas.json"
    path.write_text(json.dumps(config))
    out = tmp_path / "atlas"
    subprocess.run([glaswave_binary(), "run", str(path), "--out", str(out), "--quiet"],
                   check=True, capture_output=True)
    return out


@pytest.fixture(scope="module")
def granules(tmp_path_factory):
    out = run_pass(tmp_path_factory.mktemp("icesat2"))
    with h5py.File(out / "atl03.h5") as atl03, h5py.File(out / "atl08.h5") as atl08:
        yield atl03, atl08


def plane_height(along_m, beam):
    """The plane's height under a beam's shot: the pass starts at the plane's origin heading
    north, up the slope (aspect 180: the slope faces south), the beam AHEAD_M ahead of it."""
    return ELEVATION_M + np.tan(np.radians(SLOPE_DEG)) * (along_m + AHEAD_M[beam])


def dataset(f, path, dtype, ndim=1):
    """A dataset read as a typed reader reads it: the type it asserts, or the read fails."""
    d = f[path]
    assert d.dtype == np.dtype(dtype), f"{path}: {d.dtype} is not {dtype}"
    assert d.ndim == ndim, path
    return d[()]


def text_attribute(group, name):
    value = group.attrs[name]
    return value.decode() if isinstance(value, bytes) else str(value)


def count2index(counts):
    """SpaceLiDAR's map from segment counts to each photon's (1-based) segment position."""
    return np.repeat(np.arange(1, len(counts) + 1), counts)


def atl03_photons(atl03, beam):
    """ATL03 as SpaceLiDAR's points() reads it, with ICESat2VegR's per-photon columns."""
    g = atl03[beam]
    p = {"lon": dataset(g, "heights/lon_ph", "f8"), "lat": dataset(g, "heights/lat_ph", "f8"),
         "h": dataset(g, "heights/h_ph", "f4"), "time": dataset(g, "heights/delta_time", "f8"),
         "quality": dataset(g, "heights/quality_ph", "i1"),
         "truth": g["heights/glaswave_truth_class"][()], "order": g["heights/glaswave_order"][()]}
    confidence = dataset(g, "heights/signal_conf_ph", "i1", ndim=2)
    assert confidence.shape == (len(p["h"]), 5)
    p["confidence"] = confidence[:, 0]  # Julia's [1, :] of the column-major view
    counts = dataset(g, "geolocation/segment_ph_cnt", "i4")
    segment_ids = dataset(g, "geolocation/segment_id", "i4")
    index = count2index(counts)
    assert len(index) == len(p["h"])  # Julia's ph_ind[start:stop] would be out of bounds
    p["segment"] = segment_ids[index - 1]
    for name in ("solar_elevation", "sigma_h"):
        p[name] = dataset(g, "geolocation/" + name, "f4")[index - 1]
    p["dem_h"] = dataset(g, "geophys_corr/dem_h", "f4")[index - 1]
    # ICESat2VegR: rep(segment_id, segment_ph_cnt) and the along-track distance.
    assert np.array_equal(np.repeat(segment_ids, counts), p["segment"])
    lengths = g["geolocation/segment_length"][()]
    starts = np.concatenate([[0.0], np.cumsum(lengths[:-1])])
    p["along"] = dataset(g, "heights/dist_ph_along", "f4") + np.repeat(starts, counts)
    p["across"] = dataset(g, "heights/dist_ph_across", "f4")
    p["beg"] = dataset(g, "geolocation/ph_index_beg", "i8")
    p["counts"], p["segment_ids"] = counts, segment_ids
    return p


def spacelidar_classify(photons, atl08, beam):
    """SpaceLiDAR's classify(): each ATL08 photon's ATL03 index (0-based here)."""
    s = dataset(atl08, f"{beam}/signal_photons/ph_segment_id", "i4")
    i = dataset(atl08, f"{beam}/signal_photons/classed_pc_indx", "i4")
    dataset(atl08, f"{beam}/signal_photons/classed_pc_flag", "i1")
    first = {}
    for segment in np.unique(s):
        pos = np.searchsorted(photons["segment"], segment)  # searchsortedfirst
        if pos < len(photons["segment"]) and photons["segment"][pos] == segment:
            first[segment] = pos
    return np.array([first[a] + b - 1 for a, b in zip(s, i)])


def icesat2vegr_join(photons, atl08, beam):
    """ICESat2VegR's join on (ph_segment_id, classed_pc_indx): each ATL08 photon's ATL03 index."""
    segment = photons["segment"]
    rank = np.zeros(len(segment), dtype=np.int64)  # seq_len(.N) by ph_segment_id
    for k in range(1, len(segment)):
        rank[k] = rank[k - 1] + 1 if segment[k] == segment[k - 1] else 0
    where = {(int(a), int(b) + 1): k for k, (a, b) in enumerate(zip(segment, rank))}
    s = atl08[f"{beam}/signal_photons/ph_segment_id"][()]
    i = atl08[f"{beam}/signal_photons/classed_pc_indx"][()]
    return np.array([where[(int(a), int(b))] for a, b in zip(s, i)])


def test_both_granules_carry_what_icepyx_and_spacelidar_need(granules):
    atl03, atl08 = granules
    for f, product in ((atl03, "ATL03"), (atl08, "ATL08")):
        assert text_attribute(f, "identifier_product_type") == product
        assert text_attribute(f, "short_name") == product
        assert dataset(f, "ancillary_data/atlas_sdp_gps_epoch", "f8")[0] == 1198800018.0
        start = f["ancillary_data/data_start_utc"][0].decode()
        assert np.datetime64(start.rstrip("Z")) == np.datetime64(START.rstrip("Z"))
        end = np.datetime64(f["ancillary_data/data_end_utc"][0].decode().rstrip("Z"))
        # 400 shots at 10 kHz: the last 39.9 ms after the first.
        assert (end - np.datetime64(START.rstrip("Z"))) == np.timedelta64(39900, "us")
        orient = dataset(f, "orbit_info/sc_orient", "i1")
        assert orient.shape == (1,) and orient[0] == 0
        for name in ("rgt", "cycle_number"):
            assert f["orbit_info/" + name].shape == (1,)
        for beam in BEAMS:
            g = f[beam]
            # SpaceLiDAR's track_power from sc_orient, the attribute and the preset agree.
            power = "weak" if "r" in beam else "strong"
            assert text_attribute(g, "atlas_beam_type") == power
            assert STRONG[beam] == (power == "strong")
            spot = int(np.int8(text_attribute(g, "atlas_spot_number")))
            assert spot % 2 == (1 if STRONG[beam] else 0)  # ATLAS's strong spots: 1, 3, 5
            assert text_attribute(g, "sc_orientation") == "Backward"


def test_atl03_reads_as_spacelidar_and_icesat2vegr_read_it(granules):
    atl03, _ = granules
    counts = {}
    for beam in BEAMS:
        p = atl03_photons(atl03, beam)
        counts[beam] = len(p["h"])
        # The photons' times: SpaceLiDAR's Unix time is GPS seconds (18 s ahead of UTC); the
        # GPS seconds less the leap seconds are the run's shot times, 0.1 ms apart.
        gps_s = p["time"] + 1198800018.0
        utc = GPS_EPOCH + timedelta(seconds=float(gps_s.min()) - GPS_MINUS_UTC_S)
        # The first photon comes from one of the pass's shots (not always shot 0: a shot may
        # record none), each 0.1 ms after the one before.
        after_s = (utc - datetime(2019, 6, 21, 19, 30, tzinfo=timezone.utc)).total_seconds()
        assert 0 <= round(after_s / 1e-4) < 400 and abs(after_s - round(after_s / 1e-4) * 1e-4) \
            < 1e-6
        assert np.ptp(p["time"]) <= 399 * 1e-4 + 1e-9
        # ph_index_beg is 1-based and agrees with the counts (0 for an empty segment).
        begins = np.concatenate([[1], 1 + np.cumsum(p["counts"][:-1])])
        assert np.array_equal(np.where(p["counts"] > 0, begins, 0), p["beg"])
        # dist_ph_along within its 20 m; ICESat2VegR's along-track distance steps by the 0.7 m
        # between shots and spans the pass.
        assert np.all((p["along"] >= 0) & (p["along"] < 20.0 * len(p["counts"])))
        steps = np.diff(np.unique(np.round(p["along"], 3)))
        assert abs(np.median(steps) - 0.7) < 0.01
        # Each photon's distance is its shot's: 0.7 m for each 0.1 ms of its time (to 1 m, the
        # shots' spread about their footprint centres), and the photons span the pass.
        shot = np.round((p["time"] - p["time"].min()) / 1e-4)
        assert np.all(np.abs(p["along"] - p["along"].min() - 0.7 * shot) < 1.0)
        assert p["along"].max() - p["along"].min() > 0.9 * 399 * 0.7
        # Across track: the ground photons lie on the beam's ground track, within the 11 m
        # footprint, the ground track where the preset puts it.
        ground = p["truth"] == 1
        assert np.all(np.abs(p["across"][ground] - ACROSS_M[beam]) < 10.0)
        assert abs(np.median(p["across"][ground]) - ACROSS_M[beam]) < 1.0
        assert np.all(p["quality"] == 0)
        assert np.all(p["sigma_h"] == 0)
        assert set(np.unique(p["confidence"])) <= {0, 2, 3, 4}
        # The sun's elevation: the same for every segment of a 280 m pass, high at noon.
        assert 70.0 < p["solar_elevation"].min() <= p["solar_elevation"].max() < 80.0
        # dem_h: the plane at each 20 m segment's first shot, within 0.7 m of its start; the
        # ground photons on the plane at their shot (ICESat2VegR's along-track distance), up to
        # the footprint's 11 m.
        dem = atl03[beam]["geophys_corr/dem_h"][()]
        starts = 20.0 * np.arange(len(dem))
        rise_m = 0.35 * np.tan(np.radians(SLOPE_DEG))
        np.testing.assert_allclose(dem, plane_height(starts + 0.35, beam), atol=rise_m + 0.01)
        # Single scattering only: the multiply scattered photons' longer paths put them lower.
        single = ground & (p["order"] == 1)
        below = p["h"][single] - plane_height(p["along"][single], beam)
        assert abs(np.median(below)) < 0.1 and np.all(np.abs(below) < 1.0)
    # A weak beam carries 45/175 of a strong one's energy: fewer photons.
    assert counts["gt1r"] < 0.7 * counts["gt1l"]


def test_atl08_photons_join_atl03_photons_of_their_height(granules):
    atl03, atl08 = granules
    for beam in BEAMS:
        p = atl03_photons(atl03, beam)
        spacelidar = spacelidar_classify(p, atl08, beam)
        vegr = icesat2vegr_join(p, atl08, beam)
        assert np.array_equal(spacelidar, vegr)
        assert len(np.unique(vegr)) == len(vegr)  # each ATL03 photon classed once
        sp = atl08[f"{beam}/signal_photons"]
        flag = sp["classed_pc_flag"][()]
        ph_h = dataset(atl08, f"{beam}/signal_photons/ph_h", "f4")
        assert np.all(dataset(atl08, f"{beam}/signal_photons/d_flag", "i1") == 1)
        assert np.array_equal(dataset(atl08, f"{beam}/signal_photons/delta_time", "f8"),
                              p["time"][vegr])
        # h_ph - ph_h is the fitted ground at each photon's shot: the same for all the photons
        # of a shot (to float32's rounding), where a join off by a photon would land on canopy or
        # noise photons metres away; and about the plane there.
        ground_under = p["h"][vegr].astype(np.float64) - ph_h
        for shot_time in np.unique(p["time"][vegr]):
            assert np.ptp(ground_under[p["time"][vegr] == shot_time]) < 1e-4
        off = ground_under - plane_height(p["along"][vegr], beam)
        assert np.median(np.abs(off)) < 0.2
        # The classes against the simulation's truth: ground photons mostly ground.
        truth = p["truth"][vegr]
        assert np.mean(truth[flag == 1] == 1) > 0.8
        assert np.mean(np.isin(truth[flag >= 2], (2, 3))) > 0.6


def segment_photons(atl03, atl08, beam):
    """Per land segment, its ATL03 photons and its classed ones (from the join), by the segment
    ids ATL08 gives (segment_id_beg..segment_id_end)."""
    p = atl03_photons(atl03, beam)
    joined = icesat2vegr_join(p, atl08, beam)
    flag = atl08[f"{beam}/signal_photons/classed_pc_flag"][()]
    ph_h = atl08[f"{beam}/signal_photons/ph_h"][()].astype(np.float64)
    land = atl08[f"{beam}/land_segments"]
    beg = dataset(land, "segment_id_beg", "i4")
    end = dataset(land, "segment_id_end", "i4")
    for k in range(len(beg)):
        inside = (p["segment"] >= beg[k]) & (p["segment"] <= end[k])
        mine = (p["segment"][joined] >= beg[k]) & (p["segment"][joined] <= end[k])
        yield k, p, inside, joined[mine], flag[mine], ph_h[mine]


def test_land_segments_name_only_atl03_segments_that_exist(granules):
    # Issue 42: the last land segment's segment_id_end named the ATL03 segment one past the
    # track's last (280 m: segments 1..14, and the third land segment ended at 15).
    atl03, atl08 = granules
    for beam in BEAMS:
        ids = set(dataset(atl03[beam], "geolocation/segment_id", "i4").tolist())
        land = atl08[f"{beam}/land_segments"]
        for name in ("segment_id_beg", "segment_id_end"):
            named = set(dataset(land, name, "i4").tolist())
            assert named <= ids, (beam, name, sorted(named - ids))


def test_land_segments_read_as_spacelidar_reads_them(granules):
    _, atl08 = granules
    for beam in BEAMS:
        land = atl08[f"{beam}/land_segments"]
        n = len(dataset(land, "longitude", "f4"))
        assert n == 3  # 280 m in 100 m segments
        dataset(land, "latitude", "f4")
        dataset(land, "delta_time", "f8")
        for name in ("terrain/h_te_mean", "terrain/h_te_median", "terrain/h_te_uncertainty",
                     "canopy/h_mean_canopy_abs", "canopy/h_canopy_uncertainty", "snr", "dem_h",
                     "terrain/h_te_best_fit", "canopy/h_canopy", "canopy/canopy_openness",
                     "terrain/terrain_slope", "canopy/h_mean_canopy"):
            assert len(dataset(land, name, "f4")) == n, name
        for name in ("layer_flag", "msw_flag", "sat_flag", "ph_removal_flag"):
            assert len(dataset(land, name, "i1")) == n, name
        assert len(dataset(land, "night_flag", "i4")) == n  # int32 in real ATL08 (issue 38)
        terrain_flg = dataset(land, "terrain_flg", "i4")
        # Julia's Bool() takes 0 and 1 only.
        for flags in (terrain_flg, land["ph_removal_flag"][()], land["layer_flag"][()]):
            assert set(np.unique(flags)) <= {0, 1}
        fill = np.float32(3.4028235e38)
        h_te = land["terrain/h_te_best_fit"][()]
        assert np.array_equal(terrain_flg == 1, h_te == fill)
        assert land["terrain/h_te_mean"].attrs["_FillValue"] == fill
        assert np.all(land["canopy/h_canopy_uncertainty"][()] == fill)
        assert land["sat_flag"].attrs["_FillValue"] == 127
        # The sun is up: night_flag 0, as solar_elevation says.
        sun = land["solar_elevation"][()]
        assert np.array_equal(land["night_flag"][()], (sun < 0).astype(np.int32))
        assert np.all(land["night_flag"][()] == 0)
        for name in ("h_canopy", "canopy_openness", "h_te_mean"):
            path = "canopy/" + name if name != "h_te_mean" else "terrain/" + name
            assert land[path].attrs["contentType"] in (b"modelResult", "modelResult")


def test_land_segments_are_their_photons_statistics(granules):
    atl03, atl08 = granules
    checked = 0
    for beam in BEAMS:
        land = atl08[f"{beam}/land_segments"]
        for k, p, inside, joined, flag, ph_h in segment_photons(atl03, atl08, beam):
            ground = joined[flag == 1]
            canopy = flag >= 2
            assert land["terrain/n_te_photons"][k] == len(ground)
            assert land["canopy/n_ca_photons"][k] == np.sum(flag == 2)
            assert land["canopy/n_toc_photons"][k] == np.sum(flag == 3)
            noise = inside.sum() - len(joined)
            assert land["snr"][k] == pytest.approx(len(joined) / noise, rel=1e-6)
            if len(ground) < 5:
                continue
            h = p["h"][ground].astype(np.float64)
            x = p["along"][ground].astype(np.float64)
            t = land["terrain"]
            assert t["h_te_mean"][k] == pytest.approx(h.mean(), abs=2e-3)
            assert t["h_te_median"][k] == pytest.approx(np.median(h), abs=2e-3)
            assert t["h_te_min"][k] == pytest.approx(h.min(), abs=2e-3)
            assert t["h_te_max"][k] == pytest.approx(h.max(), abs=2e-3)
            slope, intercept = np.polyfit(x, h, 1)
            assert t["terrain_slope"][k] == pytest.approx(slope, abs=1e-4)
            residual = h - (slope * x + intercept)
            sem = np.sqrt(np.sum(residual ** 2) / (len(h) - 2)) / np.sqrt(len(h))
            assert t["h_te_uncertainty"][k] == pytest.approx(sem, rel=1e-3, abs=1e-4)
            # The plane's own slope along the track, up to the ground photons' scatter.
            assert abs(abs(t["terrain_slope"][k]) - np.tan(np.radians(SLOPE_DEG))) < 0.01
            # The mean of the ground photons against the plane under the segment's shots.
            # dem_h: the plane at the shot nearest the segment's centre.
            centre = min(100.0 * k + 50.0, 399 * 0.7)
            assert abs(land["dem_h"][k] - plane_height(centre, beam)) < 0.05
            c = land["canopy"]
            if np.isfinite(c["h_canopy"][k]) and c["h_canopy"][k] < 1e38:
                assert c["h_canopy"][k] == pytest.approx(np.percentile(ph_h[canopy], 98),
                                                         abs=2e-3)
                assert c["h_mean_canopy"][k] == pytest.approx(ph_h[canopy].mean(), abs=2e-3)
                assert c["canopy_openness"][k] == pytest.approx(ph_h[canopy].std(ddof=1),
                                                                abs=2e-3)
                for name, value in (("h_min_canopy", ph_h[canopy].min()),
                                    ("h_median_canopy", np.median(ph_h[canopy])),
                                    ("h_max_canopy", ph_h[canopy].max())):
                    assert c[name][k] == pytest.approx(value, abs=2e-3), name
                metrics = dataset(c, "canopy_h_metrics", "f4", ndim=2)
                assert metrics.shape == (len(land["longitude"]), 18)
                np.testing.assert_allclose(
                    metrics[k], np.percentile(ph_h[canopy], np.arange(10, 96, 5)), atol=2e-3)
                abs_h = p["h"][joined[canopy]].astype(np.float64)
                assert c["h_mean_canopy_abs"][k] == pytest.approx(abs_h.mean(), abs=2e-3)
            checked += 1
    assert checked >= 4


def test_20m_sub_segments_read_as_spacelidar_highres_reads_them(granules):
    """SpaceLiDAR's points(highres=true): land_segments/{latitude_20m, longitude_20m},
    terrain/{h_te_best_fit_20m, subset_te_flag}, canopy/{h_canopy_20m, subset_can_flag}, each
    segments x 5, float32 and int8; the five are the ATL03 20 m segments of the 100 m one."""
    atl03, atl08 = granules
    checked = 0
    for beam in BEAMS:
        land = atl08[f"{beam}/land_segments"]
        n = len(land["longitude"])
        lat = dataset(land, "latitude_20m", "f4", ndim=2)
        dataset(land, "longitude_20m", "f4", ndim=2)
        ground = dataset(land, "terrain/h_te_best_fit_20m", "f4", ndim=2)
        canopy = dataset(land, "canopy/h_canopy_20m", "f4", ndim=2)
        for name in ("terrain/subset_te_flag", "canopy/subset_can_flag"):
            assert dataset(land, name, "i1", ndim=2).shape == (n, 5)
        assert lat.shape == ground.shape == canopy.shape == (n, 5)
        fill = np.float32(3.4028235e38)
        # The middle 20 m's centre is the 100 m segment's: the same fitted ground.
        best = land["terrain/h_te_best_fit"][()]
        both = (best != fill) & (ground[:, 2] != fill)
        assert both.sum() >= 2
        assert np.array_equal(best[both], ground[both, 2])
        for k, p, inside, joined, flag, ph_h in segment_photons(atl03, atl08, beam):
            first = land["segment_id_beg"][k]
            for j in range(5):
                mine = p["segment"][joined] == first + j
                # The fitted ground under the photons of the 20 m (h_ph - ph_h at their shots)
                # spans the ground at its centre.
                under = p["h"][joined[mine]].astype(np.float64) - ph_h[mine]
                if ground[k, j] != fill:
                    assert under.min() - 0.05 <= ground[k, j] <= under.max() + 0.05
                # Its photons lie about its latitude, within the 20 m (2e-4 degrees).
                here = p["segment"] == first + j
                if here.any() and lat[k, j] != fill:
                    assert abs(lat[k, j] - np.median(p["lat"][here])) < 2e-4
                tall = mine & (flag >= 2)
                if canopy[k, j] != fill:
                    assert tall.sum() >= 5
                    assert canopy[k, j] == pytest.approx(np.percentile(ph_h[tall], 98), abs=2e-3)
                    checked += 1
                else:
                    assert tall.sum() < 5
    assert checked >= 10


# ICESat2VegR's ATL03_seg_metadata_dt default `attributes` (R/ATL03_seg_metadata_dt.R), each read
# at ATL03.seg.map's geolocation/<name>, in its order; it takes surf_type out and adds
# reference_photon_lon and reference_photon_lat; h_ph it derives from reference_photon_index,
# ph_index_beg and heights/h_ph. Every column must have one value a segment (a data.table's).
SEG_METADATA_DEFAULT = [
    "altitude_sc", "bounce_time_offset", "delta_time", "full_sat_fract", "near_sat_fract",
    "neutat_delay_derivative", "neutat_delay_total", "neutat_ht", "ph_index_beg", "pitch",
    "podppd_flag", "range_bias_corr", "ref_azimuth", "ref_elev", "reference_photon_index", "roll",
    "segment_dist_x", "segment_id", "segment_length", "segment_ph_cnt", "sigma_across",
    "sigma_along", "sigma_h", "sigma_lat", "sigma_lon", "solar_azimuth", "solar_elevation",
    "tx_pulse_energy", "tx_pulse_skew_est", "tx_pulse_width_lower", "tx_pulse_width_upper", "yaw",
    "reference_photon_lon", "reference_photon_lat"]
ATLAS_STRONG_J, ATLAS_WEAK_J = 175e-6, 45e-6  # ATLAS's pulse energies (the preset's ratio)


def test_atl03_segments_read_as_icesat2vegr_seg_metadata_reads_them(granules):
    atl03, _ = granules
    for beam in BEAMS:
        g = atl03[beam]
        n = len(g["geolocation/segment_id"])
        columns = {}
        for name in SEG_METADATA_DEFAULT:
            d = g["geolocation/" + name]
            assert d.shape == (n,), f"{beam}/geolocation/{name}: {d.shape}, {n} segments"
            assert "_FillValue" in d.attrs or name in ("segment_id", "delta_time",
                                                       "segment_dist_x", "segment_length",
                                                       "reference_photon_lat",
                                                       "reference_photon_lon"), name
            columns[name] = d[()]
        # h_ph: heights/h_ph at ph_index_beg + reference_photon_index - 1 (1-based), NA where
        # reference_photon_index is 0.
        ref = columns["reference_photon_index"]
        idx = columns["ph_index_beg"] + ref - 1
        h = g["heights/h_ph"][()]
        assert np.all(idx[ref > 0] >= 1) and np.all(idx[ref > 0] <= len(h))
        # The platform's numbers against the pass's own: 496 km up, the beam's energy, the range
        # as the spacecraft's height over the ground (3.3 km across it adds under 12 m), c.
        for name in ("altitude_sc",):
            assert columns[name].dtype == np.float64
        for name in SEG_METADATA_DEFAULT:
            if name not in ("altitude_sc", "delta_time", "ph_index_beg", "podppd_flag",
                            "reference_photon_index", "segment_dist_x", "segment_id",
                            "segment_length", "segment_ph_cnt", "reference_photon_lon",
                            "reference_photon_lat"):
                assert columns[name].dtype == np.float32, name
        assert columns["podppd_flag"].dtype == np.int8
        np.testing.assert_allclose(columns["altitude_sc"], 496000.0, atol=1.0)
        energy = ATLAS_STRONG_J if STRONG[beam] else ATLAS_WEAK_J
        np.testing.assert_allclose(columns["tx_pulse_energy"], energy, rtol=1e-6)
        ground = g["geophys_corr/dem_h"][()].astype(np.float64)
        one_way_s = columns["bounce_time_offset"].astype(np.float64)
        assert np.all((one_way_s * 299792458.0 - (496000.0 - ground) >= -1.0)
                      & (one_way_s * 299792458.0 - (496000.0 - ground) <= 12.0))
        # ref_elev: the spacecraft at most 3.4 km across from 496 km up, within 0.4 degrees of
        # the zenith.
        assert np.all(np.abs(columns["ref_elev"] - np.pi / 2) < np.radians(0.4))
        # By 19:30 UTC on 21 June at 118.2 W the sun stands south-east (local noon 19:52).
        assert np.all((columns["solar_azimuth"] > 90) & (columns["solar_azimuth"] < 180))
        for name in ("pitch", "roll", "yaw", "sigma_along", "sigma_across", "sigma_lat",
                     "sigma_lon", "tx_pulse_skew_est", "range_bias_corr"):
            assert np.all(columns[name] == 0), name
        fill = np.float32(3.4028235e38)
        for name in ("tx_pulse_width_lower", "tx_pulse_width_upper", "full_sat_fract",
                     "near_sat_fract", "neutat_ht"):
            assert np.all(columns[name] == fill), name


def test_land_segments_mode_confidence_and_photon_index(granules):
    """ICESat2VegR's ATL08_seg_attributes_dt and ATL08_h5_clipBox (issue 38):
    terrain/h_te_mode, the mode of the ground photons' heights (float32; glaswave's bins: 0.1 m
    centred on multiples of 0.1 m, as real ATL08's values lie on that grid, the lowest of ties);
    canopy/canopy_rh_conf, int8 (segments), by the ATL08 dictionary from the shares of canopy and
    ground photons among the classified ones: 0 canopy < 5 %, 1 canopy >= 5 % and ground < 5 %,
    2 both >= 5 %; land_segments/ph_ndx_beg (int64, 1-based) and n_seg_ph (int32), whose slice
    ph_ndx_beg .. ph_ndx_beg + n_seg_ph - 1 of signal_photons/ the clip takes as the segment's
    photons (and whose cumsum it writes back), and segment_watermask, whose length it takes as the
    segments'."""
    atl03, atl08 = granules
    fill = np.float32(3.4028235e38)
    for beam in BEAMS:
        land = atl08[f"{beam}/land_segments"]
        n = len(land["longitude"])
        mode = dataset(land, "terrain/h_te_mode", "f4")
        conf = dataset(land, "canopy/canopy_rh_conf", "i1")
        beg = dataset(land, "ph_ndx_beg", "i8")
        count = dataset(land, "n_seg_ph", "i4")
        assert len(mode) == len(conf) == len(beg) == len(count) == n
        # The clip takes the segments' length from segment_watermask (int32 as real ATL08's
        # atl08_clip.h5; no water here).
        assert np.all(dataset(land, "segment_watermask", "i4") == 0)
        assert len(land["segment_watermask"]) == n
        ph_segment = atl08[f"{beam}/signal_photons/ph_segment_id"][()]
        assert beg[0] == 1 and count.sum() == len(ph_segment)
        np.testing.assert_array_equal(beg, np.cumsum(np.concatenate([[1], count[:-1]])))
        for k, p, inside, joined, flag, ph_h in segment_photons(atl03, atl08, beam):
            mine = ph_segment[beg[k] - 1:beg[k] - 1 + count[k]]
            assert count[k] == len(joined)
            assert np.all((mine >= land["segment_id_beg"][k]) & (mine <= land["segment_id_end"][k]))
            ground = p["h"][joined[flag == 1]].astype(np.float64)
            canopy = np.sum(flag >= 2)
            share_canopy, share_ground = canopy / len(flag), len(ground) / len(flag)
            expected = 0 if share_canopy < 0.05 else (1 if share_ground < 0.05 else 2)
            assert conf[k] == expected, (beam, k)
            if len(ground) == 0:
                assert mode[k] == fill
                continue
            bins, votes = np.unique(np.round(ground / 0.1).astype(np.int64), return_counts=True)
            assert mode[k] == pytest.approx(bins[np.argmax(votes)] * 0.1, abs=1e-3), (beam, k)
            assert ground.min() - 0.05 <= mode[k] <= ground.max() + 0.05
        # A forest of 50 % cover on a plane: canopy and ground in every segment.
        assert set(conf) == {2}


def test_bounding_polygon_is_the_photons_extent(granules):
    """orbit_info/bounding_polygon_{lat1, lon1} (float64 degrees; ICESat2VegR's rgt_extract):
    glaswave's is its photons' latitude-longitude box, closed, counter-clockwise from the
    south-west corner, against the ATL03 photons of every beam."""
    atl03, atl08 = granules
    lat = np.concatenate([atl03[f"{b}/heights/lat_ph"][()] for b in BEAMS])
    lon = np.concatenate([atl03[f"{b}/heights/lon_ph"][()] for b in BEAMS])
    for f in (atl03, atl08):
        plat = dataset(f, "orbit_info/bounding_polygon_lat1", "f8")
        plon = dataset(f, "orbit_info/bounding_polygon_lon1", "f8")
        np.testing.assert_array_equal(plat, [lat.min(), lat.min(), lat.max(), lat.max(),
                                             lat.min()])
        np.testing.assert_array_equal(plon, [lon.min(), lon.max(), lon.max(), lon.min(),
                                             lon.min()])
        # Counter-clockwise: a positive signed (shoelace) area.
        area = 0.5 * np.sum(plon[:-1] * plat[1:] - plon[1:] * plat[:-1])
        assert area > 0


def test_granules_are_chunked_as_real_ones(granules):
    """ATL03's and ATL08's datasets are chunked (10000 rows, gzip): ICESat2VegR's
    ATL03_h5_clipBox copies each dataset's chunk_dims, NA for a contiguous one."""
    for f in granules:
        def check(name, d):
            if isinstance(d, h5py.Dataset) and d.size > 0:
                assert d.chunks is not None, name
                assert d.chunks[0] == min(d.shape[0], 10000), name
                assert d.chunks[1:] == d.shape[1:], name
                assert d.compression == "gzip", name
        f.visititems(check)
