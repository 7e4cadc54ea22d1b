"""The HDF5 granules (PRODUCT.md section 10) opened exactly as the real products' readers open
them, with h5py. The code paths followed, read (never copied) from:

- rGEDI, carlos-alberto-silva/rGEDI R/getLevel1BWF.R: the root's groups matching BEAM\\d{4};
  a shot found by shot_number; its waveform is rxwaveform[start:(start + count - 1)] with
  start = rx_sample_start_index - min(rx_sample_start_index) + 1 (1-based), count =
  rx_sample_count; elevations from geolocation/elevation_bin0 down to elevation_lastbin in
  rx_sample_count steps.
- rGEDI R/getLevel2AM.R: per beam shot_number, lat_lowestmode, lon_lowestmode,
  elev_highestreturn, elev_lowestmode and rh (shot x 101).
- SpaceLiDAR.jl, evetion/SpaceLiDAR.jl src/ICESat/GLAH14.jl, and NSIDC's iceflow,
  nsidc/iceflow src/nsidc/iceflow/data/models.py: Data_40HZ/Geolocation/d_lat, d_lon (0..360),
  Elevation_Surfaces/d_elev, Reflectivity/d_reflctUC, Waveform/i_numPk, Time/i_rec_ndx and
  i_shot_count, Geophysical/d_deltaEllip.
"""
import json
import re
import subprocess

import h5py
import netCDF4
import numpy as np

from conftest import glaswave_binary

# BEAMxxxx/channel in real GEDI L1B files (issue 38, from real granules).
REAL_CHANNEL = {"BEAM0000": 0, "BEAM0001": 0, "BEAM0010": 1, "BEAM0011": 1,
                "BEAM0101": 2, "BEAM0110": 3, "BEAM1000": 4, "BEAM1011": 5}

GEDI_EPOCH_S = 568036800.0  # 2018-01-01T00:00:00Z after the GLAS epoch


def write_gedi_granule(path):
    """A small GEDI L2A granule: a coverage beam and a full-power beam, two shots each."""
    with h5py.File(path, "w") as f:
        for beam, first in (("BEAM0000", 10000000001), ("BEAM0101", 10101000001)):
            f[beam + "/shot_number"] = np.array([first, first + 1], "u8")
            f[beam + "/lat_lowestmode"] = np.array([1.0, 1.0005])
            f[beam + "/lon_lowestmode"] = np.array([2.0, 2.0001])
            f[beam + "/delta_time"] = np.array([4.0e7, 4.0e7 + 0.0083])
            f[beam + "/degrade_flag"] = np.array([0, 2], "u1")


def write_glah14_granule(path):
    """A GLAH14 granule whose first record lacks its first 38 shots."""
    with h5py.File(path, "w") as f:
        f["Data_40HZ/Geolocation/d_lat"] = np.array([1.0, 1.0015, 1.0030])
        f["Data_40HZ/Geolocation/d_lon"] = np.array([2.0, 2.0002, 2.0004])
        f["Data_40HZ/Time/d_UTCTime_40"] = np.array([2.0e8, 2.0e8 + 0.025, 2.0e8 + 0.05])
        f["Data_40HZ/Time/i_rec_ndx"] = np.array([5000, 5000, 5001], "i4")
        f["Data_40HZ/Time/i_shot_count"] = np.array([39, 40, 1], "i2")


def run(tmp_path, name, granule, **output):
    config = {"seed": 1, "sensor": {"preset": "gedi"},
              "simulation": {"rays_per_shot": 300, "max_order": 2},
              "terrain": {"plane": {"origin_lat_deg": 1.0, "origin_lon_deg": 2.0,
                                    "elevation_m": 50.0}},
              "canopy": {"pai": 2.0, "cover": 0.6},
              "track": {"type": "granule", "file": str(granule), "altitude_m": 420000.0},
              "output": {"netcdf": True, "footprints": False, **output}}
    path = tmp_path / (name + ".json")
    path.write_text(json.dumps(config))
    out = tmp_path / name
    subprocess.run([glaswave_binary(), "run", str(path), "--out", str(out), "--quiet"],
                   check=True, capture_output=True)
    return out


def beams(f):
    return [g for g in f.keys() if re.fullmatch(r"BEAM\d{4}", g)]


