"""`kernels/jit.py`: device functions compile without wrappers into libraries that are linked, not emitted, and
still answer calls from Python through a twin; top-level kernels hold their device functions' code."""

from __future__ import annotations

import numpy as np
import pytest
from numba.core.codegen import JITCodeLibrary

from lumos.kernels import vec
from lumos.kernels.jit import DeviceDispatcher, DeviceLibrary, njit, njit_inline, njit_serial
from lumos.kernels.threads import parallel_for


@njit
def _scale(x, k):
    return x * k


@njit_inline
def _shift(x, k):
    return _scale(x, k) + 1.0


@njit_serial
def _kernel(values, k, out, i0, i1):
    for i in range(i0, i1):
        out[i] = _shift(values[i], k)


def test_device_functions_are_device_dispatchers_and_top_level_kernels_are_not():
    assert isinstance(_scale, DeviceDispatcher) and isinstance(_shift, DeviceDispatcher)
    assert isinstance(vec.dot, DeviceDispatcher)
    assert not isinstance(_kernel, DeviceDispatcher)


def test_a_kernel_links_its_device_functions_and_computes_with_them(tmp_path, monkeypatch):
    monkeypatch.setenv("LUMOS_CACHE_DIR", str(tmp_path))
    values = np.linspace(-2.0, 3.0, 101)
    out = np.empty_like(values)
    parallel_for(lambda i0, i1: _kernel(values, 2.5, out, i0, i1), 0, len(values), threads=2)
    np.testing.assert_array_equal(out, values * 2.5 + 1.0)
    # the device functions were compiled for the kernel into libraries that only get linked: no machine code
    (shift_cres,) = _shift.overloads.values()
    assert isinstance(shift_cres.library, DeviceLibrary)
    assert isinstance(next(iter(_kernel.overloads.values())).library, JITCodeLibrary)
    assert not isinstance(next(iter(_kernel.overloads.values())).library, DeviceLibrary)


def test_a_device_function_called_from_python_runs_a_wrapped_twin():
    a, b = np.array([1.0, 2.0, 3.0]), np.array([-2.0, 0.5, 4.0])
    assert vec.dot(a, b) == np.dot(a, b)
    assert _shift(2.0, 3.0) == 7.0
    twin = _shift.__dict__["_python_twin"]
    assert not isinstance(twin, DeviceDispatcher)
    assert all(not isinstance(c.library, DeviceLibrary) for c in twin.overloads.values())


@njit
def _column(values, k):
    return values[k] * 10.0


@njit
def _pick(pair, k):
    return pair[k]  # a heterogeneous tuple: only a constant k types


@njit_serial
def _constants_kernel(values, index, out):
    out[0] = _column(values, 0) + _column(values, 1) + _column(values, index[0])  # index: int32, as read
    out[1] = _pick((values[0], 7), 1)


def test_an_integer_constant_argument_compiles_one_plain_signature(tmp_path, monkeypatch):
    """Numba would compile `_column` once per constant column and once more for an int32 one; a device function
    gets one int64 signature, and a body that needs the constant (a static index into a heterogeneous tuple)
    gets the literal one."""
    from numba.core import types

    monkeypatch.setenv("LUMOS_CACHE_DIR", str(tmp_path))
    out = np.zeros(2)
    _constants_kernel(np.array([1.0, 2.0, 3.0]), np.array([2], np.int32), out)
    assert out.tolist() == [60.0, 7.0]
    assert list(_column.overloads) == [(types.Array(types.float64, 1, "C"), types.int64)]
    (pick_args,) = _pick.overloads
    assert isinstance(pick_args[1], types.IntegerLiteral) and pick_args[1].literal_value == 1


@njit_serial
def _assign(dst, src):
    dst[1:4] = src


def test_a_slice_assignment_of_the_wrong_size_raises_without_formatting_shapes(tmp_path, monkeypatch):
    """Numba's CPU target formats both shapes into the message, which compiled its integer `str` and string
    joins into every process's first kernel; lumos raises Numba's generic target's plain message instead."""
    monkeypatch.setenv("LUMOS_CACHE_DIR", str(tmp_path))
    dst = np.zeros(5)
    _assign(dst, np.ones(3))
    assert dst.tolist() == [0.0, 1.0, 1.0, 1.0, 0.0]
    with pytest.raises(ValueError, match="^cannot assign slice from input of different size$"):
        _assign(dst, np.ones(2))
