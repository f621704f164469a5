"""Where compiled kernels are kept, and when they are stale.

Numba's own cache stamps a function with the hash of its *own* file. A lumos kernel also inlines functions from
other files, and reads constants (`layout`'s columns, `config`'s epsilons) from others again, so a change to any of
those must recompile it, and a change to anything else must not. `KernelCache` stamps each kernel with the sha256
of its **source closure** (`source_closure`): its own file, every lumos file that a name it reads comes from, and
the closures of the kernels it calls, found from the code itself (the names each function's bytecode loads,
resolved in its module). Editing `kernels/raster.py` leaves the path tracer's cache valid; editing
`kernels/traverse.py` makes every ray method's stale. Numba's index also keys each entry on the signature, the CPU
(name and features), the Numba version and the function's bytecode, so code compiled elsewhere is never loaded.

The folders (`cache_dirs`), in the order they are read:

    LUMOS_CACHE_DIR          if set, this folder alone (benchmarks use a fresh one to time a cold start), else
    NUMBA_CACHE_DIR/lumos    if NUMBA_CACHE_DIR is set, this folder alone, else
    <package>/_kernel_cache  if writable (the wheel that `pip install .` builds ships its kernels here), else
    ~/.cache/lumos/kernels   (under XDG_CACHE_HOME if set) for a read-only install, written first and read first,
                             then <package>/_kernel_cache read, so a read-only install still finds its kernels.

Entries are written whole (Numba writes a temporary file and renames it) and the index of a function is updated
under a file lock, so processes warming the same cache in parallel (`lumos warmup`) lose no entry.

**One compile per entry, whichever process gets there first.** A process that finds no entry *claims* it (a
`.claim` file beside the index, made with O_EXCL, holding its host and process id) before compiling, and drops the claim
once the entry is saved (or the compile failed). Another process that needs the same entry meanwhile waits for it
and loads it, instead of compiling it a second time on the other core: the warm-up's families share device
functions, and a cold render shares its compile with a helper process (`methods.compile_plan`). A claim whose
process is gone, or that is held longer than `CLAIM_WAIT_S`, is not waited for. Waiting cannot deadlock: a
process waits only from inside the compile of a caller of the claimed function, and the call graph has no cycles.
"""

from __future__ import annotations

import contextlib
import dis
import hashlib
import os
import socket
import sys
import time
import types
from functools import lru_cache
from pathlib import Path

import numba
from numba.core.caching import CompileResultCacheImpl, FunctionCache, IndexDataCacheFile, _CacheLocator
from numba.core.compiler import CompileResult
from numba.core.runtime.nrt import rtsys
from numba.core.targetconfig import ConfigStack

try:
    import fcntl
except ImportError:  # not POSIX: index updates are then not locked (Numba's own behaviour)
    fcntl = None

#: the lumos package folder (the parent of `kernels/`)
PACKAGE = Path(__file__).resolve().parent.parent
_PACKAGE_NAME = __name__.split(".")[0]


def packaged_dir() -> Path:
    """The cache folder inside the installed package (filled when a wheel is built)."""
    return PACKAGE / "_kernel_cache"


def _writable(folder: Path) -> bool:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
        return True
    except OSError:
        return False


@lru_cache(maxsize=None)
def _cache_dirs(lumos_dir: str, numba_dir: str) -> tuple[Path, ...]:
    if lumos_dir:
        return (Path(lumos_dir).expanduser().resolve(),)
    if numba_dir:
        return (Path(numba_dir).expanduser().resolve() / "lumos",)
    packaged = packaged_dir()
    if _writable(packaged):
        return (packaged,)
    user = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "lumos" / "kernels"
    return (user, packaged)


def cache_dirs() -> tuple[Path, ...]:
    """The folders kernels are read from, the first also written to (see the module's docstring)."""
    return _cache_dirs(os.environ.get("LUMOS_CACHE_DIR", ""), os.environ.get("NUMBA_CACHE_DIR", ""))


# -- the source closure of a kernel ---------------------------------------------------------------------------

def _loaded_names(code: types.CodeType) -> set[str]:
    """Global and attribute names that `code` and the functions nested in it load."""
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _loaded_names(const)
    return names


