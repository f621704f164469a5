"""The `nojit` subset of the kernel tests, run again with the JIT off (`NUMBA_DISABLE_JIT=1`).

With the JIT off every `@njit` kernel is plain Python over NumPy scalars, which is how a kernel is stepped
through in a debugger and how coverage sees it; this test proves that path still gives the same answers. The
subset is small (RNG, sampling, intersection, BVH and illumination tests and a few renders of at most 48×36
pixels, ~50 tests in a few seconds) because interpreted kernels are ~1000× slower.

Everything in the subset works with the JIT off. Two things to know when adding to it:
* Numba and NumPy promote differently: NumPy keeps `float32 · float` in float32 (NEP 50) where Numba goes to
  float64, and Numba's `float()` of a float32 stays float32 where Python's gives a float64. Kernels that mix
  the float32 arrays (triangles, BVH boxes) with float64 must promote explicitly (`np.float64(x)`) to behave
  the same both ways; `kernels/test_bvh_build.py::test_axis_aligned_rays_through_bvh` guards the case that once broke
  (float32 box bound · 1e100 overflowing to inf, culling every node for axis-aligned rays).
* SplitMix64 arithmetic on NumPy uint64 scalars wraps as intended, but NumPy warns about the overflow; the
  subprocess ignores RuntimeWarning.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
FILES = ["kernels/test_rng.py", "kernels/test_sampling.py", "kernels/test_intersect.py", "kernels/test_bvh_build.py",
         "kernels/test_illumination.py", "methods/test_raycast.py", "methods/test_raster.py"]
MIN_PASSED = 40


@pytest.mark.slow
def test_nojit_subset_passes_interpreted():
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    cmd = [sys.executable, "-m", "pytest", "-q", "-m", "nojit", "-p", "no:cacheprovider", "-W",
           "ignore::RuntimeWarning", *[str(HERE / f) for f in FILES]]
    proc = subprocess.run(cmd, env=env, cwd=HERE.parent, capture_output=True, text=True, timeout=300)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-4000:]
    # pytest's own summary line, wherever plugins print their own lines after it (pytest-benchmark warns there
    # when xdist is active)
    summaries = [line for line in proc.stdout.splitlines() if re.search(r"\d+ passed.* in [\d.]+s", line)]
    assert summaries, out[-4000:]
    summary = summaries[-1]
    counts = {k: int(n) for n, k in re.findall(r"(\d+) (passed|failed|errors?|xfailed|xpassed)", summary)}
    assert counts.get("failed", 0) == 0 and counts.get("xpassed", 0) == 0 and "error" not in summary, summary
    assert counts.get("passed", 0) >= MIN_PASSED, summary
