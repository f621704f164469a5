"""Reference render of DamagedHelmet by three.js (a real glTF viewer), for comparison with lumos.

Loads examples/data/models/helmet/DamagedHelmet.glb with three's GLTFLoader (MeshStandardMaterial) in
headless Chromium (WebGL via SwiftShader), lit only by image-based lighting from
examples/data/env/courtyard.exr (EXRLoader, negatives clamped to 0, PMREMGenerator), with the same
environment as background. Camera as lumos: position (0, 0, 3.2) looking at the origin, up +y, vertical
fov 40 degrees, square image. No tone mapping, exposure 1, sRGB output (linear clipped to [0, 1], then the
sRGB curve), as lumos writes PNGs.

Environment orientation: lumos maps direction d to u = 1/2 + atan2(x, -z)/2pi, v = acos(y)/pi;
three's equirectUv maps it to u = 1/2 + atan2(z, x)/2pi. three looks up R^T d with R from
scene.environmentRotation / backgroundRotation, so R = rotation of +90 degrees about y
(Euler(0, pi/2, 0)) gives both the same pixel for every direction (checked numerically on a
background-only render, see --background-only).

Run (needs chromium + chromedriver, and selenium in the Python environment):
    npm pack three && tar xzf three-*.tgz
    python examples/path/helmet_viewer.py --three package --out docs/images/path/helmet_three.png
Last run with three.js r187 (npm three 0.187.0), Chromium 150.
"""
import argparse
import base64
import functools
import http.server
import os
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "data"
GLB = DATA / "models" / "helmet" / "DamagedHelmet.glb"
EXR = DATA / "env" / "courtyard.exr"

PAGE = """<!DOCTYPE html><html><head><style>body{margin:0}canvas{display:block}</style>
<script type="importmap">{"imports": {"three": "./three/build/three.module.js",
  "three/addons/": "./three/examples/jsm/"}}</script></head><body><script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { EXRLoader } from 'three/addons/loaders/EXRLoader.js';
window.onerror = (msg) => { window.failed = String(msg); };
window.onunhandledrejection = (e) => { window.failed = String(e.reason); };
const q = new URLSearchParams(location.search);
const size = Number(q.get('size')), bgOnly = q.get('bg') === '1';
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
renderer.setSize(size, size);
renderer.toneMapping = THREE.NoToneMapping;
renderer.toneMappingExposure = 1;
renderer.outputColorSpace = THREE.SRGBColorSpace;
document.body.appendChild(renderer.domElement);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 100);   // vertical fov in degrees
const [px, py, pz] = (q.get('pos') || '0,0,3.2').split(',').map(Number);
const [tx, ty, tz] = (q.get('target') || '0,0,0').split(',').map(Number);
camera.position.set(px, py, pz);
camera.lookAt(tx, ty, tz);
const scene = new THREE.Scene();
// lumos: u = 1/2 + atan2(x, -z)/2pi; three: u = 1/2 + atan2(z, x)/2pi of R^T d  =>  R = Ry(+90 deg)
scene.environmentRotation.set(0, Math.PI / 2, 0);
scene.backgroundRotation.set(0, Math.PI / 2, 0);
const env = await new EXRLoader().setDataType(THREE.FloatType).loadAsync('courtyard.exr');
for (let i = 0; i < env.image.data.length; i++) env.image.data[i] = Math.max(0, env.image.data[i]);
env.mapping = THREE.EquirectangularReflectionMapping;
env.needsUpdate = true;
scene.background = env;
const pmrem = new THREE.PMREMGenerator(renderer);
scene.environment = pmrem.fromEquirectangular(env).texture;
if (!bgOnly) scene.add((await new GLTFLoader().loadAsync('DamagedHelmet.glb')).scene);
const t0 = performance.now();
renderer.render(scene, camera);
renderer.getContext().finish();
window.renderMs = performance.now() - t0;
window.done = true;
</script></body></html>"""


def render(three: Path, size: int = 512, query: str = "", timeout: float = 300.0) -> bytes:
    """Render the page in headless Chromium; return the canvas as PNG bytes."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "index.html").write_text(PAGE)
        os.symlink(three.resolve(), root / "three")
        os.symlink(GLB, root / GLB.name)
        os.symlink(EXR, root / EXR.name)
        handler = functools.partial(QuietHandler, directory=tmp)
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        opts = webdriver.ChromeOptions()
        opts.binary_location = shutil.which("chromium")
        for flag in ("--headless=new", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                     "--ignore-gpu-blocklist", "--no-sandbox", "--force-device-scale-factor=1",
                     f"--window-size={size + 64},{size + 64}"):
            opts.add_argument(flag)
        driver = webdriver.Chrome(options=opts, service=Service(shutil.which("chromedriver")))
        try:
            driver.get(f"http://127.0.0.1:{server.server_port}/index.html?size={size}&{query}")
            start = time.time()
            while not driver.execute_script("return window.done === true"):
                failed = driver.execute_script("return window.failed")
                if failed or time.time() - start > timeout:
                    raise RuntimeError(f"page failed: {failed or 'timeout'}")
                time.sleep(0.5)
            ms = driver.execute_script("return window.renderMs")
            print(f"loaded + rendered in {time.time() - start:.1f} s (final render call {ms:.0f} ms)")
            url = driver.execute_script("return document.querySelector('canvas').toDataURL('image/png')")
        finally:
            driver.quit()
            server.shutdown()
    return base64.b64decode(url.split(",", 1)[1])


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map, ".js": "text/javascript"}

    def log_message(self, *args):
        pass


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--three", required=True, type=Path, help="unpacked npm 'three' package folder")
    ap.add_argument("--out", default="helmet_three.png", help="output PNG (default helmet_three.png)")
    ap.add_argument("--size", type=int, default=512, help="image width = height in pixels (default 512)")
    ap.add_argument("--background-only", action="store_true", help="environment only, no helmet")
    args = ap.parse_args()
    missing = [n for n in ("chromium", "chromedriver") if shutil.which(n) is None]
    problem = None
    if missing:
        problem = f"{' and '.join(missing)} not found (apt-get install chromium chromium-driver)"
    elif not (args.three / "build" / "three.module.js").is_file():
        problem = (f"{args.three} is not an unpacked npm 'three' package (no build/three.module.js); run: "
                   "npm pack three && tar xzf three-*.tgz")
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        sys.exit(2)
    png = render(args.three, args.size, "bg=1" if args.background_only else "")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_bytes(png)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
