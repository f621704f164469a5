"""`lumos.render(..., live=True)` in Jupyter: nbclient runs a small notebook in a real kernel and records what a
frontend would receive — the widget's comm messages (each new PNG for the ipywidgets `Image`) and, without the
widget, the display-data updates of the IPython display handles. About 2 s: the kernel starts and imports lumos
(the path kernels come from the cache)."""

from __future__ import annotations

import base64
import hashlib
import io
import json
import sys

import numpy as np
import pytest
import yaml
from helpers import TINY

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")
pytest.importorskip("ipywidgets")

SCENE = yaml.safe_load(TINY)
SCENE["render"].update(method="path", spp=5, seed=3)  # 32 × 24

SETUP = f"""\
import hashlib
import lumos, lumos.live
from lumos.methods import path as path_method
path_method.PASS_SECONDS = 1e-9  # a pass per sample: 5 images, the last one final
lumos.live.INTERVAL_S = 0.0      # and none of them held back by the throttle
scene = {SCENE!r}
"""
WIDGET = """\
img = lumos.render(scene, live=True)
print("shape", img.array.shape, "png", hashlib.sha256(img.to_png_bytes()).hexdigest())
"""
HANDLES = """\
img = lumos.render(scene, live=lumos.live.NotebookSink(widget=False))
print("shape", img.array.shape)
"""


class Recording(nbclient.NotebookClient):
    """A NotebookClient that keeps every iopub message of each cell: (cell index, msg_type, content)."""

    def __init__(self, nb, **kw):
        super().__init__(nb, **kw)
        self.messages = []

    def process_message(self, msg, cell, cell_index):
        self.messages.append((cell_index, msg["msg_type"], msg["content"], msg.get("buffers", [])))
        return super().process_message(msg, cell, cell_index)


@pytest.fixture(scope="module")
def executed(tmp_path_factory):
    """The notebook run in a kernel of this Python (a kernelspec of our own, so no other `python3` is picked)."""
    root = tmp_path_factory.mktemp("live_nb")
    spec = root / "share" / "jupyter" / "kernels" / "lumos-test"
    spec.mkdir(parents=True)
    (spec / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "lumos test", "language": "python"}))
    mp = pytest.MonkeyPatch()
    mp.setenv("JUPYTER_PATH", str(root / "share" / "jupyter"))
    try:
        nb = nbformat.v4.new_notebook()
        nb.cells = [nbformat.v4.new_code_cell(code) for code in (SETUP, WIDGET, HANDLES)]
        client = Recording(nb, kernel_name="lumos-test", timeout=120, resources={"metadata": {"path": str(root)}})
        client.execute()
    finally:
        mp.undo()
    return nb, client.messages


def stdout(cell):
    return "".join(o.get("text", "") for o in cell.outputs if o.output_type == "stream")


def png_shape(data: bytes):
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data))).shape


def test_the_widget_shows_each_pass_and_ends_on_the_final_image(executed):
    nb, messages = executed
    cell = nb.cells[1]
    assert "shape (24, 32, 3)" in stdout(cell)
    views = [o for o in cell.outputs if o.output_type == "display_data"]
    assert len(views) == 1 and "application/vnd.jupyter.widget-view+json" in views[0].data  # one widget, shown once
    opened = {m[2]["comm_id"]: m[2]["data"]["state"] for m in messages if m[0] == 1 and m[1] == "comm_open"}
    image_ids = [cid for cid, state in opened.items() if state.get("_model_name") == "ImageModel"]
    assert len(image_ids) == 1
    image_id = image_ids[0]
    values = [m[3][m[2]["data"]["buffer_paths"].index(["value"])] for m in messages  # the PNG travels as a buffer
              if m[0] == 1 and m[1] in ("comm_open", "comm_msg") and m[2]["comm_id"] == image_id
              and ["value"] in m[2]["data"].get("buffer_paths", [])]
    assert len(values) == 5  # opened with pass 1's image, then updated with passes 2, 3, 4 and the final image
    assert len({bytes(v) for v in values}) > 1
    assert all(png_shape(bytes(v)) == (24, 32, 3) for v in values)
    # the stored widget state (what the saved notebook shows) holds the final image's PNG
    state = nb.metadata["widgets"]["application/vnd.jupyter.widget-state+json"]["state"][image_id]
    final = base64.b64decode(next(b["data"] for b in state["buffers"] if b["path"] == ["value"]))
    assert f"png {hashlib.sha256(final).hexdigest()}" in stdout(cell)
    labels = [s for s in opened.values() if s.get("_model_name") == "LabelModel"]
    assert len(labels) == 1 and labels[0]["value"].startswith("rendering · 32×24 · 1 spp")
    label_id = next(cid for cid, s in opened.items() if s.get("_model_name") == "LabelModel")
    last_label = [m[2]["data"]["state"]["value"] for m in messages if m[0] == 1 and m[1] == "comm_msg"
                  and m[2]["comm_id"] == label_id and "value" in m[2]["data"].get("state", {})][-1]
    assert last_label.startswith("done · 32×24 · path · 5 spp")


def test_without_the_widget_display_handles_update_in_place(executed):
    nb, messages = executed
    cell = nb.cells[2]
    assert "shape (24, 32, 3)" in stdout(cell)
    shown = [m for m in messages if m[0] == 2 and m[1] == "display_data"]
    updates = [m for m in messages if m[0] == 2 and m[1] == "update_display_data"]
    assert len(shown) == 2  # the image and its caption, each with a display id
    image_id = shown[0][2]["transient"]["display_id"]
    image_updates = [m for m in updates if m[2]["transient"]["display_id"] == image_id]
    assert len(image_updates) == 4 and len(updates) == 8
    pngs = [base64.b64decode(m[2]["data"]["image/png"]) for m in image_updates]
    assert all(png_shape(p) == (24, 32, 3) for p in pngs) and len(set(pngs)) > 1
    # in the saved notebook the outputs were updated in place: still two, the image now the final one
    outputs = [o for o in cell.outputs if o.output_type == "display_data"]
    assert len(outputs) == 2 and base64.b64decode(outputs[0].data["image/png"]) == pngs[-1]
