"""glaswave: Monte Carlo simulation of satellite waveform lidar over vegetation and terrain.

    import glaswave
    ds = glaswave.run("forest.json", shots=range(0, 100), overrides={"canopy.pai": 2.0})
    ds.rx_waveform.sel(band=1064)        # an xarray.Dataset, as shots.nc
    glaswave.brf("forest.json")["bands"][0]["albedo"]   # brf.json as a dict
    glaswave.check({"canopy": {"pai": -1}})   # raises glaswave.ConfigError: /canopy/pai: ...

The C++ engine does the work (with the GIL released; Ctrl-C stops it); errors come back as
ConfigError (a bad configuration, a ValueError), InputError (unusable input data, a ValueError)
and RunError (a failure while running, a RuntimeError), each with the message of the command
line's `glaswave: error:` line and the `place` it names.

HDF5 as Debian builds it (under libnetcdf, netCDF4-python, Debian's h5py) is not thread-safe: a
program that reads NetCDF or HDF5 files in one thread (xarray, h5py) while glaswave runs in
another must hold glaswave.hdf5_lock() around its own reads (see hdf5_lock).
"""

import json
import operator
import os
import tempfile
import warnings
from collections.abc import Mapping

from . import _glaswave
from ._glaswave import ConfigError, InputError, RunError

__version__ = _glaswave.__version__
__all__ = ["run", "brf", "check", "hdf5_lock", "ConfigError", "InputError", "RunError",
           "__version__"]


def _config_error(place, reason):
    """A ConfigError as the engine raises it: "place: reason", with both as attributes."""
    error = ConfigError(f"{place}: {reason}" if place else reason)
    error.place, error.reason = place, reason
    return error


def _pointer_child(pointer, key):
    """The JSON pointer of `key` under `pointer`, '~' and '/' escaped (RFC 6901)."""
    return f"{pointer}/" + str(key).replace("~", "~0").replace("/", "~1")


def _check_nesting(value, prefix=""):
    """Refuses, as the engine refuses JSON text, a value nesting deeper than the engine's limit
    or holding itself, before json.dumps recurses into it (a RecursionError, or a crash, there).
    Walked without recursion; the place named is the outermost levels, as the engine names it."""
    limit = _glaswave.max_json_depth
    stack = [(value, prefix, 0, ())]  # (value, its pointer, containers above it, their ids)
    while stack:
        item, pointer, depth, above = stack.pop()
        if isinstance(item, Mapping):
            children = ((_pointer_child(pointer, k), v) for k, v in item.items())
        elif isinstance(item, (list, tuple)):
            children = ((f"{pointer}/{i}", v) for i, v in enumerate(item))
        else:
            continue
        if id(item) in above:
            raise _config_error(pointer, "refers to itself: not a JSON value")
        if depth >= limit:
            outer = "/".join(pointer[len(prefix):].split("/")[:4])
            raise _config_error(f"{prefix}{outer}/...",
                                f"nests deeper than {limit} levels of objects and arrays")
        stack.extend((v, p, depth + 1, above + (id(item),)) for p, v in children)


def _source(config):
    """(path, document, folder) for the engine: a file, or a dict as JSON text whose relative
    paths are taken from the current directory."""
    if isinstance(config, Mapping):
        _check_nesting(config)
        try:
            document = json.dumps(config, allow_nan=False)
        except (TypeError, ValueError) as error:
            raise ConfigError(f"the configuration is not a JSON document: {error}") from None
        return None, document, os.getcwd()
    if isinstance(config, (str, bytes, os.PathLike)):
        path = os.fsdecode(config)
        if "\0" in path:  # the C library would read the file named by the part before it
            raise _config_error(repr(path)[1:-1], "a path must not hold a NUL byte")
        return path, None, os.getcwd()
    raise TypeError(f"config must be a path or a dict, not {type(config).__name__}")


def _assignments(overrides):
    """{"canopy.pai": 2.0} -> ["canopy.pai=2.0"], as `--set` takes them."""
    if overrides is None:
        return []
    if not isinstance(overrides, Mapping):
        raise TypeError(f"overrides must be a dict, not {type(overrides).__name__}")
    assignments = []
    for key, value in overrides.items():
        _check_nesting(value, "/" + str(key).replace(".", "/"))
        try:
            text = json.dumps(value, allow_nan=False)
        except (TypeError, ValueError) as error:
            raise ConfigError(f"overrides[{key!r}]: not a JSON value: {error}") from None
        assignments.append(f"{key}={text}")
    return assignments


_MAX_SHOT = 2**63 - 1  # the engine's shot numbers are 64-bit signed


