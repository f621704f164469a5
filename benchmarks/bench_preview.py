"""The preview page's costs and latencies (docs/preview.md), on examples/showcase.yaml at 320x240.

    python benchmarks/bench_preview.py [--rounds 3] [--spp 256] [--no-browser] [--screenshots docs/images/preview]

    page open cost     a path render (`lumos.render(..., on_pass=...)`, the showcase at 320x240, --spp samples)
                       with the preview page open on it, as `lumos render --preview` serves it, against the same
                       render with no page: the issue asks for at most 5% longer. With Chromium (Debian's
                       chromium and chromium-driver, driven by Selenium) the page is a real browser tab on this
                       machine, decoding and drawing every frame on the same cores; with --no-browser a WebSocket
                       client that receives every frame
    first image        `lumos serve` started in a new process (warm kernel cache) to the first frame received
                       over its WebSocket (interpreter start, imports, load, compile, the quick pass); and a page
                       opened on a running server to its first image on the canvas (asked: within 1 s)
    change -> image    a slider moved on the page to the first image of the change drawn on its canvas, as the
                       page measures it (performance.now() from the change sent to the image drawn; asked: within
                       0.5 s): the red material's kd (the scene recompiled: the bunny's BVH), the key light's
                       intensity (recompiled too), a camera orbit (nothing recompiled). Without a browser, the
                       same over a WebSocket client: the edit sent to the first frame of its generation received

Each figure is given as min / median / max over --rounds rounds (latencies: 5 changes a round). --screenshots DIR
also writes the pictures of docs/preview.md.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

from common import machine

ROOT = Path(__file__).resolve().parent.parent
SHOWCASE = ROOT / "examples" / "showcase.yaml"
SIZE = {"width": 320, "height": 240}


def chromium_driver(width=1400, height=900):
    """A headless Chromium under Selenium, or None where either is missing."""
    if shutil.which("chromium") is None or shutil.which("chromedriver") is None:
        return None
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        return None
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 f"--window-size={width},{height}", "--force-device-scale-factor=1", "--hide-scrollbars"):
        options.add_argument(flag)
    return webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=options)


def wait_until(driver, script, timeout=60.0):
    deadline = time.perf_counter() + timeout
    while time.perf_counter() < deadline:
        value = driver.execute_script(script)
        if value:
            return value
        time.sleep(0.01)
    raise RuntimeError(f"timed out: {script}")


class SocketPage:
    """A page without a browser: a WebSocket client in a thread that receives every message."""

    def __init__(self, url: str):
        from websockets.sync.client import connect

        self.ws = connect(url.replace("http://", "ws://").replace("/?", "/ws?"), open_timeout=30)
        self.frames = []  # (time received, meta)
        self.replies = []
        self._meta = None
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self):
        try:
            for message in self.ws:
                if isinstance(message, bytes):
                    self.frames.append((time.perf_counter(), self._meta))
                    continue
                data = json.loads(message)
                if data["type"] == "frame":
                    self._meta = data
                else:
                    self.replies.append(data)
        except Exception:
            return

    def send(self, message):
        self.ws.send(json.dumps(message))

    def close(self):
        self.ws.close()
        self._thread.join(timeout=5)


def spread(values):
    return min(values), statistics.median(values), max(values)


# ------------------------------------------------------------------------------------------ page open cost


def page_open_cost(rounds: int, spp: int, browser: bool):
    """Render seconds of the path render without and with the page open, alternating."""
    import lumos
    from lumos.api import resolve_settings
    from lumos.preview.server import PreviewServer
    from lumos.preview.session import Session

    settings = dict(method="path", spp=spp, **SIZE)
    lumos.render(SHOWCASE, **dict(settings, spp=4))  # warm: kernels loaded in this process
    without, with_page, frames = [], [], []
    for _ in range(rounds):
        without.append(lumos.render(SHOWCASE, on_pass=lambda image: None, **settings).stats["render_s"])
        scene = lumos.load_scene(SHOWCASE)
        session = Session.viewer(scene, resolve_settings(scene, settings), path=SHOWCASE.name)
        server = PreviewServer(session).start()
        driver = chromium_driver() if browser else None
        page = None
        try:
            if driver is not None:
                driver.get(server.url)
                wait_until(driver, "return window.lumos && window.lumos.state")
            else:
                page = SocketPage(server.url)
            image = lumos.render(SHOWCASE, on_pass=session.show, **settings)
            session.show(image, final=True)
            with_page.append(image.stats["render_s"])
            if driver is not None:
                wait_until(driver, "return window.lumos.lastFrame && window.lumos.lastFrame.stage === 'shown'")
                frames.append(driver.execute_script("return window.lumos.frames"))
            else:
                time.sleep(0.3)
                frames.append(len(page.frames))
        finally:
            if driver is not None:
                driver.quit()
            if page is not None:
                page.close()
            server.stop()
            session.close()
    return without, with_page, frames


# ------------------------------------------------------------------------------------------- first image


def serve_to_first_frame(rounds: int):
    """`lumos serve` in a new process to the first frame over the socket (seconds)."""
    from websockets.sync.client import connect

    times = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "lumos", "serve", str(SHOWCASE), "--width", "320",
                                 "--height", "240"], stderr=subprocess.PIPE, text=True,
                                env=dict(os.environ, PYTHONUNBUFFERED="1"))
        try:
            url = None
            for line in proc.stderr:
                if "preview at" in line:
                    url = line.split(" at ", 1)[1].strip()
                    break
            with connect(url.replace("http://", "ws://").replace("/?", "/ws?"), open_timeout=30) as ws:
                while not isinstance(ws.recv(timeout=60), bytes):
                    pass
                times.append(time.perf_counter() - t0)
        finally:
            proc.terminate()
            proc.wait(timeout=30)
    return times


# ---------------------------------------------------------------------------------------- change -> image


EDITS = {
    # each value differs from the one before (and from the scene's own), so each change recompiles
    "material kd": lambda k: {"type": "material", "name": "red", "key": "kd", "value": 0.55 - 0.05 * (k % 6)},
    "light intensity": lambda k: {"type": "light", "index": 0, "key": "strength", "value": 1.5 + 0.1 * (k % 5)},
    "camera orbit": lambda k: {"type": "camera", "yaw": 3.0 if k % 2 else -3.0},
}


def latencies_in_browser(driver, url, rounds: int):
    """Page-measured ms from a change to its first image, per kind of change; and page open -> first image."""
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import Select

    opened = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        driver.get(url)
        wait_until(driver, "return window.lumos && window.lumos.frames > 0")
        opened.append(time.perf_counter() - t0)
    wait_until(driver, "return window.lumos.lastFrame && window.lumos.lastFrame.stage === 'final'")
    Select(driver.find_element("id", "material")).select_by_value("red")
    results = {}
    steps = {"material kd": ("material-kd", Keys.ARROW_LEFT), "light intensity": ("light-strength", Keys.ARROW_RIGHT)}
    for name in EDITS:
        values = []
        for k in range(5 * rounds):
            count = driver.execute_script("return window.lumos.latencies.length")
            if name == "camera orbit":  # a short drag on the image
                _orbit(driver, 3 if k % 2 else -3)
            else:
                element, key = steps[name]
                driver.find_element("id", element).send_keys(key if k % 4 < 2 else
                                                             (Keys.ARROW_RIGHT if key == Keys.ARROW_LEFT
                                                              else Keys.ARROW_LEFT))
            wait_until(driver, f"return window.lumos.latencies.length > {count}")
            values.append(driver.execute_script(f"return window.lumos.latencies[{count}].ms"))
            wait_until(driver, "const f = window.lumos.lastFrame; return f && f.stage === 'final' && "
                               "f.generation === Math.max(...window.lumos.latencies.map(l => l.generation))")
        results[name] = values
    return opened, results


def _orbit(driver, dx):
    from selenium.webdriver.common.action_chains import ActionChains

    canvas = driver.find_element("id", "image")
    ActionChains(driver).move_to_element(canvas).click_and_hold().move_by_offset(8 * dx, 0).release().perform()


def latencies_over_socket(url, rounds: int):
    """ms from an edit sent to the first frame of its generation received, per kind of change."""
    page = SocketPage(url)
    results = {}
    try:
        time.sleep(2.0)
        for name, make in EDITS.items():
            values = []
            for k in range(5 * rounds):
                before = len(page.replies)
                t0 = time.perf_counter()
                page.send(make(k))
                while not any(r.get("type") == "ack" for r in page.replies[before:]):
                    time.sleep(0.001)
                generation = next(r for r in page.replies[before:] if r.get("type") == "ack")["generation"]
                while not any(m and m["generation"] >= generation for _, m in page.frames):
                    time.sleep(0.001)
                t1 = next(t for t, m in page.frames if m and m["generation"] >= generation)
                values.append((t1 - t0) * 1000)
                while not any(m and m["generation"] >= generation and m["stage"] == "final" for _, m in page.frames):
                    time.sleep(0.005)
            results[name] = values
    finally:
        page.close()
    return results


# ------------------------------------------------------------------------------------------- screenshots


def screenshots(folder: Path):
    """The pictures of docs/preview.md: the page with whitted and a pixel explained; path refining; a term."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.support.ui import Select

    from lumos.preview.server import PreviewServer
    from lumos.preview.session import Session

    folder.mkdir(parents=True, exist_ok=True)
    session = Session.from_file(SHOWCASE, method="whitted", **SIZE)
    server = PreviewServer(session).start()
    driver = chromium_driver(1400, 860)
    try:
        driver.get(server.url)
        final = "return window.lumos.lastFrame && window.lumos.lastFrame.stage === 'final' && window.lumos.lastFrame"
        wait_until(driver, final)
        Select(driver.find_element("id", "material")).select_by_value("red")
        canvas = driver.find_element("id", "image")
        size = canvas.size
        ActionChains(driver).move_to_element_with_offset(canvas, int(-0.03 * size["width"]),
                                                         int(-0.07 * size["height"])).click().perform()
        wait_until(driver, "return window.lumos.explains > 0")
        time.sleep(0.3)
        driver.save_screenshot(str(folder / "page.png"))
        Select(driver.find_element("id", "method")).select_by_value("raster")
        wait_until(driver, "const f = window.lumos.lastFrame; return f && f.status.method === 'raster' && "
                           "f.stage === 'final'")
        Select(driver.find_element("id", "shading")).select_by_value("gouraud")
        wait_until(driver, "const f = window.lumos.lastFrame; return f && f.status.shading === 'gouraud' && "
                           "f.stage === 'final'")
        Select(driver.find_element("id", "view")).select_by_value("specular")
        wait_until(driver, "const f = window.lumos.lastFrame; return f && f.view === 'specular' && "
                           "f.stage === 'final'")
        ActionChains(driver).move_to_element_with_offset(canvas, int(0.26 * size["width"]),
                                                         int(0.02 * size["height"])).click().perform()
        wait_until(driver, "return window.lumos.explains > 1")
        time.sleep(0.3)
        driver.save_screenshot(str(folder / "terms.png"))
        Select(driver.find_element("id", "view")).select_by_value("image")
        Select(driver.find_element("id", "method")).select_by_value("path")
        wait_until(driver, "const f = window.lumos.lastFrame; return f && f.status.method === 'path' && "
                           "f.status.spp > 20")
        ActionChains(driver).move_to_element_with_offset(canvas, int(-0.03 * size["width"]),
                                                         int(-0.07 * size["height"])).click().perform()
        wait_until(driver, "return window.lumos.explains > 2")  # path explains none: whitted's account, noted
        time.sleep(0.2)
        driver.save_screenshot(str(folder / "path.png"))
    finally:
        driver.quit()
        server.stop()
        session.close()
    return sorted(folder.glob("*.png"))


