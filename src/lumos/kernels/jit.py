"""The one place that decides how kernels are compiled.

No `fastmath`: the watertight triangle test relies on exact IEEE products (FMA contraction would break the
antisymmetry of shared-edge tests), and "no hit yet" comparisons must not be folded away.
"""

import inspect
import os
import zlib

import llvmlite.binding as ll
import numba
from numba.core import errors, types, typing
from numba.core.codegen import JITCodeLibrary
from numba.core.compiler import Compiler
from numba.core.compiler_lock import require_global_compiler_lock
from numba.core.registry import CPUDispatcher
from numba.core.typing.templates import _OverloadFunctionTemplate
from numba.extending import overload

from .cache import OverloadCache, cached

# Device functions: what only other kernels call. Numba compiles every function it meets into a library of its
# own: it generates a CPython and a C wrapper for it (code that unboxes every argument, every array of every
# namedtuple), links in the libraries of its callees, optimises the whole (LLVM O3) and emits machine code, and
# then each caller links those libraries in again and optimises and emits them again, so a function deep in the
# call graph is optimised and emitted once per library above it. A device function here gets neither wrapper, and
# its library is linked and given Numba's cheap module pipeline, but not the full one and no machine code: the
# top-level kernel that links it in optimises everything fully once.
# benchmarks/bench_compile.py, every family from scratch: 365 -> 266 s of compiling, LLVM 219 -> 141 s
# (`_raycast_rows` 33.4 -> 21.2 s); renders as fast, images identical (BENCHMARKS.md).
# A device function is cached on its own too, as that IR (its callees' linked in), stamped with its source closure
# like a kernel: a kernel compiled in another process (another method's first render, a warm-up process, a kernel
# whose own file was edited) loads the device functions it shares instead of typing and lowering them again.
_DEVICE = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True}


class DeviceLibrary(JITCodeLibrary):
    """A device function's code: its IR (function passes run, as Numba does for every function) with its
    callees' linked in and Numba's cheap module pipeline run over it, never emitted; only other libraries link
    it."""

    def finalize(self):
        require_global_compiler_lock()
        self._raise_if_finalized()
        seen = set()
        for library in self._linking_libraries:
            if library not in seen:
                seen.add(library)
                self._reload_init.update(library._reload_init)
                self._final_module.link_in(library._get_module_for_linking(), preserve=True)
        # Numba's cheap module pipeline (inlining and simplification), as it runs before its full one: the callee
        # reaches its callers smaller, and their inliner takes it as it took the fully optimised one (A/B:
        # without it the path tracer measured ~4% slower; with the full pipeline no faster than with this)
        mpm, mpb = self._codegen._module_pass_manager(loop_vectorize=self._codegen._loopvect, slp_vectorize=False,
                                                      opt=self._codegen._opt_level, cost="cheap")
        mpm.run(self._final_module, mpb)
        self._finalized = True

    def get_pointer_to_function(self, name):
        self._ensure_finalized()
        return 0  # no machine code: Python calls go to the DeviceDispatcher's twin

    #: the kind of entry the kernel cache holds for a device function (Numba's are "bitcode" and "object")
    KIND = "lumos-device"

    def serialize_using_object_code(self):
        """What the kernel cache keeps: the IR as callers link it (exported functions linkonce_odr), callees
        included, as compressed bitcode (a third of its size, in 2 ms a function); there is no machine code."""
        return (self.name, self.KIND, zlib.compress(self._get_module_for_linking().as_bitcode(), 1))

    @classmethod
    def unserialize(cls, codegen, libdata):
        """A finalized library from a cache entry that `serialize_using_object_code` wrote."""
        name, kind, bitcode = libdata
        if kind != cls.KIND:
            raise ValueError(f"not a device library's cache entry: {kind!r}")
        library = cls(codegen, name)
        library._final_module = library._shared_module = ll.parse_bitcode(zlib.decompress(bitcode))
        library._finalized = True
        return library

    @property
    def codegen(self):
        return _NoEnvCodegen(self._codegen)


class _NoEnvCodegen:
    """The shared codegen, except that a device library has no environment global of its own to set (its module
    never reaches the JIT engine; Numba would write the address of the function's environment to address 0).
    Device functions box nothing and call back into no Python object, so their copies never read it."""

    def __init__(self, codegen):
        self._codegen = codegen

    def set_env(self, env_name, env):
        pass

    def __getattr__(self, name):
        return getattr(self._codegen, name)


