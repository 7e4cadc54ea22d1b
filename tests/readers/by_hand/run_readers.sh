#!/usr/bin/env bash
# The missions' own readers on glaswave's granules, by hand (issue 38, item 6).
#
# NOT run by ctest or CI: it needs R, the readers' R packages and the readers' fetched sources.
# It makes small GEDI (L1B, L2A, and L2B from `glaswave retrieve`), GLAS (GLAH01, GLAH14) and
# ICESat-2 (ATL03, ATL08, sc_orient 0 and 1) granules with the given binary, runs every
# user-facing function of rGEDI, ICESat2VegR, read-ICESat-2 and carbonplan/trace that reads
# them, and prints the table (call, works or the error) as Markdown. Unless --no-real, it also
# runs rGEDI and ICESat2VegR on the real subsets their packages ship (inst/extdata) and
# read-ICESat-2 on ICESat2VegR's ATL03 subset, for a column to compare with (slow: rGEDI's
# clipping of the real subsets takes about half an hour on a busy two-core machine).
#
# Usage: tests/readers/by_hand/run_readers.sh [--install] [--no-real] GLASWAVE SOURCES OUT
#   GLASWAVE  the glaswave binary (e.g. build/pipeline/glaswave)
#   SOURCES   a folder holding the readers' sources: rGEDI, ICESat2VegR, read-ICESat-2,
#             timescale (read-ICESat-2 imports it) and trace (carbonplan/trace)
#   OUT       a new folder: products/, rows/*.tsv, scratch/, table.md
#   --install installs rGEDI and ICESat2VegR into OUT/Rlib first (R CMD INSTALL; their
#             DESCRIPTION without the Imports Debian 12 lacks, which only their download and
#             Earth Engine helpers use); without it they must be on R_LIBS already.
# Needs: Debian 12's r-base-core, r-base-dev, libgdal-dev and the r-cran-* packages listed in
# docs/granules.md ("The readers, by hand"); /usr/bin/python3 with numpy, h5py, pandas,
# xarray, scipy, lxml, python3-dateutil, python3-setuptools-scm.
set -euo pipefail

install=0
real=1
while [[ $# -gt 0 && $1 == --* ]]; do
  case $1 in
    --install) install=1 ;;
    --no-real) real=0 ;;
    *) echo "run_readers.sh: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