# --------------------------------------------------------------------------------------------------- main


def main() -> int:
    import warnings

    from lumos.errors import LumosWarning

    warnings.simplefilter("ignore", LumosWarning)  # path's note on the showcase's materials, once per render
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--spp", type=int, default=256, help="samples of the path render (page open cost)")
    parser.add_argument("--no-browser", action="store_true", help="measure with a WebSocket client, no Chromium")
    parser.add_argument("--screenshots", type=Path, metavar="DIR", help="also write docs/preview.md's pictures")
    args = parser.parse_args()
    browser = not args.no_browser and shutil.which("chromium") is not None and shutil.which("chromedriver") is not None
    print(f"machine: {machine()}")
    print(f"scene: examples/showcase.yaml at 320x240; page: {'headless Chromium' if browser else 'WebSocket client'}")
    rows = []

    without, with_page, frames = page_open_cost(args.rounds, args.spp, browser)
    ratio = statistics.median(with_page) / statistics.median(without)
    rows.append((f"path {args.spp} spp, no page (s)", *spread(without), ""))
    rows.append((f"path {args.spp} spp, page open (s)", *spread(with_page),
                 f"x{ratio:.3f} of no page; {statistics.median(frames):.0f} frames "
                 f"{'drawn' if browser else 'received'}"))

    rows.append(("lumos serve start -> first frame (s)", *spread(serve_to_first_frame(args.rounds)),
                 "new process, warm kernel cache"))

    from lumos.preview.server import PreviewServer
    from lumos.preview.session import Session

    session = Session.from_file(SHOWCASE, **SIZE)
    server = PreviewServer(session).start()
    try:
        driver = chromium_driver() if browser else None
        if driver is not None:
            try:
                opened, latencies = latencies_in_browser(driver, server.url, args.rounds)
            finally:
                driver.quit()
            rows.append(("page open -> first image (s)", *spread(opened), "server running"))
        else:
            latencies = latencies_over_socket(server.url, args.rounds)
        for name, values in latencies.items():
            rows.append((f"{name} -> first image (ms)", *spread(values),
                         "drawn on the page" if driver is not None else "received over the socket"))
    finally:
        server.stop()
        session.close()

    width = max(len(r[0]) for r in rows)
    print(f"\n{'':<{width}}  {'min':>8} {'median':>8} {'max':>8}")
    for name, lo, mid, hi, note in rows:
        print(f"{name:<{width}}  {lo:8.3f} {mid:8.3f} {hi:8.3f}  {note}")
    if args.screenshots:
        if not browser:
            print("--screenshots needs Chromium", file=sys.stderr)
            return 2
        for path in screenshots(args.screenshots):
            print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
