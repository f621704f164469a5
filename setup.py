"""The wheel build compiles lumos's kernels (`lumos warmup`) into the package, like a C extension's build.

`pip install .` builds a wheel in an isolated environment that holds lumos's run-time dependencies too
(pyproject.toml's [build-system] requires), runs `python -m lumos warmup` against the built package with its cache
folder set to `lumos/_kernel_cache` inside it, and ships what it compiled. The installed kernels are stamped with
the hash of their sources, the CPU and the Numba version (`lumos.kernels.cache`): where they do not fit, lumos
compiles on first use. Set LUMOS_BUILD_KERNELS=0 to skip the step; editable installs skip it (run `lumos warmup`).
"""

import os
import subprocess
import sys
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyWithKernels(build_py):
    def run(self):
        if not getattr(self, "editable_mode", False):
            self._drop_stale_modules()
        super().run()
        if getattr(self, "editable_mode", False) or os.environ.get("LUMOS_BUILD_KERNELS", "1") == "0":
            return
        build_lib = Path(self.build_lib).resolve()
        cache = build_lib / "lumos" / "_kernel_cache"
        env = dict(os.environ, LUMOS_CACHE_DIR=str(cache),
                   PYTHONPATH=os.pathsep.join([str(build_lib)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
        print(f"lumos: compiling kernels into {cache} (LUMOS_BUILD_KERNELS=0 skips this)", flush=True)
        proc = subprocess.run([sys.executable, "-m", "lumos", "warmup"], env=env)
        if proc.returncode != 0:  # the package still works: what did not compile here compiles on first use
            print("lumos: warning: some kernels did not compile at install; they will compile on first use",
                  flush=True)

    def _drop_stale_modules(self):
        """Empty the package's build folder, the kernels compiled there before excepted: pip builds in the
        checkout's `build/`, and setuptools copies the sources over what an earlier build left, so a module since
        renamed or deleted would ship in the wheel. (Kept kernels are safe: each is stamped with its sources.)"""
        package = Path(self.build_lib) / "lumos"
        if not package.is_dir():
            return
        for path in sorted(package.rglob("*"), reverse=True):  # files before the folders that hold them
            if "_kernel_cache" in path.relative_to(package).parts:
                continue
            if path.is_dir() and not path.is_symlink():
                if not any(path.iterdir()):
                    path.rmdir()
            else:
                path.unlink()


setup(cmdclass={"build_py": BuildPyWithKernels})