@lru_cache(maxsize=None)
def _import_table(path: str, module: str, ours: frozenset) -> dict[str, str]:
    """name bound by a module-level import in `module` (whose file is `path`) -> the module it comes from
    ("lumos.kernels.layout" for `from . import layout` and for `from .layout import MAT_KD`), for lumos's own
    modules, so that a constant imported by value is traced to its file. Read from the module's bytecode (the
    cached .pyc: quick), not its source."""
    loader = getattr(getattr(sys.modules.get(module), "__spec__", None), "loader", None)
    try:
        code = loader.get_code(module)
    except Exception:  # no loader that gives code (a frozen or built-in module): nothing imported to trace
        return {}
    package = module.split(".") if Path(path).name == "__init__.py" else module.split(".")[:-1]
    table, consts, source, binding = {}, [None, None], None, None
    for ins in dis.get_instructions(code):
        if ins.opname == "LOAD_CONST":
            consts = [consts[1], ins.argval]
        elif ins.opname == "IMPORT_NAME":
            level, name = consts[0] or 0, ins.argval
            base = package[: len(package) - level + 1] if level else []
            source = ".".join(base + ([name] if name else []))
            binding = source if level or consts[1] else source.split(".")[0]  # `import a.b` binds a
        elif ins.opname == "IMPORT_FROM" and source is not None:
            sub = f"{source}.{ins.argval}"
            binding = sub if sub in sys.modules else source
        elif ins.opname in ("STORE_NAME", "STORE_GLOBAL") and binding is not None:
            table[ins.argval] = binding
            binding = None
    return {k: v for k, v in table.items() if v.split(".")[0] in ours}


@lru_cache(maxsize=None)
def _module_file(name: str):
    module = sys.modules.get(name)
    path = getattr(module, "__file__", None)
    return str(Path(path).resolve()) if path else None


def _is_dispatcher(obj) -> bool:
    return hasattr(obj, "py_func") and hasattr(obj, "overloads")


def source_closure(py_func) -> set[str]:
    """The source files a compiled `py_func` depends on (absolute paths): its own, the files of the names it
    loads from lumos or its own package (functions, classes, modules, and constants imported by value), and
    those of the kernels it calls, recursively; and always `kernels/jit.py`, which holds the compile options."""
    ours = {_PACKAGE_NAME, py_func.__module__.split(".")[0]}
    files: set[str] = {str(Path(__file__).resolve().with_name("jit.py"))}
    seen: set[int] = set()
    todo = [py_func]
    while todo:
        func = todo.pop()
        if id(func) in seen:
            continue
        seen.add(id(func))
        own = _module_file(func.__module__)
        if own is None:
            continue
        files.add(own)
        imports = _import_table(own, func.__module__, frozenset(ours))
        names = _loaded_names(func.__code__)
        cells = [c.cell_contents for c in (func.__closure__ or ()) if _cell_filled(c)]
        values = [func.__globals__.get(n) for n in names] + cells
        for name in names & imports.keys():  # a constant or function imported by name: its module's file
            path = _module_file(imports[name])
            if path:
                files.add(path)
        for value in values:
            if _is_dispatcher(value):
                todo.append(value.py_func)
            elif isinstance(value, types.ModuleType) and value.__name__.split(".")[0] in ours:
                if getattr(value, "__file__", None):
                    files.add(str(Path(value.__file__).resolve()))
                todo.extend(a.py_func for a in (getattr(value, n, None) for n in names) if _is_dispatcher(a))
            elif isinstance(value, types.FunctionType) and value.__module__.split(".")[0] in ours:
                todo.append(value)  # an @overload stub or a plain helper: its file, and what it loads
            elif str(getattr(value, "__module__", "")).split(".")[0] in ours:
                path = _module_file(value.__module__)  # a class (namedtuple layouts)
                if path:
                    files.add(path)
    return files


def _cell_filled(cell) -> bool:
    try:
        cell.cell_contents
        return True
    except ValueError:
        return False


@lru_cache(maxsize=None)
def _file_digest(path: str, mtime_ns: int, size: int) -> bytes:
    return hashlib.sha256(Path(path).read_bytes()).digest()


