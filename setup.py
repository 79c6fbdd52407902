# SPDX-License-Identifier: BSD-3-Clause
"""Builds the extension ukdyn._ukdyn with CMake for setuptools (pyproject.toml).

The compiled part of the package is the CMake target ukdyn_python (python/CMakeLists.txt); this
file only configures and builds it and copies the result where setuptools packs it. The CMake
build directory is UKDYN_CMAKE_BUILD_DIR, by default build/ of this tree — the one
scripts/setup.sh has just built, so that `pip install .` after it compiles nothing. Extra CMake
arguments: UKDYN_CMAKE_ARGS (split on spaces), e.g. the ccache launchers. The extension links the
static library, so the installed package needs no libukdyn.so.
"""

import os
import pathlib
import shlex
import shutil
import subprocess
import sys
import sysconfig

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


class CMakeExtension(Extension):
    """An extension that CMake builds: no sources for setuptools to compile."""

    def __init__(self, name: str) -> None:
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    """Configures (if needed) and builds the CMake target ukdyn_python, then copies _ukdyn.*.so."""

    def build_extension(self, ext: Extension) -> None:
        build_dir = pathlib.Path(os.environ.get("UKDYN_CMAKE_BUILD_DIR", ROOT / "build")).resolve()
        # the interpreter the extension is for: the one running this build (a venv's python is
        # Debian's /usr/bin/python3 underneath; CMake wants the real executable)
        python = os.path.realpath(sys.executable)
        if not (build_dir / "CMakeCache.txt").exists():
            args = ["cmake", "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                    "-DUKDYN_BUILD_PYTHON=ON", f"-DUKDYN_PYTHON={python}"]
            if shutil.which("ninja"):
                args += ["-G", "Ninja"]
            args += shlex.split(os.environ.get("UKDYN_CMAKE_ARGS", ""))
            subprocess.run(args, check=True)
        subprocess.run(["cmake", "--build", str(build_dir), "--parallel", "2", "--target",
                        "ukdyn_python", "ukdyn_python_files"], check=True)
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        built = build_dir / "python" / "ukdyn" / f"_ukdyn{suffix}"
        if not built.exists():
            raise RuntimeError(f"{built} was not built: is {build_dir} configured for another "
                               f"Python (CMake cache variable UKDYN_PYTHON)?")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built, target)


# setup.cfg puts setuptools' scratch (egg-info, build/lib...) here
(ROOT / "build" / "setuptools").mkdir(parents=True, exist_ok=True)
setup(ext_modules=[CMakeExtension("ukdyn._ukdyn")], cmdclass={"build_ext": CMakeBuild})
