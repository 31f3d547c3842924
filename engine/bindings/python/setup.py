"""Builds the grove extension module with CMake for the interpreter running pip.

    python3 -m venv --system-site-packages venv        # numpy from Debian's python3-numpy
    venv/bin/pip install --no-build-isolation ./engine/bindings/python

Configures the repository (three folders up) in its build-pip/ with -DPython_EXECUTABLE=<this
interpreter>, tests, benchmarks and MPI off, builds only the module (GROVE_BUILD_JOBS parallel
jobs, default 2) and copies it where setuptools packs it. Needs what tools/scripts/setup.sh
installs.
"""
import os
import pathlib
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parents[3]


def version():
    text = (ROOT / "engine/include/grove/version.h").read_text()
    parts = [re.search(rf"#define GROVE_VERSION_{p} (\d+)", text).group(1)
             for p in ("MAJOR", "MINOR", "PATCH")]
    return ".".join(parts)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = pathlib.Path(self.build_temp).resolve() / "cmake"
        subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                        f"-DPython_EXECUTABLE={sys.executable}", "-DGROVE_BUILD_TESTS=OFF",
                        "-DGROVE_BUILD_BENCHMARKS=OFF", "-DGROVE_MPI=OFF"], check=True)
        subprocess.run(["cmake", "--build", str(build), "--target", "grove_python", "-j",
                        os.environ.get("GROVE_BUILD_JOBS", "2")], check=True)
        built = sorted((build / "python").glob("grove*.so"))
        if len(built) != 1:
            sys.exit(f"grove: expected one module in {build / 'python'}, found {built}")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built[0], target)


# Builds in the repository's build-pip/ (ignored by git, reused by the next install), not beside
# this file: the source tree's checks read every folder of engine/.
setup(version=version(), ext_modules=[Extension("grove", sources=[])],
      cmdclass={"build_ext": CMakeBuild}, options={"build": {"build_base": str(ROOT / "build-pip")}})
