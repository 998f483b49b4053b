"""The iphong Python package for pip (pyproject.toml): the compiled module `iphong._core` is built
by CMake, the one build iphong has, and copied in beside python/iphong's pure-Python files.

The CMake build goes to build/pip/cmake (tests and benchmarks off), or to IPHONG_CMAKE_BUILD_DIR
when that names a configured build tree (its `_core` target is brought up to date and used).
The version is CMake's `project(VERSION)`, the one place it is written."""
import os
import pathlib
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


def version():
    text = (ROOT / "CMakeLists.txt").read_text()
    return re.search(r"project\(iphong VERSION ([0-9][0-9.]*)", text).group(1)


class CMakeExtension(Extension):
    def __init__(self):
        super().__init__("iphong._core", sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = pathlib.Path(os.environ.get("IPHONG_CMAKE_BUILD_DIR") or ROOT / "build" / "pip" / "cmake")
        if not (build_dir / "CMakeCache.txt").exists():
            subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                            "-DIPHONG_TESTS=OFF", "-DIPHONG_BENCH=OFF",
                            f"-DPython_EXECUTABLE={sys.executable}"], check=True)
        jobs = str(max(1, os.cpu_count() or 1))
        subprocess.run(["cmake", "--build", str(build_dir), "--target", "_core", "-j", jobs], check=True)
        built = sorted((build_dir / "python" / "iphong").glob("_core*.so"))
        if not built:
            raise RuntimeError(f"{build_dir}: CMake built no iphong/_core module")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built[0], target)


pip_dir = ROOT / "build" / "pip"
pip_dir.mkdir(parents=True, exist_ok=True)
setup(
    version=version(),
    ext_modules=[CMakeExtension()],
    cmdclass={"build_ext": CMakeBuild},
    # setuptools' own build and egg-info folders, kept out of CMake's build/ and the source tree.
    options={"build": {"build_base": str(pip_dir / "setuptools")}, "egg_info": {"egg_base": str(pip_dir)}},
)
