"""Builds the glaswave module (_glaswave, pybind11) and the glaswave program with CMake, and
packages both with the module's Python files: `pip install --no-build-isolation .` and
`python3 -m build --no-isolation` (metadata in pyproject.toml).

The CMake build folder is GLASWAVE_BUILD_DIR, else build/ of the checkout, where ./scripts/setup
builds: an up-to-date build is reused and only the two targets are built, never the tests.
Parallel jobs: CMAKE_BUILD_PARALLEL_LEVEL, else every core. setuptools' own files go to
BUILD/setuptools, not into the source tree.
"""
import os
import shutil
import subprocess
import sys

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py

ROOT = os.path.dirname(os.path.abspath(__file__))
CMAKE_BUILD = os.path.abspath(os.environ.get("GLASWAVE_BUILD_DIR") or os.path.join(ROOT, "build"))
SETUPTOOLS_BUILD = os.path.join(CMAKE_BUILD, "setuptools")
# The data the program reads at run time, beside it as `cmake --install` puts it (P/share/glaswave
# next to P/bin): the plotting script, the presets and the demo.
SHARE = ["plots", "presets", "demo"]


class BuildWithCMake(build_py):
    """build_py, then the module and the program built with CMake and copied into the package."""

    def run(self):
        super().run()
        if not os.path.isfile(os.path.join(CMAKE_BUILD, "CMakeCache.txt")):
            subprocess.run(["cmake", "-S", ROOT, "-B", CMAKE_BUILD, "-DCMAKE_BUILD_TYPE=Release"],
                           check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 2)
        subprocess.run(["cmake", "--build", CMAKE_BUILD, "--target", "glaswave", "_glaswave",
                        "-j", jobs], check=True)
        package = os.path.join(self.build_lib, "glaswave")
        built_package = os.path.join(CMAKE_BUILD, "python", "glaswave")
        modules = [f for f in os.listdir(built_package) if f.startswith("_glaswave.")]
        if not modules:
            sys.exit(f"setup.py: CMake built no _glaswave module in {built_package} "
                     "(pybind11-dev and python3-dev are needed: ./scripts/setup)")
        for module in modules:
            shutil.copy2(os.path.join(built_package, module), package)
        os.makedirs(os.path.join(package, "bin"), exist_ok=True)
        shutil.copy2(os.path.join(CMAKE_BUILD, "pipeline", "glaswave"),
                     os.path.join(package, "bin", "glaswave"))
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
