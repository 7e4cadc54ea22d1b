"""glah01.h5 and glah14.h5 opened as the GLAS readers open a real granule (issue 38): the paths
each function opens, in its order, with the dtype and shape it expects, read (never copied)
from:

- carbonplan/trace, carbonplan_trace/v1/glas_extract.py: read_dimensions (Time/i_rec_ndx,
  i_shot_count), extract_GLAH14_data's name_map (one value a shot, values above 1e30 missing)
  and gaussian_fit_params (shot x 6, whose buffer it reinterprets as float: float64), and
  extract_GLAH01_data's name_map, r_tx_wf, r_rng_wf and the ANCILLARY_DATA group's attributes
  tx_wf_sample_location_table and rec_wf_sample_location_table (row i_rec_wf_location_index - 1,
  127 missing); glas_preprocess.py's distance of a received sample from the spacecraft,
  (table + i_RespEndTime - i_time_txWfPk) x 1e-9 x c / 2.
- evetion/SpaceLiDAR.jl, src/ICESat/GLAH14.jl: points() without a bbox asserts Vector{Float64}
  for d_lon, d_lat, d_elev, d_satElevCorr, DS_UTCTime_40, d_reflctUC, d_DEM_elv, Vector{Int8}
  for elev_use_flg, elv_cloud_flg, sat_corr_flg, sigma_att_flg and Vector{Int32} for i_gval_rcv,
  i_numPk; it drops shots whose d_lon, d_lat, d_elev or d_satElevCorr is GLAS's fill
  1.7976931348623157e308, and its quality is elev_use_flg == 0, sigma_att_flg == 0,
  i_numPk == 1 and d_satElevCorr < 3 (Smith et al. 2020).

The numbers checked are independent of the writer: the spacecraft-to-footprint distance from
shots.nc's positions on WGS84 (a flat bare plane, so the return's centre is the footprint's),
the detector's configured background and noise, a Gaussian pulse's skewness (0) and its one peak.
"""
import json
import subprocess

import h5py
import netCDF4
import numpy as np

from conftest import glaswave_binary

GLAS_FILL = 1.7976931348623157e308
NAN_THRESHOLD = 1e30  # carbonplan's
C_M_S = 299792458.0
BACKGROUND_W, NOISE_W, GAIN = 2e-9, 3e-10, 13.0

GLAH14_CARBONPLAN = [
    "Time/d_UTCTime_40", "Geolocation/d_lat", "Geolocation/d_lon", "Elevation_Surfaces/d_elev",
    "Elevation_Corrections/d_satElevCorr", "Geophysical/d_DEM_elv", "Geophysical/d_deltaEllip",
    "Geophysical/d_gdHt", "Elevation_Surfaces/d_refRng", "Elevation_Offsets/d_SigBegOff",
    "Elevation_Offsets/d_SigEndOff", "Elevation_Offsets/d_ldRngOff", "Waveform/i_numPk",
    "Waveform/d_skew1", "Waveform/i_nPeaks1"]
GLAH14_CARBONPLAN_SIX = ["Elevation_Offsets/d_gpCntRngOff", "Waveform/d_Gamp",
                         "Waveform/d_Gsigma"]
GLAH01_CARBONPLAN = [
    "Waveform/Characteristics/d_4nsBgMean", "Waveform/Characteristics/d_4nsBgSDEV",
    "Waveform/RecWaveform/i_rec_wf_location_index", "Waveform/RecWaveform/i_RespEndTime",
    "Waveform/TransmitWaveform/i_time_txWfPk"]
# SpaceLiDAR.jl's points(), in its order, with the element type it asserts.
GLAH14_SPACELIDAR = [
    ("Geolocation/d_lon", np.float64), ("Geolocation/d_lat", np.float64),
    ("Elevation_Surfaces/d_elev", np.float64), ("Elevation_Corrections/d_satElevCorr", np.float64),
    ("DS_UTCTime_40", np.float64), ("Quality/elev_use_flg", np.int8),
    ("Elevation_Flags/elv_cloud_flg", np.int8), ("Quality/sat_corr_flg", np.int8),
    ("Quality/sigma_att_flg", np.int8), ("Reflectivity/d_reflctUC", np.float64),
    ("Waveform/i_gval_rcv", np.int32), ("Waveform/i_numPk", np.int32),
    ("Geophysical/d_DEM_elv", np.float64)]