def closure_stamp(py_func) -> str:
    """sha256 over the (package-relative) names and contents of `source_closure(py_func)`."""
    digest = hashlib.sha256()
    for path in sorted(source_closure(py_func)):
        st = os.stat(path)
        rel = os.path.relpath(path, PACKAGE) if path.startswith(str(PACKAGE)) else "/".join(Path(path).parts[-2:])
        digest.update(rel.encode() + b"\0" + _file_digest(path, st.st_mtime_ns, st.st_size))
    return digest.hexdigest()


# -- Numba's cache, with the closure stamp and lumos's folders ----------------------------------------------------

class KernelLocator(_CacheLocator):
    """Caches a lumos function under `<cache dir>/<its folder relative to the package>/`."""

    def __init__(self, py_func, py_file):
        self._py_func = py_func
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        folder = Path(py_file).resolve().parent
        try:
            self._subdir = folder.relative_to(PACKAGE)
        except ValueError:  # code outside lumos made with lumos's decorators (tests, users' kernels): by module
            self._subdir = Path("_other") / py_func.__module__
        self._stamp = None

    def paths(self) -> list[str]:
        return [str(root / self._subdir) for root in cache_dirs()]

    def get_cache_path(self):
        return self.paths()[0]

    def get_source_stamp(self):
        if self._stamp is None:  # computed at the first load or save, once every module is imported
            if self._py_func.__module__.split(".")[0] == "numba":  # Numba's own overloads: its version's
                self._stamp = f"numba {numba.__version__}"
            else:
                self._stamp = closure_stamp(self._py_func)
        return self._stamp

    def get_disambiguator(self):
        return str(self._lineno)

    @classmethod
    def from_function(cls, py_func, py_file):
        return cls(py_func, py_file)


class _KernelCacheImpl(CompileResultCacheImpl):
    _locator_classes = [KernelLocator]
    #: for a device function's cache, the code library class that reads its entries back
    #: (`library_class.unserialize(codegen, libdata)`); None for a kernel's, which Numba reads back
    library_class = None

    def reduce(self, cres):
        """Numba's `CompileResult._reduce`, without the type annotation: Numba writes it out as text (the source,
        each line annotated with its variables' types; 2 ms a function, 0.4 s of ray casting's first compile), and
        nothing reads it back (a loaded kernel's `inspect_types` shows none)."""
        libdata = cres.library.serialize_using_object_code()
        fndesc = cres.fndesc
        fndesc.typemap = fndesc.calltypes = None  # (as Numba: not needed, and they may not pickle)
        return (libdata, fndesc, cres.environment, cres.signature, cres.objectmode, cres.lifted, "",
                cres.reload_init, tuple(cres._find_referenced_environments()))

    def rebuild(self, target_context, payload):
        if self.library_class is None:
            return super().rebuild(target_context, payload)
        return _rebuild(target_context, self.library_class.unserialize(target_context.codegen(), payload[0]),
                        *payload[1:])


def _rebuild(target_context, library, fndesc, env, signature, objectmode, lifted, typeann, reload_init,
             referenced_envs) -> CompileResult:
    """Numba's `CompileResult._rebuild`, given the library rather than the data Numba's own class reads."""
    for fn in reload_init or ():
        fn()
    result = CompileResult(target_context=target_context, typing_context=target_context.typing_context,
                           library=library, environment=env,
                           entry_point=target_context.get_executable(library, fndesc, env), fndesc=fndesc,
                           type_annotation=typeann, signature=signature, objectmode=objectmode, lifted=lifted,
                           typing_error=None, call_helper=None, metadata=None, reload_init=reload_init,
                           referenced_envs=referenced_envs)
    for env in referenced_envs:
        library.codegen.set_env(env.env_name, env)
    return result


class _LockedIndexFile(IndexDataCacheFile):
    """Numba's index-and-data files, with the read-modify-write of the index under a lock on the folder."""

    def save(self, key, data):
        with _folder_lock(self._cache_path):
            super().save(key, data)


@contextlib.contextmanager
def _folder_lock(folder: str):
    if fcntl is None:
        yield
        return
    with open(os.path.join(folder, ".lock"), "a+b") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


#: the longest a compile waits for an entry another process has claimed (seconds; the longest compile of one
#: function, a method's top-level kernel with its callees, takes about 20 s on a slow core)
CLAIM_WAIT_S = 120.0
_POLL_S = 0.005


_HOST = socket.gethostname()