def test_gedi_l1b_reads_as_rgedi_reads_it(tmp_path):
    granule = tmp_path / "GEDI02_A_small.h5"
    write_gedi_granule(granule)
    out = run(tmp_path, "gedi", granule, gedi_l1b=True, gedi_l2a=True)
    shots = netCDF4.Dataset(out / "shots.nc")
    number = shots["shot_number"][:]
    band = int(np.argmin(np.abs(shots["wavelength"][:] - 1064)))
    rx_W = shots["rx_waveform"][:, band, :]
    with h5py.File(out / "gedi_l1b.h5") as f:
        assert beams(f) == ["BEAM0000", "BEAM0101"]
        seen = 0
        for g in beams(f):
            b = f[g]
            assert b["shot_number"].dtype == np.uint64
            assert b["rx_sample_start_index"].dtype == np.uint64
            assert b["rx_sample_count"].dtype == np.uint16
            assert b["rxwaveform"].dtype == np.float32
            assert b["ancillary/master_time_epoch"][0] == 1198800018.0
            start = b["rx_sample_start_index"][:].astype(np.int64)
            start_n = start - start.min() + 1  # rGEDI: 1-based, from the beam's first
            count = b["rx_sample_count"][:].astype(np.int64)
            for i, shot_number in enumerate(b["shot_number"][:]):
                k = int(np.flatnonzero(number == shot_number)[0])
                # rxwaveform[start_n:(start_n + count - 1)] in R is [start_n - 1, +count) here.
                wave = b["rxwaveform"][start_n[i] - 1:start_n[i] - 1 + count[i]]
                counts_per_W = 1e9  # no digitiser configured: 1 count per nW
                np.testing.assert_allclose(wave, rx_W[k] * counts_per_W, rtol=1e-6, atol=1e-3)
                # rGEDI's elevations: bin0 down to lastbin in rx_sample_count steps.
                bin0 = b["geolocation/elevation_bin0"][i]
                last = b["geolocation/elevation_lastbin"][i]
                z = np.linspace(last, bin0, count[i] + 1)[::-1][1:]
                assert abs(z[0] - shots["elev_bin0"][k]) <= (bin0 - last) / count[i] + 1e-6
                assert b["beam"][i] == int(g[4:], 2)
                # The channel as real L1B files number it (two coverage beams a channel).
                assert b["channel"][i] == REAL_CHANNEL[g]
                assert abs(b["delta_time"][i] + GEDI_EPOCH_S - shots["time"][k]) < 1e-6
                assert np.isfinite(b["geolocation/solar_elevation"][i])
                seen += 1
        assert seen == len(number) == 4
        # Coverage beams carry half the pulse: the same scene gives about half the energy.
        e0 = f["BEAM0000/glaswave_truth/rx_energy_ground"][:] + \
            f["BEAM0000/glaswave_truth/rx_energy_canopy"][:]
        e5 = f["BEAM0101/glaswave_truth/rx_energy_ground"][:] + \
            f["BEAM0101/glaswave_truth/rx_energy_canopy"][:]
        assert 0.3 < e0.sum() / e5.sum() < 0.7


def test_gedi_l2a_reads_as_rgedi_reads_it_and_is_a_granule_track(tmp_path):
    granule = tmp_path / "GEDI02_A_small.h5"
    write_gedi_granule(granule)
    out = run(tmp_path, "gedi", granule, gedi_l2a=True)
    shots = netCDF4.Dataset(out / "shots.nc")
    number = shots["shot_number"][:]
    band = int(np.argmin(np.abs(shots["wavelength"][:] - 1064)))
    with h5py.File(out / "gedi_l2a.h5") as f:
        for g in beams(f):
            b = f[g]
            assert b["rh"].shape == (len(b["shot_number"]), 101)
            for i, shot_number in enumerate(b["shot_number"][:]):
                k = int(np.flatnonzero(number == shot_number)[0])
                np.testing.assert_allclose(b["rh"][i], shots["rh"][k, band, :], rtol=1e-6,
                                           atol=1e-4)
                np.testing.assert_allclose(b["elev_lowestmode"][i],
                                           shots["ground_elev_est"][k, band], atol=1e-3)
                np.testing.assert_allclose(b["elev_highestreturn"][i],
                                           shots["sig_begin_m"][k, band], atol=1e-3)
                assert b["degrade_flag"][i] == [0, 2][i]
    # The round trip: the simulated L2A as a granule track gives the same footprints.
    again = netCDF4.Dataset(run(tmp_path, "again", out / "gedi_l2a.h5") / "shots.nc")
    assert list(again["shot_number"][:]) == list(number)
    np.testing.assert_allclose(again["lat"][:], shots["lat"][:], atol=1e-6)
    np.testing.assert_allclose(again["lon"][:], shots["lon"][:], atol=1e-6)
    np.testing.assert_allclose(again["time"][:], shots["time"][:], atol=1e-6)


