"""Builds the slam_mms wheel around the CMake-built extension module.

Where the module comes from (first match):
  1. $SLAM_MMS_PYTHON_MODULE: the path of a built _slam_mms*.so;
  2. the CMake build folder $SLAM_MMS_BUILD_DIR (default: ../build next to this file):
     <build>/python/_slam_mms*.so, rebuilt first with `cmake --build <build> --target _slam_mms`
     when <build>/CMakeCache.txt exists;
  3. otherwise CMake configures and builds a fresh Release tree in <build>.
No network is used: pip install --no-build-isolation --no-deps ./python.
"""

import glob
import os
import pathlib
import re
import shutil
import subprocess
import sys
import sysconfig

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = pathlib.Path(__file__).resolve().parent
REPO = HERE.parent


def _version() -> str:
    m = re.search(r"project\(slam_mms VERSION ([0-9.]+)", (REPO / "CMakeLists.txt").read_text())
    return m.group(1) if m else "0.0.0"


def _built_module(build_dir: pathlib.Path):
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
    hits = sorted(glob.glob(str(build_dir / "python" / f"_slam_mms{suffix}")))
    return pathlib.Path(hits[0]) if hits else None


class CMakeBuildExt(build_ext):
    def build_extension(self, ext):
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        module = os.environ.get("SLAM_MMS_PYTHON_MODULE")
        if module:
            src = pathlib.Path(module)
        else:
            build_dir = pathlib.Path(os.environ.get("SLAM_MMS_BUILD_DIR", REPO / "build"))
            jobs = os.environ.get("JOBS", "2")
            if not (build_dir / "CMakeCache.txt").exists():
                subprocess.check_call(["cmake", "-S", str(REPO), "-B", str(build_dir),
                                       "-DCMAKE_BUILD_TYPE=Release",
                                       f"-DPython_EXECUTABLE={sys.executable}"])
            subprocess.check_call(["cmake", "--build", str(build_dir), "-j", jobs,
                                   "--target", "_slam_mms"])
            src = _built_module(build_dir)
            if src is None:
                raise RuntimeError(f"_slam_mms was not built in {build_dir}/python (is "
                                   "pybind11-dev installed? see the CMake output)")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, target)


setup(
    version=_version(),
    ext_modules=[Extension("slam_mms._slam_mms", sources=[])],
    cmdclass={"build_ext": CMakeBuildExt},
)
