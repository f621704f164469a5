"""`kernels/threads.py`: `parallel_for` covers its range exactly once, on the threads asked for, nests without
deadlock, passes errors on, and the renders built on it give the same image on any number of threads."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from lumos.kernels.threads import parallel_for


@pytest.mark.parametrize("threads", [1, 2, 3, 8])
@pytest.mark.parametrize("lo, hi, grain", [(0, 1, None), (0, 7, None), (5, 1000, None), (0, 1000, 1), (3, 50, 64)])
def test_runs_cover_the_range_exactly_once(threads, lo, hi, grain):
    seen = np.zeros(hi + 1, np.int64)
    lock = threading.Lock()
    runs = []

    def body(k0, k1):
        assert lo <= k0 < k1 <= hi
        with lock:
            seen[k0:k1] += 1
            runs.append((k0, k1))

    parallel_for(body, lo, hi, grain=grain, threads=threads)
    assert (seen[lo:hi] == 1).all() and seen[:lo].sum() == 0 and seen[hi] == 0
    if threads == 1:  # one thread: one call, whatever the grain
        assert runs == [(lo, hi)]
    elif grain is not None:
        assert all(k1 - k0 <= grain for k0, k1 in runs)


def test_an_empty_range_calls_nothing():
    parallel_for(lambda k0, k1: pytest.fail("called"), 4, 4, threads=2)
    parallel_for(lambda k0, k1: pytest.fail("called"), 4, 2, threads=2)


def test_more_than_one_thread_runs_and_the_caller_is_one_of_them():
    names = set()
    barrier = threading.Barrier(2, timeout=10)  # two runs must be under way at once to pass it

    def body(k0, k1):
        names.add(threading.current_thread().name)
        barrier.wait()

    parallel_for(body, 0, 2, grain=1, threads=2)
    assert threading.current_thread().name in names and len(names) == 2


def test_nested_calls_finish():
    """A run that itself calls parallel_for (a render on a Dask worker thread, a BVH built inside a task) never
    waits on a helper that cannot start: every pool thread may be busy with outer runs."""
    total = np.zeros(64, np.int64)

    def inner(i):
        def body(k0, k1):
            total[i] += k1 - k0
        parallel_for(body, 0, 100, grain=3, threads=4)

    parallel_for(lambda k0, k1: [inner(i) for i in range(k0, k1)], 0, 64, grain=1, threads=8)
    assert (total == 100).all()


def test_an_error_in_a_run_reaches_the_caller_and_stops_the_rest():
    calls = []

    def body(k0, k1):
        calls.append(k0)
        if k0 == 0:
            raise ValueError("run 0 failed")

    with pytest.raises(ValueError, match="run 0 failed"):
        parallel_for(body, 0, 1000, grain=1, threads=2)
    assert len(calls) < 1000


def test_renders_are_the_same_on_one_and_on_two_threads():
    import lumos

    scene = lumos.load_scene({
        "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "fov": 45},
        "lights": [{"type": "point", "position": [2, 4, 3], "intensity": 1.0}],
        "objects": [{"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6,
                     "material": {"kd": [0.7, 0.3, 0.2], "ks": 0.4, "shininess": 30, "kr": 0.3}},
                    {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": {"kd": 0.6}}],
    })
    for method, extra in (("raycast", {"spp": 4}), ("whitted", {"antialias": "adaptive"}), ("path", {"spp": 8}),
                          ("raster", {"shading": "phong", "spp": 2})):
        one = lumos.render(scene, method=method, width=48, height=36, threads=1, **extra)
        two = lumos.render(scene, method=method, width=48, height=36, threads=2, **extra)
        np.testing.assert_array_equal(one.array, two.array, err_msg=method)
        assert one.stats["rays"] == two.stats["rays"], method