class DeviceCompiler(Compiler):
    """Numba's compiler pipeline, lowering into a `DeviceLibrary`."""

    def __init__(self, typingctx, targetctx, library, args, return_type, flags, locals):
        if library is None:
            library = DeviceLibrary(targetctx.codegen(), "lumos_device")
        super().__init__(typingctx, targetctx, library, args, return_type, flags, locals)


def _plain(arg):
    """The type a device function is compiled for when called with `arg`: int64 for a signed integer (constant
    or narrower), `arg` otherwise (see `DeviceDispatcher.get_call_template`)."""
    if isinstance(arg, types.IntegerLiteral):
        arg = types.unliteral(arg)
    if isinstance(arg, types.Integer) and arg.signed and arg.bitwidth < 64:
        return types.int64
    return arg


class DeviceDispatcher(CPUDispatcher):
    """A device function's dispatcher: jitted callers link its `DeviceLibrary`; a call from Python (tests, a
    Python helper) goes to a twin compiled as an ordinary kernel (with wrappers, cached apart)."""

    def get_call_template(self, args, kws):
        """Numba's, except that an integer argument, constant or narrow, is typed as a plain int64: Numba would
        compile the callee once per constant (`rand01` seven times, one per random dimension; `_log3` sixteen,
        one per log column; a loop counter that starts at 0 twice) and once more for an int32 (an index read
        from an int32 array: `sample_light`, `intersect_triangle`, `clip_polygon` and eight more compiled twice).
        Unsigned integers keep their type (the random numbers' hashes wrap on purpose). Boolean constants stay
        literal (LLVM folds them), but Numba still types and compiles both sides of a branch on one: code to be
        left out is selected by a None argument and an `is None` test, which Numba prunes before typing
        (raycast's `shadows`, `traverse._pass_through`'s `shaped`). A body that needs the constant itself (a
        static index into a heterogeneous tuple) still gets it: its plain compile fails to type, and the literal
        one is made."""
        pysig, args = self._compiler.fold_argument_types(args, kws)
        if self._can_compile:
            plain = tuple(_plain(a) for a in args)
            try:
                self.compile(plain)
            except errors.TypingError:
                if plain == tuple(args):
                    raise
                self.compile(tuple(args))
        name = self.py_func.__name__
        template = typing.make_concrete_template(f"CallTemplate({name})", key=name,
                                                 signatures=self.nopython_signatures)
        return template, pysig, args, {}

    def __call__(self, *args, **kwargs):
        twin = self.__dict__.get("_python_twin")
        if twin is None:
            options = {k: v for k, v in self.targetoptions.items() if k not in _DEVICE and k != "nopython"}
            twin = self._python_twin = cached(numba.njit(cache=False, **options)(self.py_func), prefix="py")
        return twin(*args, **kwargs)


def _cached_overload(jitter):
    """Numba's jit decorator for an `@overload`'s implementation, which, when the implementation is Numba's or
    lumos's and comes from a source file (not `exec`), compiles it as a device function (`DeviceCompiler`: no
    wrappers, no machine code of its own; its callers link its IR in, as they did) and keeps it in the kernel
    cache (`cache.OverloadCache`)."""

    def jit_cached(*args, **options):
        decorate = jitter(*args, **options)

        def wrap(py_func):
            module = str(getattr(py_func, "__module__", None) or "").split(".")[0]
            source = inspect.getsourcefile(py_func) if module in ("numba", __name__.split(".")[0]) else None
            if args or "pipeline_class" in options or not source or not os.path.isfile(source):
                return decorate(py_func)
            dispatcher = jitter(**{**options, **_DEVICE}, pipeline_class=DeviceCompiler)(py_func)
            if type(dispatcher) is not CPUDispatcher:  # (NUMBA_DISABLE_JIT: the function itself)
                return dispatcher
            return cached(dispatcher, prefix="dol", library_class=DeviceLibrary, cache_class=OverloadCache)

        return wrap

    return jit_cached


def _cache_overloads():
    """Numba compiles the implementation of each `@overload` it meets (its own `np.empty`, `max`, `hasattr`…, and
    `simd`'s) into a dispatcher of its own, with a Python wrapper, its own full optimisation and machine code
    that nothing runs (its callers link its IR in), and without a cache, so every process compiled them again:
    79 of them, 3.1-3.3 s of ray casting's first compile. From here on they compile as device functions (1.2 s)
    and are cached. Numba's overload templates take their jit decorator from `_get_jit_decorator`, which is
    wrapped once, for every function compiled in this process."""
    numba_decorator = _OverloadFunctionTemplate._get_jit_decorator
    if getattr(numba_decorator, "_lumos", False):
        return

    def _get_jit_decorator(self):
        jitter = numba_decorator(self)
        return _cached_overload(jitter) if jitter is numba.jit else jitter

    _get_jit_decorator._lumos = True
    _OverloadFunctionTemplate._get_jit_decorator = _get_jit_decorator