def _claim_holder(path: str):
    """The process a claim file names ("host pid"), "" while its writer has not written it yet, None if it is
    gone."""
    try:
        with open(path) as handle:
            return handle.read().strip()
    except OSError:
        return None


def _alive(holder: str) -> bool:
    """Whether the claim's process is running: on another host (a cache folder shared by cluster workers) it is
    taken to be, and `CLAIM_WAIT_S` bounds the wait."""
    host, _, pid = holder.rpartition(" ")
    if host != _HOST:
        return True
    try:
        os.kill(int(pid), 0)
    except (ProcessLookupError, ValueError):
        return False
    except OSError:  # (someone else's process: alive)
        return True
    return True


class KernelCache(FunctionCache):
    """Numba's function cache, stamped with the source closure, read from every folder of `cache_dirs` and
    written to the first, with a claim on an entry while it compiles (the module's docstring); the stamp is
    computed when the cache is first used, not when the kernel is defined."""

    _impl_class = _KernelCacheImpl
    #: whether entries are claimed while they compile
    claims = True

    def __init__(self, py_func):  # Numba's __init__ stamps eagerly; everything else is Numba's
        self._name = repr(py_func)
        self._py_func = py_func
        self._impl = self._impl_class(py_func)
        self._files = None
        self._held: dict[str, str] = {}  # the claims this process holds: repr(key) -> file
        self.enable()

    @property
    def cache_path(self):
        return self._impl.locator.get_cache_path()

    def _index_files(self) -> list[_LockedIndexFile]:
        locator = self._impl.locator
        paths = locator.paths()
        if self._files is None or [f._cache_path for f in self._files] != paths:
            stamp = locator.get_source_stamp()
            self._files = [_LockedIndexFile(p, self._impl.filename_base, stamp) for p in paths]
        return self._files

    @property
    def _cache_file(self):
        return self._index_files()[0]

    def load_overload(self, sig, target_context):
        """Numba's, without its refresh of the target context first: that installs every lowering and typing
        registry Numba has (0.25 s in a fresh process: a tenth of the radiosity box's warm first render), which only
        a compile needs, and a compile refreshes the context itself (`CompilerBase`). Code read back needs only
        the runtime's functions to link against, initialised here."""
        rtsys.initialize(target_context)
        with self._guard_against_spurious_io_errors():
            data = self._load_overload(sig, target_context)
            if data is None and self.claims and self._enabled:
                data = self._claim_or_wait(sig, target_context)
            return data

    def _claim_or_wait(self, sig, target_context):
        """Claim the entry for `sig` (then return None: the caller compiles it and `save_overload` drops the
        claim), or, while another live process holds the claim, wait for the entry and return it loaded."""
        key = self._index_key(sig, target_context.codegen())
        if key is None:
            return None
        name = repr(key)
        digest = hashlib.sha256(name.encode()).hexdigest()[:24]
        path = os.path.join(self._impl.locator.get_cache_path(), f"{self._impl.filename_base}.{digest}.claim")
        deadline = time.monotonic() + CLAIM_WAIT_S
        unwritten_since = None
        try:
            os.makedirs(os.path.dirname(path), exist_ok=True)
        except OSError:  # a folder this process cannot write: no claims, as before them
            return None
        while True:
            try:
                fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                holder = _claim_holder(path)
                if holder == "":  # being written, or left empty by a writer that died at once
                    unwritten_since = unwritten_since or time.monotonic()
                    stale = time.monotonic() - unwritten_since > 1.0
                else:
                    unwritten_since = None
                    stale = holder is not None and (holder == f"{_HOST} {os.getpid()}" or not _alive(holder))
                if stale:
                    with contextlib.suppress(OSError):
                        os.unlink(path)
                    continue
                if time.monotonic() > deadline:
                    return None  # compiled here as well, unclaimed
                time.sleep(_POLL_S)
                data = self._load_overload(sig, target_context)
                if data is not None:
                    return data
                continue
            except OSError:  # a folder this process cannot write: no claims, as before them
                return None
            with os.fdopen(fd, "w") as handle:
                handle.write(f"{_HOST} {os.getpid()}")
            self._held[name] = path
            data = self._load_overload(sig, target_context)  # saved between the first look and the claim
            if data is not None:
                self.release_claims()
            return data

    def release_claims(self) -> None:
        """Drop the claims this process holds on this function's entries (after a save, or a failed compile)."""
        for path in self._held.values():
            with contextlib.suppress(OSError):
                os.unlink(path)
        self._held.clear()

    def _load_overload(self, sig, target_context):
        if not self._enabled:
            return None
        key = self._index_key(sig, target_context.codegen())
        if key is None:
            return None
        for index in self._index_files():
            data = index.load(key)
            if data is not None:
                return self._impl.rebuild(target_context, data)
        return None

    def _save_overload(self, sig, data):
        try:
            super()._save_overload(sig, data)
        except OSError:
            pass  # an unwritable cache folder: the kernel stays compiled for this process only
        finally:
            self.release_claims()


