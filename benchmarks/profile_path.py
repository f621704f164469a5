"""Where the path tracer's time goes, by source file and line: perf samples of the kernel mapped to lumos's code.

    python benchmarks/profile_path.py [--scene examples/path/cornell.yaml] [--spp 48] [--threads 1] [--lines 40]

Needs Linux `perf` (Debian's linux-perf; the software clock is enough, no hardware counters) and binutils'
`objdump`. Numba's JIT code has no symbols perf can read, and the path kernel is one inlined body, so a function
profile says nothing. Instead this script runs the render in a child process under `perf record -e cpu-clock`,
with `NUMBA_DEBUGINFO=1`. A first child compiles the kernel into an empty `NUMBA_CACHE_DIR` and writes its
object code (`CodeLibrary._get_compiled_object()`); the second, under perf, loads that same code from the cache
and writes the address it runs at. Each sampled instruction address, less that address, is looked up in
`objdump -dl` of the object code, whose debug lines name the source line the instruction came from (after
inlining: a helper's lines are counted wherever it was inlined). The attribution of optimised code to lines is
approximate, by a line or two; the totals by file are solid.

Only the samples at the kernel's addresses count (the import and the warm-up render fall
outside them). The scene renders at its own size with `--spp` samples, `--threads` threads.
"""

from __future__ import annotations

import argparse
import bisect
import collections
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def child(args) -> None:
    """The first child compiles the kernel (into the fresh cache) and writes its object code into args.out; the
    second, under perf, loads that same code from the cache, writes the address it runs at and renders."""
    import warnings

    import lumos
    from lumos.methods import path_trace

    warnings.simplefilter("ignore")  # NUMBA_DEBUGINFO's warnings about generated functions without source

    scene = lumos.load_scene(args.scene)
    settings = dict(method="path", threads=args.threads)
    lumos.render(scene, spp=1, seed=0, **settings)
    overload = path_trace.pass_rows.overloads[path_trace.pass_rows.signatures[0]]
    library = overload.library
    out = Path(args.out)
    if not (out / "kernel.o").exists():
        # compiled here: one object holds the kernel and everything inlined into it (while this process runs
        # it, the parallel loop's body is loaded on its own; loaded back from the cache, it is this object)
        (out / "kernel.o").write_bytes(library._get_compiled_object())
        return
    (out / "kernel.json").write_text(json.dumps(
        {"address": library.get_pointer_to_function(overload.fndesc.llvm_func_name),
         "symbol": overload.fndesc.llvm_func_name}))
    t0 = time.perf_counter()
    lumos.render(scene, spp=args.spp, seed=1, **settings)
    print(f"render: {time.perf_counter() - t0:.2f} s", file=sys.stderr)


def symbol_offset(obj: Path, symbol: str) -> int:
    """The offset of `symbol` in the object's .text (the loader keeps the section whole, so the instruction at
    offset o runs at load address + o − this)."""
    table = subprocess.run(["objdump", "-t", str(obj)], capture_output=True, text=True, check=True).stdout
    for line in table.splitlines():
        if line.endswith(" " + symbol):
            return int(line.split()[0], 16)
    sys.exit(f"profile_path.py: {symbol} is not in the kernel's object code")


def line_table(obj: Path) -> tuple[list[int], dict[int, str]]:
    """Sorted instruction offsets of the object's .text and, for each, 'file.py:line' (paths under lumos/)."""
    text = subprocess.run(["objdump", "-d", "-l", "--no-show-raw-insn", str(obj)], capture_output=True,
                          text=True, check=True).stdout
    current, where = "?", {}
    for line in text.splitlines():
        m = re.match(r"^(/\S+\.py):(\d+)", line)
        if m:
            current = f"{m.group(1).split('/lumos/')[-1]}:{m.group(2)}"
            continue
        m = re.match(r"^\s+([0-9a-f]+):\s", line)
        if m:
            where[int(m.group(1), 16)] = current
    return sorted(where), where


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", default=str(ROOT / "examples" / "path" / "cornell.yaml"))
    parser.add_argument("--spp", type=int, default=48)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--lines", type=int, default=40, help="how many source lines to list")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--out", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args)
        return
    for tool in ("perf", "objdump"):
        if shutil.which(tool) is None:
            sys.exit(f"profile_path.py: needs `{tool}` (apt-get install -y linux-perf binutils)")
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, NUMBA_DEBUGINFO="1", NUMBA_CACHE_DIR=str(Path(tmp) / "cache"))
        data = Path(tmp) / "perf.data"
        run = [sys.executable, __file__, "--child", "--out", tmp, "--scene", args.scene, "--spp", str(args.spp),
               "--threads", str(args.threads)]
        print("compiling the kernel with debug lines (about a minute)...", file=sys.stderr)
        subprocess.run(run, env=env, check=True)
        subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", "-F", "4000", "-o", str(data)] + run, env=env,
                       check=True)
        kernel = json.loads((Path(tmp) / "kernel.json").read_text())
        base = kernel["address"] - symbol_offset(Path(tmp) / "kernel.o", kernel["symbol"])
        ips = subprocess.run(["perf", "script", "-i", str(data), "-F", "ip"], capture_output=True, text=True,
                             check=True).stdout.split()
        offsets, where = line_table(Path(tmp) / "kernel.o")
        size = offsets[-1] + 16 if offsets else 0
        lines, files = collections.Counter(), collections.Counter()
        for ip in ips:
            off = int(ip, 16) - base
            if 0 <= off < size:
                at = where[offsets[bisect.bisect_right(offsets, off) - 1]]
                lines[at] += 1
                files[at.rsplit(":", 1)[0]] += 1
    n = sum(files.values())
    print(f"{n} samples in the kernel ({len(ips)} in the whole process); share of the kernel's samples:")
    for name, count in files.most_common():
        print(f"  {100 * count / n:5.1f}%  {name}")
    print("by line:")
    for name, count in lines.most_common(args.lines):
        print(f"  {100 * count / n:5.1f}%  {name}")


if __name__ == "__main__":
    main()