def chunked_as_real_granules(f):
    """Every non-empty dataset chunked, min(rows, 10000) rows a chunk: rGEDI's and
    ICESat2VegR's clips copy each dataset's chunk_dims (NA for a contiguous one)."""
    def check(name, d):
        if isinstance(d, h5py.Dataset) and d.size > 0:
            assert d.chunks is not None, name
            assert d.chunks[0] == min(d.shape[0], 10000) and d.chunks[1:] == d.shape[1:], name
    f.visititems(check)


def test_gedi_l2a_has_what_rgedi_clip_level2a_reads(tmp_path):
    """rGEDI's clipLevel2A (getSpatialData2A): BEAMxxxx/ancillary/l2a_alg_count, then for each
    group j up to it geolocation/{lat,lon}_{highest,lowest}return_aj (float64), and
    elev_highestreturn_aj's length; then it copies every dataset with its chunk_dims.
    glaswave runs one setting group, the beam group's own: the count is 1 (real L2A: 6)."""
    granule = tmp_path / "GEDI02_A_small.h5"
    write_gedi_granule(granule)
    out = run(tmp_path, "gedi", granule, gedi_l1b=True, gedi_l2a=True)
    shots = netCDF4.Dataset(out / "shots.nc")
    number = shots["shot_number"][:]
    band = int(np.argmin(np.abs(shots["wavelength"][:] - 1064)))
    with h5py.File(out / "gedi_l2a.h5") as f:
        chunked_as_real_granules(f)
        for g in beams(f):
            b = f[g]
            count = b["ancillary/l2a_alg_count"]
            assert count.dtype == np.uint8 and list(count[()]) == [1]
            n = len(b["shot_number"])
            geo = {}
            for name in ("lat_highestreturn", "lon_highestreturn", "lat_lowestreturn",
                         "lon_lowestreturn"):
                geo[name] = b[f"geolocation/{name}_a1"]
                assert geo[name].dtype == np.float64 and geo[name].shape == (n,), name
            for name in ("elev_highestreturn", "elev_lowestreturn"):
                assert b[f"geolocation/{name}_a1"].dtype == np.float32
            np.testing.assert_array_equal(geo["lat_highestreturn"], b["lat_highestreturn"])
            np.testing.assert_array_equal(geo["lon_highestreturn"], b["lon_highestreturn"])
            np.testing.assert_array_equal(b["geolocation/elev_highestreturn_a1"],
                                          b["elev_highestreturn"])
            for i, shot_number in enumerate(b["shot_number"][:]):
                k = int(np.flatnonzero(number == shot_number)[0])
                # The lowest return is the signal's end, below the lowest mode's centre.
                low = b["geolocation/elev_lowestreturn_a1"][i]
                np.testing.assert_allclose(low, shots["sig_end_m"][k, band], atol=1e-3)
                assert low < b["elev_lowestmode"][i]
                # Its point lies on the beam near the footprint centre (a 25 m footprint).
                assert abs(geo["lat_lowestreturn"][i] - shots["lat"][k]) < 1e-3
    with h5py.File(out / "gedi_l1b.h5") as f:
        chunked_as_real_granules(f)
        assert f[beams(f)[0] + "/rx_sample_start_index"].chunks is not None