def _shot_range(shots):
    """None, range(a, b) or (a, b) -> the half-open (first, last) of `--shots A:B`."""
    if shots is None:
        return None, None
    if isinstance(shots, range):
        if shots.step != 1:
            raise ConfigError(f"shots: a range with step 1, got {shots!r}")
        first, last = shots.start, shots.stop
    else:
        try:
            first, last = shots
        except (TypeError, ValueError):
            raise ConfigError(f"shots: a range or (first, last), got {shots!r}") from None
    bounds = []
    for value in (first, last):
        if value is not None:
            # Any integer type (numpy's too, through __index__), not bool nor a float.
            try:
                value = None if isinstance(value, bool) else operator.index(value)
            except TypeError:
                value = None
            if value is None or value < 0:
                raise ConfigError(f"shots: integer shot numbers >= 0, got {shots!r}")
            if value > _MAX_SHOT:
                raise ConfigError(f"shots: shot number {value} is too large (at most 2**63 - 1)")
        bounds.append(value)
    return bounds[0], bounds[1]


def _threads(threads):
    if isinstance(threads, bool) or not isinstance(threads, int) or not 0 <= threads <= 65536:
        raise ConfigError(f"threads: an integer from 0 (every core) to 65536, got {threads!r}")
    return threads


def _warn(summary):
    """The engine's warnings (a stands file under no shot...) as Python warnings."""
    for message in summary.pop("warnings", []):
        warnings.warn(message, UserWarning, stacklevel=3)


def run(config, shots=None, threads=0, overrides=None):
    """Simulates the configuration's shots and returns shots.nc as an xarray.Dataset.

    config:    a configuration file's path, or a dict of the JSON configuration (relative
               paths in it are taken from the current directory).
    shots:     None (the whole track), range(a, b) or (a, b): shot numbers a to b - 1, as
               `--shots A:B`.
    threads:   0 uses every core; results do not depend on it.
    overrides: {"canopy.pai": 2.0, ...}, each applied as `--set KEY=VALUE`.

    The Dataset has the variables, dimensions, attributes and values of the shots.nc that
    `glaswave run` writes for the same configuration, decoded as xarray.open_dataset decodes.
    """
    import xarray  # here, so that check() works without it

    path, document, folder = _source(config)
    first, last = _shot_range(shots)
    assignments = _assignments(overrides)
    threads = _threads(threads)
    described = repr(os.fsdecode(config)) if path is not None else "{...}"
    command_line = (
        f"glaswave.run({described}, shots={shots!r}, threads={threads}, overrides={overrides!r})"
    )
    # The engine writes its products into a directory of its own, removed whatever happens; the
    # Dataset is read into memory before it goes.
    with tempfile.TemporaryDirectory(prefix="glaswave-") as scratch:
        out_dir = os.path.join(scratch, "run")
        summary = _glaswave.run(path, document, folder, assignments, out_dir, threads, first,
                                last, command_line)
        _warn(summary)
        # netCDF4-python calls the libnetcdf and HDF5 the engine uses, with the GIL released:
        # under the engine's lock, so that another thread's run is not writing meanwhile.
        with _glaswave.netcdf_lock():
            return xarray.load_dataset(os.path.join(out_dir, "shots.nc"))


def hdf5_lock():
    """The engine's lock on libnetcdf and HDF5, as a context manager, for your own reads.

    HDF5 as Debian builds it is not thread-safe, and glaswave's calls into it (a run's shots.nc,
    a granule track, a NetCDF voxel grid) hold this lock: while glaswave runs in another thread,
    hold it around your own calls into the same libraries (xarray.open_dataset/load_dataset,
    netCDF4.Dataset, h5py.File from Debian's python3-h5py), or both may crash or hang:

        with glaswave.hdf5_lock():
            ds = xarray.load_dataset("other.nc")   # read whole while the lock is held

    Lazily loaded datasets read on access: load them inside the block. Waiting for the lock
    releases the GIL. An h5py from pip carries its own HDF5 and needs no lock.
    """
    return _glaswave.netcdf_lock()


def brf(config, threads=0, overrides=None):
    """The scene's reflectance under the sun, as `glaswave brf` computes it (FLIGHT's mode).

    Returns the dict that brf.json holds: {"bands": [{"name", "albedo", "views": [{"zenith_deg",
    "azimuth_deg", "brf", "brf_stderr"}]}]}, with the sky's keys beside them when the
    configuration has an atmosphere (docs/guide/atmosphere.md); scene.tif is not made. `config`,
    `threads` and `overrides` as for run(); results do not depend on `threads`.
    """
    path, document, folder = _source(config)
    return json.loads(_glaswave.brf(path, document, folder, _assignments(overrides),
                                    _threads(threads)))


def check(config, overrides=None):
    """Validates the configuration and opens its inputs, simulating nothing, as `glaswave check`.

    Raises ConfigError (the message names the key as a JSON path) or InputError; returns a dict
    with the track's `shots`, `sequence_length` and `shots_off_terrain`.
    """
    path, document, folder = _source(config)
    summary = _glaswave.check(path, document, folder, _assignments(overrides))
    _warn(summary)
    return summary
