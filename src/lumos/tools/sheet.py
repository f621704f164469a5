"""The comparison sheet: one scene rendered by every method (and each shading of the scan-line method), side by
side in one labelled grid image, the figure the textbook asks readers to make.

    sheet, cells = make_sheet("scene.yaml", width=320, height=240)
    save_sheet(sheet, "sheet.png")
    cells[1]["label"], cells[1]["render_s"], cells[1]["image"]    # 'raster · Gouraud', 0.84, <lumos.Image>
    sheet, cells = make_sheet("scene.yaml", reference="whitted", diff=True)
    cells[1]["figures"]["rmse"], cells[1]["figures"]["mean_rel_error"]    # against the whitted cell

Layout, in pixels (`layout` computes it; every column is `slot_w` wide, every row `cell_h + caption_h`):

    MARGIN  title: the scene file name
            info:  320x240 · 1 spp · warm-up 1.23 s
    MARGIN  cell  MARGIN  cell  MARGIN  ...   (up to `columns` cells a row)
            label          label
            time           time
            figures        figures     (with a reference: its error figures, or "reference")
    MARGIN  cell  ...
            legend: the diff colour scale   (with diff: the difference images, laid out as the cells)
            diff           diff
            label          label

Each cell is the render's PNG encoding (`tonemap.to_png8`, the path `Image.save` takes), pixel for pixel. Before
the timed renders each (method, shading) pair is rendered once at WARMUP_SIZE, so a cell's time is its render
alone, not Numba compiling (or loading from its cache) the kernel; that warm-up is the `warm-up` time of the
info line, shared by all cells.

With a reference cell (`--reference whitted`, `raster:phong`...), every other rendered cell is compared with it
in linear radiance (`metrics.compare`: RMSE and mean relative error in its caption, all figures in its dict);
with `diff`, each also gets a difference image, its largest-channel |cell − reference| through the heat ramp
of `lumos compare --diff` on one fixed scale (DIFF_SCALE), under the grid in the same places as the cells.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Iterable, Optional

import numpy as np

from .. import api
from ..errors import LumosError
from ..io.atomic import one_line
from .sheet_drawing import compose_sheet, format_figures, format_seconds

#: Widest default cell: a scene wider than this is rendered at this width (same aspect) unless a width is given.
MAX_CELL_WIDTH = 640
#: Width and height of the warm-up renders (any size compiles the same kernels).
WARMUP_SIZE = 8
#: Shadings of the scan-line method, in the textbook's order: (caption name, `shading` setting).
RASTER_SHADINGS = (("flat", "flat"), ("Gouraud", "gouraud"), ("Phong", "phong"))
#: Samples per pixel of the path tracer's cell at least, unless the sheet is given an spp.
PATH_MIN_SPP = 64
#: Samples per pixel of the supersampling that stands in for whitted's adaptive anti-aliasing in the other
#: methods' cells, unless the sheet is given an spp (`api.ADAPTIVE_STAND_IN_SPP`).
ADAPTIVE_STAND_IN_SPP = api.ADAPTIVE_STAND_IN_SPP
#: Bounces of whitted's cell when the scene asks for unbounded depth (max_depth: -1, a path-tracing setting).
WHITTED_STAND_IN_DEPTH = 5
#: Output formats of a sheet, by extension.
SHEET_FORMATS = {".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG"}

# ------------------------------------------------------------------------------------------------- entries


def default_entries() -> list[tuple[str, dict]]:
    """The cells of a full sheet with the methods registered now: `(label, {"method": ..., "shading": ...})`.

    `raster` once per shading (flat, Gouraud, Phong), then every other method of `api.METHODS` once
    (shading None: the scene's setting, which those methods ignore).
    """
    entries = []
    if "raster" in api.METHODS:
        entries += [(f"raster · {name}", {"method": "raster", "shading": shading})
                    for name, shading in RASTER_SHADINGS]
    entries += [(name, {"method": name, "shading": None}) for name in api.METHODS if name != "raster"]
    return entries


def entries_for(methods: Iterable[str]) -> list[tuple[str, dict]]:
    """The `default_entries` of the named methods, in the order named (`--methods raycast,raster`).

    Raises LumosError for an empty list or a name that is not a registered method.
    """
    names = list(dict.fromkeys(name.strip() for name in methods if name.strip()))
    if not names:
        raise LumosError("--methods: name at least one method (available: " + ", ".join(api.METHODS) + ")")
    for name in names:
        if name not in api.METHODS:
            raise LumosError(f"--methods: unknown method {name!r} (available: {', '.join(api.METHODS)})")
    available = default_entries()
    return [entry for name in names for entry in available if entry[1]["method"] == name]


def reference_choices() -> list[str]:
    """What `--reference` accepts with the methods registered now: each method, and `raster:SHADING`."""
    choices = []
    for name in api.METHODS:
        choices.append(name)
        if name == "raster":
            choices += [f"raster:{shading}" for _, shading in RASTER_SHADINGS]
    return choices


def parse_reference(text: str) -> tuple[str, Optional[str]]:
    """`METHOD` or `raster:SHADING` (`whitted`, `raster:phong`) -> (method, shading or None).

    Raises LumosError, naming the choices, for an empty text, an unknown method or shading, or a shading given
    to a method other than raster.
    """
    choices = ", ".join(reference_choices())
    name, colon, shading = (part.strip() for part in str(text).partition(":"))
    if not name:
        raise LumosError(f"--reference: name the method of one cell (choose from {choices})")
    if name not in api.METHODS:
        raise LumosError(f"--reference: unknown method {name!r} (choose from {choices})")
    if not colon:
        return name, None
    if name != "raster":
        raise LumosError(f"--reference: {text!r}: only raster has shadings; write {name!r} alone")
    shadings = [value for _, value in RASTER_SHADINGS]
    if shading not in shadings:
        raise LumosError(f"--reference: unknown raster shading {shading!r} (choose from {', '.join(shadings)})")
    return name, shading


def _reference_index(text: str, configs: list, default_shading: str) -> int:
    """The index of the cell `text` names among cells rendered with `configs` (their RenderSettings).

    `raster` alone is the raster cell with `default_shading` (the scene's, as `lumos render --method raster`);
    another method is its first cell. Raises LumosError when the sheet has no such cell.
    """
    method, shading = parse_reference(text)
    if method == "raster" and shading is None:
        shading = default_shading
    for i, cfg in enumerate(configs):
        if cfg.method == method and (method != "raster" or cfg.shading == shading):
            return i
    named = f"raster:{shading}" if method == "raster" else method
    cells = ", ".join(dict.fromkeys(f"raster:{c.shading}" if c.method == "raster" else c.method for c in configs))
    raise LumosError(f"--reference: the sheet has no {named} cell (its cells: {cells})")


# ----------------------------------------------------------------------------------------------- rendering


def make_sheet(scene, entries: Optional[list[tuple[str, dict]]] = None, columns: Optional[int] = None,
               progress: bool = False, *, title: Optional[str] = None, warm_up: bool = True,
               max_cell_width: Optional[int] = MAX_CELL_WIDTH, reference: Optional[str] = None,
               diff: bool = False, **settings):
    """Render `scene` once per entry and compose the renders into one labelled grid.

    scene:     a Scene, a scene dict or a path.
    entries:   `(label, settings)` pairs, default `default_entries()`; those whose method is not in
               `api.METHODS` are skipped.
    columns:   cells per row, default min(MAX_COLUMNS, number of cells).
    progress:  True prints one line per cell on stderr (and each render's progress bar).
    title:     the sheet's title, default the scene file's name.
    reference: the cell the others are compared with, `METHOD` or `raster:SHADING` (`parse_reference`); it is
               rendered first, and the sheet fails (LumosError) if it cannot be.
    diff:      with a reference, add the difference images under the grid (one scale: DIFF_SCALE).
    settings:  override the scene's `render:` block for every cell (width, height, spp, threads ...). Without a
               width, a scene wider than `max_cell_width` is rendered at that width with its aspect ratio kept.

    Returns `(sheet, cells)`: a `PIL.Image.Image` (RGB) and per cell a dict with label, method, shading,
    width, height, render_s, image (the lumos `Image`), error (why the method could not draw the scene, or
    None), box (x, y, width, height of the render in the sheet), reference (True for the reference cell),
    figures (`metrics.compare` of the image against the reference's, linear: rmse, psnr, mean_rel_error,
    max_abs_error; None for the reference, a cell not rendered, or without a reference) and diff_box (where
    its difference image is, or None). `sheet.info["compile_s"]` is the warm-up time.
    """
    from ..scene.loader import load_scene

    title = _title_of(scene) if title is None else title
    scene = load_scene(scene)
    if columns is not None and columns < 1:
        raise LumosError(f"sheet: columns must be at least 1, got {columns}")
    if diff and reference is None:
        raise LumosError("--diff: difference images are against a reference cell: give --reference METHOD too")
    jobs = _jobs(scene, default_entries() if entries is None else entries, settings, max_cell_width)
    configs = [api.resolve_settings(scene, job) for _, job in jobs]  # every bad value fails before any render
    ref = None if reference is None else _reference_index(reference, configs,
                                                           settings.get("shading") or scene.render.shading)
    say = _say if progress else (lambda text: None)

    compile_s = _warm_up(scene, [job for _, job in jobs], progress, say) if warm_up else None
    cells: list[Optional[dict]] = [None] * len(jobs)
    # the reference first: if it cannot be drawn the sheet stops before the other renders, and each later
    # cell's progress line can give its figures
    order = list(range(len(jobs))) if ref is None else [ref] + [i for i in range(len(jobs)) if i != ref]
    for i in order:
        cell = cells[i] = _render_cell(scene, jobs[i], configs[i], progress)
        cell["reference"] = i == ref
        if i == ref and cell["image"] is None:
            raise LumosError(f"--reference: the reference cell ({cell['label']}) could not be rendered: "
                             f"{cell['error']}")
        if ref is not None and i != ref and cell["image"] is not None:
            cell["figures"] = _figures(cell, cells[ref])
        say(f"[{i + 1}/{len(jobs)}] {cell['label']}: " + _progress_text(cell))

    if all(cell["image"] is None for cell in cells):
        raise LumosError(f"sheet: no method could render the scene ({cells[0]['label']}: {cells[0]['error']})")
    cfg = configs[0]
    same_size = all((c.width, c.height) == (cfg.width, cfg.height) for c in configs)
    info = [f"{cfg.width}x{cfg.height}" if same_size else "", f"{cfg.spp} spp" if same_size else "",
            f"warm-up {format_seconds(compile_s)}" if compile_s is not None else "",
            f"errors against {cells[ref]['label']}" if ref is not None else ""]
    sheet = compose_sheet(cells, columns, title=title, info=" · ".join(part for part in info if part), diff=diff)
    sheet.info["compile_s"] = compile_s
    return sheet, cells


def make_terms_sheet(scene, method: str = "whitted", columns: Optional[int] = None, progress: bool = False, *,
                     title: Optional[str] = None, max_cell_width: Optional[int] = MAX_CELL_WIDTH, **settings):
    """One method's render taken apart: its term AOVs (ambient, diffuse, specular, emitted, reflected,
    transmitted) side by side, then their sum, the image. `method` is `METHOD` or `raster:SHADING`
    (`parse_reference`'s syntax); it must be raycast, raster or whitted, the methods that compute the terms.
    Returns `(sheet, cells)` as `make_sheet` (each cell's image is one term, on the render's exposure)."""
    from ..image import Image
    from ..scene.loader import load_scene
    from ..scene.model import TERM_AOVS

    title = _title_of(scene) if title is None else title
    scene = load_scene(scene)
    name, shading = parse_reference(method)
    if name not in ("raycast", "raster", "whitted"):
        raise LumosError(f"--terms: method {name} does not compute the classic model's terms (raycast, raster "
                         "and whitted do)")
    entry = {"method": name, "aov": list(TERM_AOVS)}
    if shading is not None:
        entry["shading"] = shading
    label = name if name != "raster" else f"raster · {shading or settings.get('shading') or scene.render.shading}"
    jobs = _jobs(scene, [(label, entry)], settings, max_cell_width)
    label, job = jobs[0]
    api.resolve_settings(scene, job)
    say = _say if progress else (lambda text: None)
    img = api.render(scene, progress=progress, **job)
    say(f"{label}: {img.width}x{img.height}, {format_seconds(img.stats['render_s'])}")
    cells = []
    for term in TERM_AOVS:
        part = Image(np.ascontiguousarray(img.aovs[term], np.float32), exposure=img.exposure)
        cells.append({"label": term, "method": name, "shading": shading, "width": img.width, "height": img.height,
                      "render_s": None, "image": part, "error": None, "figures": None, "diff_box": None,
                      "caption": f"max {float(img.aovs[term].max()):.3g}"})
    cells.append({"label": "sum: the image", "method": name, "shading": shading, "width": img.width,
                  "height": img.height, "render_s": float(img.stats["render_s"]), "image": img, "error": None,
                  "figures": None, "diff_box": None})
    info = f"{label} · {img.width}x{img.height} · its terms, which add up to the image"
    sheet = compose_sheet(cells, columns or 4, title=title, info=info)
    return sheet, cells


def _render_cell(scene, entry: tuple[str, dict], cfg, progress: bool) -> dict:
    """Render one cell: its dict, with image and render_s, or error (one line) where the method cannot."""
    label, job = entry
    cell = {"label": label, "method": job["method"], "shading": job.get("shading"), "width": cfg.width,
            "height": cfg.height, "figures": None, "diff_box": None}
    try:
        img = api.render(scene, progress=progress, **job)
    except LumosError as exc:  # this method cannot draw this scene: a cell that says why, not a failed sheet
        why = one_line(exc)
        if scene.source is not None and why.startswith(f"{scene.source}: "):
            why = why[len(f"{scene.source}: "):]  # the sheet's title names the file
        return {**cell, "render_s": None, "image": None, "error": why}
    return {**cell, "render_s": float(img.stats["render_s"]), "image": img, "error": None}


def _figures(cell: dict, ref: dict) -> dict[str, float]:
    """`metrics.compare` of a cell's linear image against the reference cell's (same size, or LumosError)."""
    from . import metrics

    img, ref_img = cell["image"], ref["image"]
    if (img.width, img.height) != (ref_img.width, ref_img.height):
        raise LumosError(f"--reference: cell {cell['label']} is {img.width}x{img.height} and the reference "
                         f"({ref['label']}) {ref_img.width}x{ref_img.height}: only images of one size compare")
    return metrics.compare(img.array, ref_img.array)


def _progress_text(cell: dict) -> str:
    """`48x36, 0.12 s`, then `, reference` or `, RMSE 0.0123 · rel. err. 4.5%`; or `not rendered: why`."""
    if cell["image"] is None:
        return f"not rendered: {cell['error']}"
    text = f"{cell['image'].width}x{cell['image'].height}, {format_seconds(cell['render_s'])}"
    if cell.get("reference"):
        return text + ", reference"
    return text + (f", {format_figures(cell['figures'])}" if cell.get("figures") else "")


def _jobs(scene, entries, settings: dict, max_cell_width: Optional[int]) -> list[tuple[str, dict]]:
    """`(label, settings)` per cell that can be rendered now: cell size, then `settings`, then the entry's own."""
    size = {}
    width, height = scene.render.width, scene.render.height
    if settings.get("width") is None and max_cell_width is not None and width > max_cell_width:
        size = {"width": max_cell_width}
        if settings.get("height") is None:
            size["height"] = max(1, round(height * max_cell_width / width))
    jobs = []
    for label, entry in entries:
        if "method" not in entry:
            raise LumosError(f"sheet: entry {label!r} names no method")
        if entry["method"] in api.METHODS:
            job = {**size, **settings, **entry}
            if job["method"] != "whitted" and settings.get("antialias", scene.render.antialias) == "adaptive":
                # adaptive anti-aliasing is whitted's: the others supersample at about its cost
                job["antialias"] = "supersample"
                if settings.get("spp") is None:
                    job["spp"] = max(scene.render.spp, ADAPTIVE_STAND_IN_SPP)
                label = f"{label} · supersampled"
            depth = settings.get("max_depth", scene.render.max_depth)
            if job["method"] == "whitted" and depth is not None and depth < 0 and entry.get("max_depth") is None:
                # unbounded depth is the path tracer's (roulette ends its paths); whitted takes its default
                job["max_depth"] = WHITTED_STAND_IN_DEPTH
                label = f"{label} · depth {WHITTED_STAND_IN_DEPTH}"
            if job["method"] == "path" and settings.get("spp") is None and scene.render.spp < PATH_MIN_SPP:
                # a scene's spp is meant for anti-aliasing; a path tracer needs samples to show its light
                job["spp"] = PATH_MIN_SPP
                label = f"{label} · {PATH_MIN_SPP} spp"
            jobs.append((label, job))
    if not jobs:
        raise LumosError(f"sheet: no entry uses an available method ({', '.join(api.METHODS)})")
    return jobs


def _warm_up(scene, jobs: list[dict], progress: bool, say) -> float:
    """Render each (method, shading) pair once, tiny, so the timed renders find their kernels compiled.

    With `progress` as for the cells, so that loading the progress bar's module is not timed either.
    """
    started = time.perf_counter()
    seen = set()
    for job in jobs:
        key = (job["method"], job.get("shading"))
        if key not in seen:
            seen.add(key)
            say(f"warming up {job['method']}" + (f" ({job['shading']})" if job.get("shading") else ""))
            try:
                api.render(scene, progress, **{**job, "width": WARMUP_SIZE, "height": WARMUP_SIZE, "spp": 1})
            except LumosError:
                pass  # the method cannot draw this scene: its cell will say why
    return time.perf_counter() - started


def _title_of(scene) -> str:
    if isinstance(scene, (str, os.PathLike)):
        return Path(scene).name
    source = getattr(scene, "source", None)
    return source.name if source is not None else "scene"


def _say(text: str) -> None:
    print(f"lumos: sheet {text}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------------------------------------- writing


def check_sheet_path(path: str | os.PathLike) -> Path:
    """Check that a sheet could be written to `path` (.png, .jpg or .jpeg, in a writable folder); return it."""
    out = Path(path)
    fail = f"cannot write sheet '{path}'"
    if out.suffix.lower() not in SHEET_FORMATS:
        shown = f"unsupported extension '{out.suffix}'" if out.suffix else "no extension"
        raise LumosError(f"{fail}: {shown} (a sheet is {', '.join(SHEET_FORMATS)})")
    if out.is_dir():
        raise LumosError(f"{fail}: it is a directory")
    folder = out.parent
    if not folder.is_dir():
        raise LumosError(f"{fail}: folder '{folder}' does not exist" if not folder.exists()
                         else f"{fail}: '{folder}' is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise LumosError(f"{fail}: permission denied (folder '{folder}' is not writable)")
    return out


def save_sheet(sheet, path: str | os.PathLike) -> Path:
    """Write `sheet` (a PIL image) to `path` atomically, as PNG or JPEG by its extension; returns the path."""
    from ..io.atomic import write_atomically

    out = check_sheet_path(path)
    fmt = SHEET_FORMATS[out.suffix.lower()]
    options = {"quality": 95} if fmt == "JPEG" else {}
    write_atomically(out, lambda tmp: sheet.save(tmp, format=fmt, **options), f"cannot write image '{out}'")
    return out
