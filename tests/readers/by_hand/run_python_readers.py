"""read-ICESat-2's and carbonplan/trace's readers on glaswave's granules (issue 38, item 6).

Called by run_readers.sh, not by ctest. Usage:
  run_python_readers.py --read-icesat2 DIR --trace DIR --label L --out OUT.tsv
      [--atl03 FILE] [--glah01 FILE] [--glah14 FILE]
Appends one row a call to OUT.tsv (reader, call, label, result), as run_readers.R does.
read-ICESat-2 is imported from DIR (it needs its package metadata: run_readers.sh writes it
with `setup.py egg_info`); carbonplan's glas_extract.py is loaded by path, without the rest
of carbonplan_trace (whose other modules import s3fs, xgboost, boto3, ...). h5py's KeyError is
made to name the path it could not open; nothing else is changed.
"""
import argparse
import importlib.util
import os
import sys
import warnings

import h5py
import numpy as np

_h5_getitem = h5py.Group.__getitem__


def _getitem_naming_the_path(group, name):
    """h5py's KeyError says 'component not found' without the path; the table wants it."""
    try:
        return _h5_getitem(group, name)
    except KeyError as error:
        path = name if str(name).startswith("/") else f"{group.name.rstrip('/')}/{name}"
        raise KeyError(f"{path}: {error.args[0]}") from None


h5py.Group.__getitem__ = _getitem_naming_the_path


def one_line(text):
    return " ".join(str(text).split())[:160]


class Table:
    def __init__(self, label):
        self.label = label
        self.rows = []

    def record(self, reader, name, call, check=None):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                value = call()
        except Exception as error:  # any reader failure is a row, not a stop
            self.rows.append((reader, name, self.label,
                              one_line(f"error: {type(error).__name__}: {error}")))
            return None
        try:
            problem = check(value) if check else None
        except Exception as error:  # a check that cannot read the result says so
            problem = f"check failed: {type(error).__name__}: {error}"
        self.rows.append((reader, name, self.label, one_line(problem or "works")))
        return value


def all_fill(values):
    values = np.asarray(values, dtype=float)
    return values.size == 0 or bool(np.all(~np.isfinite(values) | (np.abs(values) > 1e30)))


def check_atl03_granule(value):
    mds, attrs, beams = value
    if not beams:
        return "empty: no beams"
    heights = mds[beams[0]]["heights"]["h_ph"]
    if all_fill(heights):
        return f"all fill: {beams[0]}/heights/h_ph"
    return None


def check_dataset(fields):
    def check(ds):
        empty = [f for f in fields if f not in ds or all_fill(ds[f].values)]
        if empty:
            return "all fill or absent: " + ", ".join(empty)
        return None
    return check


def run_read_icesat2(table, atl03):
    import icesat2_toolkit.io.ATL03 as ATL03
    reader = "read-ICESat-2"
    table.record(reader, "io.ATL03.read_granule", lambda: ATL03.read_granule(atl03),
                 check_atl03_granule)
    table.record(reader, "io.ATL03.read_granule(ATTRIBUTES=True)",
                 lambda: ATL03.read_granule(atl03, ATTRIBUTES=True), check_atl03_granule)
    beams = table.record(reader, "io.ATL03.find_beams", lambda: ATL03.find_beams(atl03),
                         lambda b: None if len(b) else "empty: no beams")
    def check_main(value):
        mds = value[0]
        groups = [g for g in ("ancillary_data", "orbit_info") if not mds.get(g)]
        return "empty: " + ", ".join(groups) if groups else None
    table.record(reader, "io.ATL03.read_main", lambda: ATL03.read_main(atl03), check_main)
    if beams:
        def check_beam(value):
            mds = value[0]
            return "all fill: heights/h_ph" if all_fill(mds["heights"]["h_ph"]) else None
        table.record(reader, "io.ATL03.read_beam", lambda: ATL03.read_beam(atl03, beams[0]),
                     check_beam)


def run_trace(table, trace_dir, glah01, glah14):
    path = os.path.join(trace_dir, "carbonplan_trace", "v1", "glas_extract.py")
    spec = importlib.util.spec_from_file_location("glas_extract", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    reader = "carbonplan/trace"
    if glah14:
        table.record(reader, "extract_GLAH14_data", lambda: module.extract_GLAH14_data(glah14),
                     check_dataset(["lat", "lon", "elevation", "elevation_correction",
                                    "ref_range", "centroid_offset", "gaussian_amp"]))
    if glah01:
        table.record(reader, "extract_GLAH01_data", lambda: module.extract_GLAH01_data(glah01),
                     check_dataset(["rec_wf", "tx_wf", "noise_mean", "rec_wf_sample_loc"]))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--read-icesat2", required=True)
    parser.add_argument("--trace", required=True)
    parser.add_argument("--label", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--atl03")
    parser.add_argument("--glah01")
    parser.add_argument("--glah14")
    args = parser.parse_args()
    sys.path.insert(0, args.read_icesat2)
    table = Table(args.label)
    if args.atl03:
        run_read_icesat2(table, args.atl03)
    if args.glah01 or args.glah14:
        run_trace(table, args.trace, args.glah01, args.glah14)
    header = not os.path.exists(args.out)
    with open(args.out, "a") as out:
        if header:
            out.write("reader\tcall\tlabel\tresult\n")
        for row in table.rows:
            out.write("\t".join(row) + "\n")


if __name__ == "__main__":
    main()
