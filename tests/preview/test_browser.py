"""The preview page in a real browser: headless Chromium (Debian's `chromium` and `chromium-driver`, driven by
Selenium) opens the page on the showcase at 320x240, waits for the image, moves a material slider and a light
slider, measures the time from each change to the first updated image on the canvas, clicks a pixel and reads
the explain panel, and checks screenshots: not blank, and different after the edit.

The latencies are written to `preview-latency.json` in the test's tmp folder and printed (BENCHMARKS.md quotes
them); `.ci/run` installs Chromium when it is missing, elsewhere the test is skipped with the reason.
"""

from __future__ import annotations

import json
import shutil
import statistics
import time

import numpy as np
import pytest
from helpers import EXAMPLES

pytest.importorskip("starlette")
pytest.importorskip("uvicorn")
webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed (pip install '.[test]')")


CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(shutil.which(CHROMIUM) is None or shutil.which(CHROMEDRIVER) is None,
                       reason="headless Chromium is not installed (apt-get install chromium chromium-driver; "
                              ".ci/run does)"),
]


def wait_until(driver, script, timeout=30.0, every=0.02):
    """Run `script` (JavaScript returning a value) until it returns something truthy; return that."""
    deadline = time.perf_counter() + timeout
    while time.perf_counter() < deadline:
        value = driver.execute_script(script)
        if value:
            return value
        time.sleep(every)
    raise AssertionError(f"timed out waiting for: {script}")


def canvas_pixels(driver) -> np.ndarray:
    """The canvas as uint8 (H, W, 4), read in the page."""
    data = driver.execute_script(
        "const c = document.getElementById('image');"
        "const d = c.getContext('2d').getImageData(0, 0, c.width, c.height);"
        "return [c.width, c.height, Array.from(d.data)];")
    w, h, values = data
    return np.array(values, np.uint8).reshape(h, w, 4)


def screenshot(driver, path) -> np.ndarray:
    from PIL import Image

    assert driver.save_screenshot(str(path))
    return np.asarray(Image.open(path).convert("RGB"), np.float32)


def edit_and_time(driver, element_id, keys):
    """Press `keys` on the slider `element_id`; the page's time (ms) from the change to its first image."""
    count = driver.execute_script("return window.lumos.latencies.length")
    driver.find_element("id", element_id).send_keys(keys)
    wait_until(driver, f"return window.lumos.latencies.length > {count}")
    latency = driver.execute_script(f"return window.lumos.latencies[{count}].ms")
    # the render of that change finished: the last frame is final and as new as the last change
    wait_until(driver, "const f = window.lumos.lastFrame; return f && f.stage === 'final' && "
                       "f.generation === Math.max(...window.lumos.latencies.map(l => l.generation))")
    return latency


@pytest.fixture
def browser():
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--window-size=1400,1000", "--force-device-scale-factor=1"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    yield driver
    driver.quit()


def test_the_page_refines_edits_and_explains_in_chromium(browser, tmp_path):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import Select

    from lumos.preview.server import PreviewServer
    from lumos.preview.session import Session

    session = Session.from_file(EXAMPLES / "showcase.yaml", width=320, height=240)
    server = PreviewServer(session).start()
    try:
        t0 = time.perf_counter()
        browser.get(server.url)
        wait_until(browser, "return window.lumos && window.lumos.frames > 0")
        first_image_s = time.perf_counter() - t0
        wait_until(browser, "return window.lumos.lastFrame && window.lumos.lastFrame.stage === 'final'")
        before = canvas_pixels(browser)
        assert before.shape == (240, 320, 4) and before[..., :3].std() > 20  # an image, not a blank canvas
        shot_before = screenshot(browser, tmp_path / "before.png")

        # the red ball's diffuse coefficient, down a few steps; then the key light's intensity, up
        Select(browser.find_element("id", "material")).select_by_value("red")
        latencies = [edit_and_time(browser, "material-kd", Keys.ARROW_LEFT) for _ in range(3)]
        latencies.append(edit_and_time(browser, "light-strength", Keys.ARROW_RIGHT * 4))
        after = canvas_pixels(browser)
        assert np.abs(after.astype(int) - before.astype(int)).mean() > 0.5
        shot_after = screenshot(browser, tmp_path / "after.png")
        assert shot_after.std() > 20 and np.abs(shot_after - shot_before).mean() > 0.2

        # a pixel on the red ball: the explain panel shows raycast's account of it
        canvas = browser.find_element("id", "image")
        size = canvas.size
        ActionChains(browser).move_to_element_with_offset(canvas, int(-0.02 * size["width"]),
                                                          int(-0.05 * size["height"])).click().perform()
        text = wait_until(browser, "return window.lumos.explains > 0 && document.getElementById('explain-text')"
                                   ".textContent")
        assert "method raycast" in text and "hit sphere#1" in text and "light 0 (point)" in text
        assert "pixel (" in browser.find_element("id", "explain-head").text
        assert browser.execute_script("return window.lumos.errors") == []
        screenshot(browser, tmp_path / "explained.png")
    finally:
        server.stop()
        session.close()
    figures = {"scene": "examples/showcase.yaml", "size": "320x240", "method": "raycast",
               "first_image_after_page_open_s": first_image_s, "edit_to_first_image_ms": latencies,
               "median_ms": statistics.median(latencies)}
    (tmp_path / "preview-latency.json").write_text(json.dumps(figures, indent=2))
    print(f"\npreview latency: {json.dumps(figures)}")
    assert first_image_s < 5.0 and max(latencies) < 2000.0  # loose: the figures themselves go to BENCHMARKS.md
