#!/usr/bin/env bash
# `pip install --no-build-isolation .` as a user runs it, into a fresh virtual environment that
# sees Debian's numpy and xarray (--system-site-packages), with no PYTHONPATH: the module and the
# command come from the environment, the command finds its plotting script in the package, and
# glaswave.run simulates the demo (3 shots, 200 rays). The CMake build is BUILD's (already built
# by the suite: only the two targets are checked), so nothing is compiled again.
#   pip_install_test.sh SOURCE_DIR BUILD_DIR WORK_DIR
set -euo pipefail
source_dir=$1 build_dir=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
unset PYTHONPATH
export GLASWAVE_BUILD_DIR="$build_dir" CMAKE_BUILD_PARALLEL_LEVEL=2 PYTHONDONTWRITEBYTECODE=1
# Nothing is fetched: numpy and xarray must come from the system's site-packages.
export PIP_NO_INDEX=1 PIP_DISABLE_PIP_VERSION_CHECK=1
/usr/bin/python3 -m venv --system-site-packages "$work/venv"
venv="$work/venv"
(cd "$source_dir" && "$venv/bin/pip" install --no-build-isolation --quiet .)

# The command, from the environment's bin/.
[ -x "$venv/bin/glaswave" ] || { echo "no glaswave command in $venv/bin" >&2; exit 1; }
# The granule, voxel grid and retrieve input readers' programs, beside the package's own program
# (footprints/granule.hpp, canopy/voxel_grid.hpp).
package=$("$venv/bin/python" -c 'import glaswave, os; print(os.path.dirname(glaswave.__file__))')
for reader in glaswave-read-granule glaswave-read-voxels glaswave-read-retrieval-input; do
  [ -x "$package/bin/$reader" ] || { echo "no $package/bin/$reader in the package" >&2; exit 1; }
done
"$venv/bin/glaswave" --version | grep -qx "glaswave [0-9.]*"

# The demo's terrain, then the command and the module on it, from outside the source tree.
/usr/bin/python3 "$source_dir/share/demo/make_demo_dem.py" "$work/demo_dem.tif" >/dev/null
cd "$work"
demo="$source_dir/share/demo/demo.json"
small=(--set "terrain.dem=$work/demo_dem.tif" --set simulation.rays_per_shot=200
       --set track.shots=3)
"$venv/bin/glaswave" check "$demo" "${small[@]}" | grep -q "is valid: 3 shots"
"$venv/bin/glaswave" run "$demo" "${small[@]}" --out "$work/run" --quiet --threads 2 >/dev/null
for product in shots.nc footprints.geojson plots/waveforms.png; do
  [ -s "$work/run/$product" ] || { echo "glaswave run wrote no $product" >&2; exit 1; }
done
"$venv/bin/python" - "$venv" "$demo" "$work/demo_dem.tif" <<'PY'
import sys
import glaswave

venv, demo, dem = sys.argv[1:]
assert glaswave.__file__.startswith(venv), f"glaswave imported from {glaswave.__file__}, not {venv}"
ds = glaswave.run(demo, shots=range(0, 3), threads=2, overrides={
    "terrain.dem": dem, "simulation.rays_per_shot": 200, "output.plots": False})
assert ds.sizes["shot"] == 3 and list(ds.band.values) == [532, 1064], ds
assert int(ds.quality_flag.sum()) == 3, ds.quality_flag.values
print("glaswave", glaswave.__version__, "from", glaswave.__file__)
PY
