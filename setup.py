"""Builds the `deform` extension with the project's CMake (no scikit-build in Debian 12): see pyproject.toml.

The CMake build goes to build-pip/ in the repository (ignored by git, kept between installs, so a second install
recompiles only what changed); the module it makes is copied where setuptools puts extensions.
Environment: DEFORM_CMAKE_ARGS adds arguments to the configure step (e.g. -DDEFORM_BUILD_IMPORT=OFF).
"""
import os
import pathlib
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = ROOT / "build-pip"
        configure = ["cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                     "-DDEFORM_LIBRARY_ONLY=ON", "-DDEFORM_BUILD_PYTHON=ON", "-DDEFORM_BUILD_GPU=OFF",
                     f"-DPython3_EXECUTABLE={sys.executable}"]
        configure += shlex.split(os.environ.get("DEFORM_CMAKE_ARGS", ""))
        subprocess.run(configure, check=True)
        jobs = str(os.cpu_count() or 2)
        targets = ["deform_python"]
        subprocess.run(["cmake", "--build", str(build), "-j", jobs, "--target", *targets], check=True)
        built = sorted((build / "python").glob("deform.*.so"))
        if not built:
            raise RuntimeError("the CMake build made no deform module in build-pip/python")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)


setup(ext_modules=[Extension("deform", sources=[])], cmdclass={"build_ext": CMakeBuild}, packages=[], py_modules=[])