def run_glas(tmp_path, atmosphere=None):
    """Four GLAS shots at nadir over a flat bare plane, the detector adding a known noise
    (through `atmosphere`, a section or preset name, where given)."""
    config = {
        "seed": 5, "sensor": {"preset": "glas"},
        "simulation": {"rays_per_shot": 400, "max_order": 2},
        "terrain": {"plane": {"origin_lat_deg": 40.0, "origin_lon_deg": -105.0,
                              "elevation_m": 1600.0}, "soil_reflectance": 0.3},
        "detector": {"enabled": True, "background_W": BACKGROUND_W, "noise_rms_W": NOISE_W,
                     "gain": GAIN},
        "track": {"type": "pass", "start_lat_deg": 40.0, "start_lon_deg": -105.0,
                  "heading_deg": 10.0, "shots": 4, "spacing_m": 172.0},
        "output": {"netcdf": True, "footprints": False, "glah01": True, "glah14": True},
    }
    if atmosphere is not None:
        config["atmosphere"] = atmosphere
    path = tmp_path / "glas.json"
    path.write_text(json.dumps(config))
    out = tmp_path / "glas"
    subprocess.run([glaswave_binary(), "run", str(path), "--out", str(out), "--quiet"],
                   check=True, capture_output=True)
    return out


def ecef(lat_deg, lon_deg, h_m):
    a, e2 = 6378137.0, 6.69437999014e-3
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    n = a / np.sqrt(1 - e2 * np.sin(lat) ** 2)
    return np.stack([(n + h_m) * np.cos(lat) * np.cos(lon), (n + h_m) * np.cos(lat) * np.sin(lon),
                     (n * (1 - e2) + h_m) * np.sin(lat)], axis=-1)


def spacecraft_range(shots):
    sc = ecef(shots["sc_lat"][:], shots["sc_lon"][:], shots["sc_alt"][:])
    ground = ecef(shots["lat"][:], shots["lon"][:], shots["elev"][:])
    return np.linalg.norm(sc - ground, axis=1)


def carbonplan_1d(f, path, n):
    values = f["Data_40HZ/" + path][:]
    assert values.shape == (n,), path
    values = values * 1.0 if (values > NAN_THRESHOLD).sum() > 0 else values
    if values.dtype.kind == "f":
        values[values > NAN_THRESHOLD] = np.nan
    return values


