"""Builds the gradus Python module with CMake (see pyproject.toml and the README).

GRADUS_CMAKE_BUILD_DIR=DIR reuses a configured build directory (only its _gradus
target is built); otherwise the libraries and the module are built in a
temporary directory without tests and benchmarks.
"""
import glob
import os
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))


def version():
    with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
        return re.search(r"project\(Gradus VERSION ([0-9.]+)", f.read()).group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = os.environ.get("GRADUS_CMAKE_BUILD_DIR")
        if build:
            build = os.path.abspath(build)
            if not os.path.exists(os.path.join(build, "CMakeCache.txt")):
                sys.exit("GRADUS_CMAKE_BUILD_DIR=%s is not a configured build directory" % build)
        else:
            build = os.path.join(os.path.abspath(self.build_temp), "cmake")
            subprocess.check_call(["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release",
                                   "-DGRADUS_BUILD_TESTS=OFF", "-DGRADUS_BUILD_BENCHMARKS=OFF",
                                   "-DPython_EXECUTABLE=" + sys.executable])
        subprocess.check_call(["cmake", "--build", build, "--target", "_gradus", "-j", str(os.cpu_count() or 1)])
        built = glob.glob(os.path.join(build, "python", "gradus", "_gradus*.so"))
        if len(built) != 1:
            sys.exit("expected one _gradus module in %s/python/gradus, found %s" % (build, built))
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(built[0], target)


setup(
    name="gradus",
    version=version(),
    description="Gradus renderer: Python module",
    python_requires=">=3.9",
    install_requires=["numpy"],
    packages=["gradus"],
    package_dir={"": "python"},
    ext_modules=[Extension("gradus._gradus", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    # Not build/: that is the CMake build directory of scripts/build.
    options={"build": {"build_base": "build-pip"}},
    zip_safe=False,
)
