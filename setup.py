"""Builds the glaswave module (_glaswave, pybind11) and the glaswave program with CMake, and
packages both with the module's Python files: `pip install --no-build-isolation .` and
`python3 -m build --no-isolation` (metadata in pyproject.toml).

The CMake build folder is GLASWAVE_BUILD_DIR, else build/ of the checkout, where ./scripts/setup
builds: an up-to-date build is reused and only the two targets are built, never the tests.
Parallel jobs: CMAKE_BUILD_PARALLEL_LEVEL, else every core. setuptools' own files go to
BUILD/setuptools, not into the source tree.
"""
import glob
import os
import re
import shutil
import subprocess
import sys
import sysconfig


def missing(what, how):
    """Stops the build with one line naming what is missing and how to get it."""
    sys.exit(f"setup.py: {what} is needed to build glaswave: {how}")


# What the build needs (pyproject.toml's [build-system] requires, and the tools CMake runs),
# checked before anything is built: `pip install --no-build-isolation .` installs none of them.
if sys.version_info < (3, 9):
    missing("Python 3.9 or later", f"this is {sys.version.split()[0]}")
try:
    import setuptools
    from setuptools import Distribution, setup
    from setuptools.command.build_py import build_py
except ImportError:
    missing("setuptools (61 or later)",
            "pip install 'setuptools>=61', or apt install python3-setuptools")


def version_of(text):
    return tuple(int(part) for part in re.findall(r"\d+", text)[:2])


if version_of(setuptools.__version__) < (61, 0):
    missing("setuptools 61 or later", f"this is {setuptools.__version__}: "
            "pip install 'setuptools>=61'")
# setuptools before 70.1 builds wheels with the wheel package's bdist_wheel command.
if version_of(setuptools.__version__) < (70, 1):
    try:
        import wheel  # noqa: F401
    except ImportError:
        missing("the Python package wheel", "pip install wheel, or apt install python3-wheel")

ROOT = os.path.dirname(os.path.abspath(__file__))
CMAKE_BUILD = os.path.abspath(os.environ.get("GLASWAVE_BUILD_DIR") or os.path.join(ROOT, "build"))
SETUPTOOLS_BUILD = os.path.join(CMAKE_BUILD, "setuptools")
# The data the program reads at run time, beside it as `cmake --install` puts it (P/share/glaswave
# next to P/bin): the plotting script, the presets and the demo.
SHARE = ["plots", "presets", "demo"]


def check_tools():
    """CMake 3.20 or later, a C++17 compiler, pybind11 and this Python's headers."""
    cmake = shutil.which("cmake")
    if not cmake:
        missing("CMake 3.20 or later", "apt install cmake, or pip install cmake")
    output = subprocess.run([cmake, "--version"], capture_output=True, text=True).stdout
    if version_of(output) < (3, 20):
        missing("CMake 3.20 or later", f"{cmake} is {output.split()[2] if output else '?'}: "
                "pip install cmake")
    if not (os.environ.get("CXX") or shutil.which("c++") or shutil.which("g++")
            or shutil.which("clang++")):
        missing("a C++17 compiler", "apt install g++ (or set CXX)")
    headers = sysconfig.get_paths().get("include") or ""
    if not os.path.isfile(os.path.join(headers, "Python.h")):
        missing(f"this Python's headers ({headers}/Python.h)",
                f"apt install python{sys.version_info[0]}.{sys.version_info[1]}-dev")
    return pybind11_cmake_dir()


def pybind11_cmake_dir():
    """pybind11's CMake package: the Python package's (pip install pybind11), else Debian's."""
    try:
        import pybind11
        return pybind11.get_cmake_dir()
    except ImportError:
        pass
    for pattern in ("/usr/lib/cmake/pybind11", "/usr/share/cmake/pybind11",
                    "/usr/lib/*/cmake/pybind11", "/usr/local/lib/cmake/pybind11"):
        if any(os.path.isfile(os.path.join(d, "pybind11Config.cmake"))
               for d in glob.glob(pattern)):
            return None  # CMake finds it by itself
    missing("pybind11", "pip install pybind11, or apt install pybind11-dev")


class BuildWithCMake(build_py):
    """build_py, then the module and the program built with CMake and copied into the package."""

    def run(self):
        pybind11_dir = check_tools()
        super().run()
        if not os.path.isfile(os.path.join(CMAKE_BUILD, "CMakeCache.txt")):
            # The module for the Python that builds it (CMake prefers Debian's otherwise).
            python = [f"-D{v}={sys.executable}"
                      for v in ("Python_EXECUTABLE", "Python3_EXECUTABLE", "PYTHON_EXECUTABLE")]
            pybind11 = [f"-Dpybind11_DIR={pybind11_dir}"] if pybind11_dir else []
            subprocess.run(["cmake", "-S", ROOT, "-B", CMAKE_BUILD, "-DCMAKE_BUILD_TYPE=Release",
                            *python, *pybind11], check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 2)
        subprocess.run(["cmake", "--build", CMAKE_BUILD, "--target", "glaswave", "_glaswave",
                        "-j", jobs], check=True)
        package = os.path.join(self.build_lib, "glaswave")
        built_package = os.path.join(CMAKE_BUILD, "python", "glaswave")
        modules = [f for f in os.listdir(built_package) if f.startswith("_glaswave.")]
        if not modules:
            sys.exit(f"setup.py: CMake built no _glaswave module in {built_package} "
                     "(pybind11-dev and python3-dev are needed: ./scripts/setup)")
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        if "_glaswave" + suffix not in modules:
            sys.exit(f"setup.py: {CMAKE_BUILD} holds a module for another Python ({modules[0]}), "
                     f"not this one ({sys.executable}, {suffix}): set GLASWAVE_BUILD_DIR to a new "
                     "folder to build one for it")
        modules = ["_glaswave" + suffix]
        for module in modules:
            shutil.copy2(os.path.join(built_package, module), package)
        os.makedirs(os.path.join(package, "bin"), exist_ok=True)
        shutil.copy2(os.path.join(CMAKE_BUILD, "pipeline", "glaswave"),
                     os.path.join(package, "bin", "glaswave"))
        # The granule, NetCDF-4 voxel grid and retrieve input readers' own programs
        # (footprints/granule.hpp, canopy/voxel_grid.hpp, pipeline/retrieval/retrieve_inputs.hpp):
        # the module and the program look for them in glaswave/bin/.
        for folder, reader in (("footprints", "glaswave-read-granule"),
                               ("canopy", "glaswave-read-voxels"),
                               ("pipeline", "glaswave-read-retrieval-input")):
            shutil.copy2(os.path.join(CMAKE_BUILD, folder, reader),
                         os.path.join(package, "bin", reader))
        share = os.path.join(package, "share", "glaswave")
        for folder in SHARE:
            shutil.rmtree(os.path.join(share, folder), ignore_errors=True)
            shutil.copytree(os.path.join(ROOT, "share", folder), os.path.join(share, folder),
                            ignore=shutil.ignore_patterns("__pycache__"))


class BinaryDistribution(Distribution):
    """A wheel of compiled code: tagged for this Python and platform, not pure."""

    def has_ext_modules(self):
        return True


os.makedirs(SETUPTOOLS_BUILD, exist_ok=True)
setup(
    cmdclass={"build_py": BuildWithCMake},
    distclass=BinaryDistribution,
    options={
        "build": {"build_base": SETUPTOOLS_BUILD},
        "egg_info": {"egg_base": SETUPTOOLS_BUILD},
    },
)