_cache_overloads()


def _shape_mismatch(src_shapes, index_shape):
    """What a slice assignment of the wrong size raises (see `_plain_shape_errors`)."""
    raise ValueError("cannot assign slice from input of different size")


@overload(_shape_mismatch, target="generic")
def _shape_mismatch_jit(src_shapes, index_shape):
    def impl(src_shapes, index_shape):
        raise ValueError("cannot assign slice from input of different size")

    return impl


def _plain_shape_errors():
    """Numba's CPU target raises a slice assignment's size mismatch (`a[i, :6] = box`, `row[:] = (x, y)`: every
    kernel has one) with both shapes in the message, formatted at run time, so the first such assignment in a
    process compiled Numba's integer `str`, `repr`, string joins and concatenation: 0.9 s of the BVH build's
    first compile, the warm-up's serial start. The message without the shapes is Numba's own for its generic
    target; lumos's assignments are sized by construction, so the error would be lumos's bug either way."""
    from numba.np import arrayobj

    arrayobj.raise_with_shape_context = _shape_mismatch


_plain_shape_errors()


def _cached_njit(device=False, **options):
    """`numba.njit(**options)` whose dispatchers keep their code in lumos's kernel cache (`cache.KernelCache`:
    stamped with each kernel's source closure, kept in the package or the user's cache folder), or with `device`
    a `DeviceDispatcher` (see above), cached as its `DeviceLibrary`'s IR."""
    compile_ = numba.njit(cache=False, **options)

    def decorate(py_func):
        if not device:
            dispatcher = compile_(py_func)
            return cached(dispatcher) if hasattr(dispatcher, "py_func") else dispatcher  # NUMBA_DISABLE_JIT=1
        if numba.config.DISABLE_JIT:
            return py_func
        dispatcher = DeviceDispatcher(py_func=py_func, locals={},
                                      targetoptions={"nopython": True, **options, **_DEVICE},
                                      pipeline_class=DeviceCompiler)
        return cached(dispatcher, prefix="dev", library_class=DeviceLibrary)

    return decorate


#: Device functions (intersection, traversal, shading: everything on the per-ray path), linked into the kernels that
#: call them (`DeviceLibrary` above). They are
#: compiled without Numba's runtime (NRT): they allocate nothing, and their callers own every array they see, so
#: they need no reference counts. With the runtime, each call that is not inlined increments and decrements the
#: count of every array in its tuple arguments (30 calls on entry and 30 on exit for `whitted.trace`), which took a
#: quarter of the ray tracers' time (perf: NRT_incref, NRT_decref) and bounced shared counters between cores.
#: (`_nrt` is the option Numba's own `register_jitable(_nrt=False)` uses.) Every decorator here states `_nrt` and
#: `forceinline`: an option a function does not state is inherited from the caller being compiled.
njit = _cached_njit(device=True, nogil=True, error_model="numpy", _nrt=False, forceinline=False)
#: Device functions on the per-ray path that are inlined into their callers (LLVM alwaysinline). Numba passes
#: every array of a namedtuple argument as its own fields (`closest_hit` takes 96 machine arguments,
#: `illuminate_coeffs` 220), most of them on the stack, at each call that is not inlined.
njit_inline = _cached_njit(device=True, nogil=True, error_model="numpy", _nrt=False, forceinline=True)
#: Helpers that allocate arrays (BVH build, raster bins, scratch buffers, csg crossing lists): with the runtime,
#: said explicitly, since a function called from a device function would otherwise inherit its "no runtime".
njit_alloc = _cached_njit(device=True, nogil=True, error_model="numpy", _nrt=True, forceinline=False)
#: Top-level kernels: called from Python, over a range of rows (or rays, chunks, tasks), serially, with the GIL
#: released, so that `threads.parallel_for` runs several at once on Python threads. (Not `parallel=True`: Numba
#: optimises each `prange` body apart from its kernel, which doubled LLVM's share of the compile; see `threads`.)
#: A kernel that reads the scene through views (`views.geometry_of`...) builds them in a device function it calls,
#: never itself: the views hold no references, and a kernel with Numba's runtime would release them (BENCHMARKS:
#: `views.owned_views` in the kernel instead made ray casting 27% slower).
njit_serial = _cached_njit(nogil=True, error_model="numpy", _nrt=True, forceinline=False)