if [[ $# -ne 3 ]]; then
  sed -n '2,/^set -euo/p' "$0" | sed '$d' >&2
  exit 2
fi
glaswave=$(realpath "$1")
src=$(realpath "$2")
out=$3
here=$(cd "$(dirname "$0")" && pwd)
for d in rGEDI ICESat2VegR read-ICESat-2 timescale trace; do
  [[ -d $src/$d ]] || { echo "run_readers.sh: $src/$d: no such folder" >&2; exit 2; }
done
# A snapshot without ICESat2VegR's readme/ GIFs stops `git archive HEAD` before src/.
[[ -d $src/ICESat2VegR/src ]] || { echo "run_readers.sh: $src/ICESat2VegR/src: no such folder (extract with git archive HEAD -- . ':!readme')" >&2; exit 2; }
[[ -x $glaswave ]] || { echo "run_readers.sh: $glaswave: not an executable" >&2; exit 2; }
[[ -e $out ]] && { echo "run_readers.sh: $out exists; give a new folder" >&2; exit 2; }
mkdir -p "$out"/{products,rows,scratch,py}
out=$(realpath "$out")
p=$out/products
log=$out/log.txt

if [[ $install == 1 ]]; then
  mkdir -p "$out/Rlib" "$out/build"
  cp -r "$src/rGEDI" "$src/ICESat2VegR" "$out/build/"
  # Imports that Debian 12 does not package: getPass (rGEDI's, ICESat2VegR's download login),
  # geojsonsf, googleCloudStorageR, servr (ICESat2VegR's Earth Engine and map helpers). Their
  # NAMESPACEs import none of them, so the functions tested here do not touch them.
  sed -i -E '/^ +(getPass|geojsonsf|googleCloudStorageR|servr),$/d' \
    "$out/build/rGEDI/DESCRIPTION" "$out/build/ICESat2VegR/DESCRIPTION"
  R CMD INSTALL --no-test-load -l "$out/Rlib" "$out/build/rGEDI" >>"$log" 2>&1
  R CMD INSTALL --no-test-load -l "$out/Rlib" "$out/build/ICESat2VegR" >>"$log" 2>&1
  export R_LIBS=$out/Rlib${R_LIBS:+:$R_LIBS}
fi

echo "glaswave: $glaswave ($("$glaswave" --version 2>&1 | head -1))" | tee -a "$log" >&2
run() { "$glaswave" run "$here/$1.json" --out "$p/$2" --quiet "${@:3}" >>"$log" 2>&1; }
run gedi gedi
"$glaswave" retrieve "$p/gedi/gedi_l1b.h5" "$p/gedi/gedi_l2a.h5" --out "$p/gedi_l2b" --quiet \
  >>"$log" 2>&1
run glas glas
run atlas atlas_backward --set sensor.sc_orient=backward
run atlas atlas_forward --set sensor.sc_orient=forward

rows=$out/rows
R_run() { Rscript "$here/run_readers.R" "$@" >>"$log" 2>&1; }
if [[ $real == 1 ]]; then
  mkdir -p "$out/real"
  for z in "$src"/rGEDI/inst/extdata/*.zip; do unzip -o -q "$z" -d "$out/real"; done
  R_run gedi "real subset" "$out"/real/GEDI01_B_*.h5 "$out"/real/GEDI02_A_*.h5 \
    "$out"/real/GEDI02_B_*.h5 "$rows/gedi.tsv" "$out/scratch/gedi_real"
fi
R_run gedi glaswave "$p/gedi/gedi_l1b.h5" "$p/gedi/gedi_l2a.h5" "$p/gedi_l2b/gedi_l2b.h5" \
  "$rows/gedi.tsv" "$out/scratch/gedi"
if [[ $real == 1 ]]; then
  R_run icesat2 "real subset" "$src/ICESat2VegR/inst/extdata/atl03_clip.h5" \
    "$src/ICESat2VegR/inst/extdata/atl08_clip.h5" "$rows/icesat2.tsv" "$out/scratch/is2_real"
fi
for o in backward forward; do
  label="glaswave, sc_orient $([[ $o == backward ]] && echo 0 || echo 1)"
  R_run icesat2 "$label" "$p/atlas_$o/atl03.h5" "$p/atlas_$o/atl08.h5" "$rows/icesat2.tsv" \
    "$out/scratch/is2_$o"
done

# read-ICESat-2 reads its own version from its package metadata, and so does timescale:
# write it (setup.py egg_info) in copies of their sources, leaving SOURCES untouched.
cp -r "$src/read-ICESat-2" "$src/timescale" "$out/py/"
(cd "$out/py/timescale" && /usr/bin/python3 setup.py -q egg_info >>"$log" 2>&1)
(cd "$out/py/read-ICESat-2" && /usr/bin/python3 setup.py -q egg_info >>"$log" 2>&1)
py_run() {
  PYTHONPATH=$out/py/read-ICESat-2:$out/py/timescale /usr/bin/python3 \
    "$here/run_python_readers.py" --read-icesat2 "$out/py/read-ICESat-2" --trace "$src/trace" \
    --out "$rows/python.tsv" "$@" >>"$log" 2>&1
}
if [[ $real == 1 ]]; then
  py_run --label "real subset" --atl03 "$src/ICESat2VegR/inst/extdata/atl03_clip.h5"
fi
py_run --label "glaswave, sc_orient 0" --atl03 "$p/atlas_backward/atl03.h5"
py_run --label "glaswave, sc_orient 1" --atl03 "$p/atlas_forward/atl03.h5"
py_run --label glaswave --glah01 "$p/glas/glah01.h5" --glah14 "$p/glas/glah14.h5"

/usr/bin/python3 "$here/format_table.py" "$rows/gedi.tsv" "$rows/icesat2.tsv" "$rows/python.tsv" \
  | tee "$out/table.md"