def test_glas_granules_read_as_the_glas_readers_read_them(tmp_path):
    out = run_glas(tmp_path)
    shots = netCDF4.Dataset(out / "shots.nc")
    n = len(shots["shot_number"][:])
    distance = spacecraft_range(shots)
    with h5py.File(out / "glah14.h5") as f:
        # carbonplan's extract_GLAH14_data.
        record = f["Data_40HZ/Time/i_rec_ndx"][:]
        count = f["Data_40HZ/Time/i_shot_count"][:]
        assert record.shape == count.shape == (n,)
        g = {p: carbonplan_1d(f, p, n) for p in GLAH14_CARBONPLAN}
        for p in GLAH14_CARBONPLAN_SIX:
            six = f["Data_40HZ/" + p]
            assert six.shape == (n, 6) and six.dtype == np.float64, p
        # Its centroid distance d_refRng + d_ldRngOff is the range to the flat ground's return.
        np.testing.assert_allclose(g["Elevation_Surfaces/d_refRng"] +
                                   g["Elevation_Offsets/d_ldRngOff"], distance, atol=0.3)
        # The last gate lies below the ground: its range is longer.
        assert np.all(g["Elevation_Surfaces/d_refRng"] > distance + 10)
        assert np.all(g["Elevation_Corrections/d_satElevCorr"] == 0)
        assert np.all(np.isnan(g["Geophysical/d_gdHt"]))  # no geoid: fill, read as missing
        # One Gaussian return: one smoothed peak, and a skewness near a Gaussian's 0.
        assert list(g["Waveform/i_nPeaks1"]) == [1] * n
        assert np.all(np.abs(g["Waveform/d_skew1"]) < 0.5), g["Waveform/d_skew1"]
        # SpaceLiDAR.jl's points(): exact element types, no shot dropped, all of high quality.
        read = {}
        for p, dtype in GLAH14_SPACELIDAR:
            read[p] = f["Data_40HZ/" + p][:]
            assert read[p].dtype == dtype and read[p].shape == (n,), p
        valid = ((read["Geolocation/d_lon"] != GLAS_FILL) & (read["Geolocation/d_lat"] != GLAS_FILL)
                 & (read["Elevation_Surfaces/d_elev"] != GLAS_FILL)
                 & (read["Elevation_Corrections/d_satElevCorr"] != GLAS_FILL))
        assert valid.all()
        quality = ((read["Quality/elev_use_flg"] == 0) & (read["Quality/sigma_att_flg"] == 0)
                   & (read["Waveform/i_numPk"] == 1)
                   & (read["Elevation_Corrections/d_satElevCorr"] < 3))
        assert quality.all()
        assert list(read["Elevation_Flags/elv_cloud_flg"]) == [0] * n
        assert list(read["Waveform/i_gval_rcv"]) == [int(GAIN)] * n
        np.testing.assert_array_equal(read["DS_UTCTime_40"], shots["time"][:])
    with h5py.File(out / "glah01.h5") as f:
        # carbonplan's extract_GLAH01_data.
        assert f["Data_40HZ/Time/i_rec_ndx"].shape == (n,)
        g = {p: carbonplan_1d(f, p, n) for p in GLAH01_CARBONPLAN}
        tx = f["Data_40HZ/Waveform/TransmitWaveform/r_tx_wf"][:]
        rx = f["Data_40HZ/Waveform/RecWaveform/r_rng_wf"][:]
        tx_loc = f["ANCILLARY_DATA"].attrs["tx_wf_sample_location_table"]
        rec_loc = f["ANCILLARY_DATA"].attrs["rec_wf_sample_location_table"]
        assert tx_loc.shape == (tx.shape[1],) and rec_loc.ndim == 2
        assert rec_loc.shape[1] == rx.shape[1]
        assert g["Waveform/RecWaveform/i_rec_wf_location_index"].dtype == np.int8
        # The noise is the detector's (1 count per nW without a digitiser): its mean the
        # background, its sd the detector's noise, within what the bins before the signal allow.
        np.testing.assert_allclose(g["Waveform/Characteristics/d_4nsBgMean"], BACKGROUND_W * 1e9,
                                   atol=4 * NOISE_W * 1e9 / np.sqrt(50))
        np.testing.assert_allclose(g["Waveform/Characteristics/d_4nsBgSDEV"], NOISE_W * 1e9,
                                   rtol=0.25)
        index = g["Waveform/RecWaveform/i_rec_wf_location_index"]
        assert np.all(index != 127)
        loc = rec_loc[index.astype(int) - 1]
        dist = ((loc + g["Waveform/RecWaveform/i_RespEndTime"][:, None]
                 - g["Waveform/TransmitWaveform/i_time_txWfPk"][:, None]) * 1e-9 * C_M_S / 2)
        # Each sample's distance is its range: the waveform peaks at the ground's, within a bin
        # (15 cm) and the counts' rounding (7.5 cm); the last sample's is d_refRng.
        peak = dist[np.arange(n), np.argmax(rx, axis=1)]
        np.testing.assert_allclose(peak, distance, atol=0.3)
        with h5py.File(out / "glah14.h5") as g14:
            np.testing.assert_allclose(dist[:, -1], g14["Data_40HZ/Elevation_Surfaces/d_refRng"][:],
                                       atol=0.08)
        np.testing.assert_array_equal(f["Data_40HZ/DS_UTCTime_40"][:], shots["time"][:])


def test_glah14_cloud_flag_is_the_layer_finders(tmp_path):
    """elv_cloud_flg (issue 38): 1 where a layer the atmosphere's layer finder reports lies in
    the column. The `cirrus` preset's layer 9 km above the ellipsoid, over this plane at 1600 m,
    is reported (docs/guide/atmosphere.md; ATL08's layer_flag is 1 for it,
    tests/pipeline/app/atmosphere_flags_test.cpp); without a section the flag stays 0
    (test_glas_granules_read_as_the_glas_readers_read_them)."""
    out = run_glas(tmp_path, atmosphere="cirrus")
    with h5py.File(out / "glah14.h5") as f:
        flag = f["Data_40HZ/Elevation_Flags/elv_cloud_flg"]
        assert flag.dtype == np.int8 and flag.shape == (4,)
        assert list(flag[:]) == [1] * 4
