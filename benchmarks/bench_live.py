"""What watching a render costs: path on examples/path/cornell.yaml (256×256, its 64 spp) without a live view, with
the notebook's view (each update a PNG, as `NotebookSink` makes it, without a notebook to send it to) and streaming
to tev (`TevSink`, to a stand-in for tev in another process that reads and drops the packets), all in one process,
the three interleaved round by round so that the machine's drift falls on all alike.

    python benchmarks/bench_live.py [--rounds 7] [--spp 64] [--size 256] [--pass-seconds 1.0]

Prints min / median / max of each render's wall time and of the process's CPU time (`lumos.render` end to end),
the ratios over the render without a view (the least wall times: the rounds where nothing else took a core; the
median CPU times: the work done, whatever else ran), the updates each view showed per render and the time spent
inside them. "null sink" takes each image and drops it: the cost of getting the image out of path after each pass.
Issue 30 asks for at most 5% more.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

from common import machine

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "examples" / "path" / "cornell.yaml"
#: A stand-in for tev: accepts connections, reads everything and drops it; prints its port.
DRAIN = """\
import socket, threading
server = socket.create_server(("127.0.0.1", 0))
print(server.getsockname()[1], flush=True)
def drain(conn):
    with conn:
        while conn.recv(1 << 20):
            pass
while True:
    conn, _ = server.accept()
    threading.Thread(target=drain, args=(conn,), daemon=True).start()
"""


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--pass-seconds", type=float, default=None,
                        help="path's pass length (lumos.methods.path.PASS_SECONDS; default its own, 1 s)")
    args = parser.parse_args(argv)

    import lumos
    from lumos.live import Sink, TevSink, png_bytes
    from lumos.methods import path as path_method

    if args.pass_seconds is not None:
        path_method.PASS_SECONDS = args.pass_seconds

    class PngSink(Sink):
        """NotebookSink's work without a notebook: the PNG of each update."""

        def show(self, image, final):
            png_bytes(image, final)

    class Counting(Sink):
        """Passes each update on to `sink` (which throttles; this does not) and counts those it showed."""

        def __init__(self, sink):
            super().__init__(interval=0.0)
            self.sink, self.shown, self.seconds = sink, 0, 0.0

        def show(self, image, final):
            t0 = time.perf_counter()
            self.shown += bool(self.sink.update(image, final))
            self.seconds += time.perf_counter() - t0

    class NullSink(Sink):
        """Takes every image and does nothing with it: the cost of getting the image out of path each pass."""

        def show(self, image, final):
            pass

    drain = subprocess.Popen([sys.executable, "-c", DRAIN], stdout=subprocess.PIPE, text=True)
    try:
        port = int(drain.stdout.readline())
        scene = lumos.load_scene(SCENE)
        settings = dict(width=args.size, height=args.size, spp=args.spp)
        lumos.render(scene, **{**settings, "spp": 1})  # kernels loaded, caches warm
        views = {"none": lambda: None, "null sink": NullSink, "notebook (PNG)": PngSink,
                 "tev": lambda: TevSink(f"127.0.0.1:{port}")}
        wall = {name: [] for name in views}
        cpu = {name: [] for name in views}
        shown = {name: 0 for name in views}
        inside = {name: 0.0 for name in views}
        passes = 0
        for _ in range(args.rounds):
            for name, make in views.items():
                sink = make()
                counted = None if sink is None else Counting(sink)
                t0, c0 = time.perf_counter(), time.process_time()
                img = lumos.render(scene, live=counted, **settings)
                wall[name].append(time.perf_counter() - t0)
                cpu[name].append(time.process_time() - c0)
                if sink is not None:
                    shown[name] += counted.shown
                    inside[name] += counted.seconds
                    sink.close()
                passes += img.stats["passes"] if name == "none" else 0
    finally:
        drain.kill()
        drain.wait()

    print(f"lumos.render path {SCENE.relative_to(ROOT)} {args.size}x{args.size} {args.spp} spp, "
          f"{passes / args.rounds:.1f} passes a render (PASS_SECONDS {path_method.PASS_SECONDS:g}), "
          f"{args.rounds} rounds; {machine()}")
    def spread(ts):
        return f"{min(ts):.3f} / {statistics.median(ts):.3f} / {max(ts):.3f}"

    print(f"  {'view':15s} {'wall s min / median / max':27s} {'CPU s min / median / max':26s} wall min  CPU median"
          f"  updates  in update")
    for name in views:
        line = f"  {name:15s} {spread(wall[name]):27s} {spread(cpu[name]):26s}"
        if name != "none":
            line += (f" {min(wall[name]) / min(wall['none']):8.3f}  "
                     f"{statistics.median(cpu[name]) / statistics.median(cpu['none']):10.3f}"
                     f"  {shown[name] / args.rounds:7.1f}  {1e3 * inside[name] / args.rounds:6.1f} ms")
        print(line)
    print("  (ratios are over 'none'; updates and the time inside the view's update are per render)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
