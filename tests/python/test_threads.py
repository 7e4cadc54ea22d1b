"""The library from several Python threads at once: two threads calling glaswave.run together
(each run writing shots.nc through libnetcdf and HDF5 while the other reads its own back) end
without a crash and give the products of one call; a granule track runs beside other threads
without a fork; and the shot range accepts numpy integers."""

import ctypes
import threading

import numpy as np
import pytest

import glaswave
from conftest import assert_datasets_identical, small_config

ROUNDS = 100


def test_two_threads_run_together_and_give_the_products_of_one_call():
    config = small_config(shots=1, rays=20)
    reference = glaswave.run(config, threads=1)
    failures = []
    start = threading.Barrier(2)

    def runs():
        try:
            for _ in range(ROUNDS):
                start.wait(timeout=60)  # the two runs begin together, round after round
                dataset = glaswave.run(config, threads=1)
                assert_datasets_identical(dataset, reference)
        except Exception as error:  # noqa: BLE001 - reported by the main thread
            failures.append(repr(error))
            start.abort()

    threads = [threading.Thread(target=runs) for _ in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert failures == []


def test_a_run_in_another_thread_keeps_hdf5s_probes_off_stderr(capfd):
    # HDF5 keeps its error printing per thread and libnetcdf turns it off in the first thread
    # only: shots.nc read back in any other printed a dozen HDF5-DIAG lines a run.
    config = small_config(shots=1, rays=20)
    glaswave.run(config, threads=1)  # libnetcdf starts in this thread
    thread = threading.Thread(target=lambda: glaswave.run(config, threads=1))
    thread.start()
    thread.join()
    assert "HDF5-DIAG" not in capfd.readouterr().err


def test_numpy_integers_select_shots_and_too_large_a_shot_is_a_value_error():
    config = small_config(shots=3, rays=20)
    part = glaswave.run(config, shots=(np.int64(1), np.int64(3)))
    assert list(part["shot_number"].values) == [1, 2]
    with pytest.raises(ValueError, match=r"shot number 18446744073709551616 is too large"):
        glaswave.run(config, shots=(0, 2**64))
    with pytest.raises(glaswave.ConfigError, match=r"integer shot numbers >= 0"):
        glaswave.run(config, shots=(0.0, 2))


def test_a_config_path_with_a_nul_byte_is_refused():
    with pytest.raises(glaswave.ConfigError, match="NUL byte"):
        glaswave.check("track.json\0.ignored")


def test_the_users_own_netcdf_reads_share_the_engines_lock(tmp_path):
    # The user's xarray reads in one thread while glaswave runs in another: under
    # glaswave.hdf5_lock() (Debian's HDF5 is not thread-safe), 20 reads during 20 runs.
    import xarray
    config = small_config(shots=1, rays=20)
    reference = glaswave.run(config, threads=1)
    theirs = tmp_path / "theirs.nc"
    reference.to_netcdf(theirs)
    failures = []

    def runs():
        try:
            for _ in range(20):
                assert_datasets_identical(glaswave.run(config, threads=1), reference)
        except Exception as error:  # noqa: BLE001
            failures.append(repr(error))

    thread = threading.Thread(target=runs)
    thread.start()
    for _ in range(20):
        with glaswave.hdf5_lock():
            read = xarray.load_dataset(theirs)
        assert (read["shot_number"].values == reference["shot_number"].values).all()
    thread.join()
    assert failures == []


def test_a_granule_track_beside_other_threads_runs_without_a_fork(tmp_path):
    # Issue 42: the granule reader forked, and the child hung in PROJ's fork handler while
    # another thread held PROJ's lock. A fork handler registered through libc counts every fork
    # of this process (a library's fork() runs it; posix_spawn runs none): none may come while
    # the granule track runs beside two pass runs, round after round. The child also kept a copy
    # of the other runs' shots.nc with HDF5's lock on it, so that reading it back failed
    # ("NetCDF: HDF error", 4 tries of 6 under load, and two granule tracks in every try).
    import h5py
    granule = tmp_path / "GEDI02_A.h5"
    with h5py.File(granule, "w") as f:
        f["BEAM0101/shot_number"] = np.array([10101000001, 10101000002], "u8")
        f["BEAM0101/lat_lowestmode"] = np.array([1.0, 1.0005])
        f["BEAM0101/lon_lowestmode"] = np.array([2.0, 2.0001])
        f["BEAM0101/delta_time"] = np.array([4.0e7, 4.0e7 + 0.0083])
    track = {"seed": 1, "sensor": {"preset": "gedi"},
             "simulation": {"rays_per_shot": 20, "max_order": 1},
             "terrain": {"plane": {"origin_lat_deg": 1.0, "origin_lon_deg": 2.0,
                                   "elevation_m": 50.0}},
             "track": {"type": "granule", "file": str(granule), "altitude_m": 420000.0}}
    passes = small_config(shots=1, rays=20)
    forks = []
    counting = threading.Event()
    handler = ctypes.CFUNCTYPE(None)(lambda: forks.append(1) if counting.is_set() else None)
    libc = ctypes.CDLL(None)
    # pthread_atfork itself is a static wrapper of glibc's around this exported function.
    assert libc.__register_atfork(handler, None, None, None) == 0
    failures = []
    counting.set()

    def loop(config):
        try:
            for _ in range(10):
                glaswave.run(config, threads=1)
        except Exception as error:  # noqa: BLE001 - reported by the main thread
            failures.append(f"{config['track']['type']} track: {error!r}")

    threads = [threading.Thread(target=loop, args=(c,)) for c in (track, passes, passes)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=300)
    counting.clear()
    assert not any(thread.is_alive() for thread in threads), "a run hung"
    assert failures == []
    assert forks == []
    handler_kept.append(handler)  # a registered handler cannot be removed: it must outlive us


handler_kept = []