class OverloadCache(KernelCache):
    """The cache of an `@overload`'s implementation (Numba's own `np.empty`, `max`, `hasattr`…, which Numba
    compiles again in every process: 79 of them, 3.2 s of ray casting's first compile). Keyed as Numba keys any
    entry, by the signature, the bytecode and the closure's cell contents (which the overload chose for the
    argument types), and stamped with Numba's version; an implementation whose cells or code do not pickle is
    compiled and not kept."""

    claims = False  # (small, and compiled from inside Numba's typing of a caller: never waited for)

    #: the options an implementation takes from the function that calls it (Numba's `inherit_if_not_set`): Numba
    #: keeps one implementation per caller's options in a process, so the cache keys them too (an implementation
    #: compiled without the runtime, for a device function, never reaches a kernel that counts references)
    INHERITED = ("nrt", "error_model", "fastmath", "forceinline")

    def _index_key(self, sig, codegen):
        try:
            key = super()._index_key(sig, codegen)
        except Exception:  # (cloudpickle's errors for a cell it cannot pickle are of no one class)
            return None
        caller = ConfigStack.top_or_none()  # the caller's options while it types this call, at load and at save
        return key + (tuple(str(getattr(caller, name, None)) for name in self.INHERITED),)

    def _save_overload(self, sig, data):
        if self._index_key(sig, data.codegen) is None:
            return
        try:
            super()._save_overload(sig, data)
        except Exception:  # what it refers to does not pickle (a generator in its environment): not kept
            pass


def has_entries(dispatcher) -> bool:
    """Whether a cache folder holds entries of `dispatcher` for its sources as they are (compiled before, for
    some signature): a quick test that a first run is cold, which reads the index and no entry. True when Numba
    compiles nothing (NUMBA_DISABLE_JIT: the kernels are Python functions)."""
    cache = getattr(dispatcher, "_cache", None)
    return cache is None or any(f._load_index() for f in cache._index_files())


def has_entry_for(dispatcher, first_arg) -> bool:
    """Whether a cache folder holds an entry of `dispatcher` for its sources as they are whose first argument is of
    type `first_arg` (whatever the others): whether it was compiled for those arrays before
    (`methods.common.kernel_arrays`). True when Numba compiles nothing (NUMBA_DISABLE_JIT)."""
    cache = getattr(dispatcher, "_cache", None)
    if cache is None:
        return True
    return any(key[0] and key[0][0] == first_arg for f in cache._index_files() for key in f._load_index())


def cached(dispatcher, prefix: str = "", library_class=None, cache_class=KernelCache):
    """Give a Numba dispatcher (compiled with `cache=False`) a `KernelCache` (or `cache_class`); `prefix` names
    its entries apart from another dispatcher's of the same function (Numba's index keys leave the compile
    options out); `library_class` reads back the entries of a dispatcher whose code library is not Numba's (a
    device function's, `jit.DeviceLibrary`)."""
    dispatcher._cache = cache_class(dispatcher.py_func)
    if prefix:
        dispatcher._cache._impl._filename_base = f"{prefix}-{dispatcher._cache._impl._filename_base}"
    dispatcher._cache._impl.library_class = library_class
    if dispatcher._cache.claims:
        compile_ = dispatcher.compile

        def compile(sig):
            try:
                return compile_(sig)
            finally:  # a compile that failed (a signature Numba refused) leaves no claim behind
                dispatcher._cache.release_claims()

        dispatcher.compile = compile
    return dispatcher