def test_glah14_keeps_the_true_record_and_shot_count(tmp_path):
    granule = tmp_path / "GLAH14_small.H5"
    write_glah14_granule(granule)
    out = run(tmp_path, "glas", granule, glah14=True, glah01=True)
    shots = netCDF4.Dataset(out / "shots.nc")
    assert list(shots["shot_number"][:]) == [5000 * 40 + 38, 5000 * 40 + 39, 5001 * 40]
    with h5py.File(out / "glah14.h5") as f:
        d = f["Data_40HZ"]
        assert list(d["Time/i_rec_ndx"][:]) == [5000, 5000, 5001]
        assert list(d["Time/i_shot_count"][:]) == [39, 40, 1]
        np.testing.assert_allclose(d["Geolocation/d_lon"][:], [2.0, 2.0002, 2.0004], atol=1e-6)
        np.testing.assert_allclose(d["Time/d_UTCTime_40"][:], shots["time"][:])
        # WGS84 heights by default; d_deltaEllip is WGS84 less T/P height, about -0.7 m here.
        assert np.all(np.abs(d["Geophysical/d_deltaEllip"][:] + 0.7) < 0.05)
        # GLA14's reflectivity is not corrected for the atmosphere.
        band = int(np.argmin(np.abs(shots["wavelength"][:] - 1064)))
        bands = json.loads(shots.getncattr("config"))["sensor"]["bands"]
        transmission = bands[band]["atmos_transmission_roundtrip"]
        np.testing.assert_allclose(d["Reflectivity/d_reflctUC"][:],
                                   shots["reflectance"][:, band] * transmission, rtol=1e-12)
        assert d["Waveform/d_Gamp"].shape == (3, 6)
        elev = d["Elevation_Surfaces/d_elev"][:]
    topex = run(tmp_path, "topex", granule, glah14=True, glas_ellipsoid="topex")
    with h5py.File(topex / "glah14.h5") as f:
        d = f["Data_40HZ"]
        np.testing.assert_allclose(d["Elevation_Surfaces/d_elev"][:],
                                   elev - d["Geophysical/d_deltaEllip"][:], atol=1e-6)
    with h5py.File(out / "glah01.h5") as f:
        assert f["Data_40HZ/Waveform/RecWaveform/r_rng_wf"].shape[0] == 3
        assert list(f["Data_40HZ/Time/i_shot_count"][:]) == [39, 40, 1]


def test_gedi_l1b_has_one_dataset_per_sample_index_as_rgedi_clip_level1b_needs(tmp_path):
    """rGEDI's clipLevel1B (clipByMask1B) walks every group under a beam; a 1-D dataset whose
    length is the beam's sum of rx_sample_count or tx_sample_count (or a multiple of its shots)
    is taken for a waveform: it writes BEAMxxxx/{rx,tx}_sample_start_index for it, by the name's
    first two letters, and fails on a second one ("already exists"). So a beam holds one such
    dataset per prefix, rxwaveform and txwaveform; the truth's waveform parts lie outside the
    beams, in glaswave_truth/BEAMxxxx/, indexed as rxwaveform and summing to it."""
    granule = tmp_path / "GEDI02_A_small.h5"
    write_gedi_granule(granule)
    out = run(tmp_path, "gedi", granule, gedi_l1b=True)
    with h5py.File(out / "gedi_l1b.h5") as f:
        for g in beams(f):
            b = f[g]
            shots = len(b["shot_number"])
            sizes = {int(b["rx_sample_count"][:].sum()), int(b["tx_sample_count"][:].sum())}
            taken = {"rx": [], "tx": []}

            def visit(name, d):
                if not isinstance(d, h5py.Dataset) or d.ndim != 1 or d.shape[0] in (1, shots):
                    return
                if name.endswith("_sample_start_index"):
                    return
                if d.shape[0] in sizes or d.shape[0] % shots == 0:
                    taken["rx" if name.split("/")[-1][:2] == "rx" else "tx"].append(name)
            b.visititems(visit)
            assert taken == {"rx": ["rxwaveform"], "tx": ["txwaveform"]}, taken
            # The truth's parts: the beam's indices; no detector is configured (no noise), so
            # the parts last scattered by vegetation and by the ground sum to rxwaveform.
            canopy = f[f"glaswave_truth/{g}/rxwaveform_canopy"][:]
            ground = f[f"glaswave_truth/{g}/rxwaveform_ground"][:]
            assert canopy.shape == ground.shape == b["rxwaveform"].shape
            np.testing.assert_allclose(canopy + ground, b["rxwaveform"][:], rtol=1e-5,
                                       atol=1e-3)
