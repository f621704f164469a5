"""Rendering an animation: one `Image` per frame, each the render of the scene at the frame's time.

    scene = lumos.load_scene("examples/animation/turntable.yaml")
    for img in lumos.render_frames(scene, frames=range(0, 48, 2), method="raycast", width=320, height=240):
        img.save(f"frame_{img.stats['frame']:04d}.png")

Frame k is `render_frame(scene, k)` = `lumos.render(scene_at(scene, k / fps), **settings)`, the same image bit for
bit (and the function a cluster maps over its workers). With method `radiosity`, an animation that moves only
the camera is solved once and every frame drawn from that solution (the view independence of radiosity); each
Image's `stats["radiosity_solves"]` says how many solves its frame took (1 for the frame that solved, else 0).
"""

from __future__ import annotations

import numbers
import os
from typing import TYPE_CHECKING, Callable, Iterable, Iterator, Optional

from .errors import LumosError
from .scene.animation import animated_kinds, frame_count, frame_time, scene_at

if TYPE_CHECKING:
    from .image import Image


def _scene(scene):
    from .scene.loader import load_scene

    return load_scene(scene)


def _source(scene) -> str:
    return str(scene.source) if scene.source is not None else "scene"


def describe_frames(frames) -> str:
    """A frame selection as the command line writes it: 0:48, 0:48:2, 5, [0, 3, 7]."""
    if isinstance(frames, (range, slice)):
        start = "" if frames.start is None else frames.start
        stop = "" if frames.stop is None else frames.stop
        step = "" if frames.step in (None, 1) else f":{frames.step}"
        return f"{start}:{stop}{step}"
    if isinstance(frames, numbers.Integral):
        return str(frames)
    return "[" + ", ".join(map(str, frames)) + "]"


def frame_indices(scene, frames=None) -> list[int]:
    """The frame numbers `frames` selects: None (all), an int, a range, a slice (half-open, as Python's) or a
    list of frame numbers. Raises LumosError (one line) for a selection outside the animation, an empty one, or
    negative numbers."""
    scene = _scene(scene)
    n = frame_count(scene)
    if frames is None:
        return list(range(n))
    what = describe_frames(frames)
    have = (f"the animation has {n} frame{'s' if n != 1 else ''} (0 to {n - 1})" if scene.animation is not None
            else "the scene has no animation: block, so one frame (0)")
    if isinstance(frames, bool):
        raise LumosError(f"frames: expected a frame number, a range, a slice or a list, got {frames!r}")
    if isinstance(frames, numbers.Integral):
        frames = [int(frames)]
    elif isinstance(frames, (range, slice)):
        start = 0 if frames.start is None else frames.start
        stop = n if frames.stop is None else frames.stop
        step = 1 if frames.step is None else frames.step
        if any(not isinstance(x, int) or isinstance(x, bool) for x in (start, stop, step)):
            raise LumosError(f"frames {what}: start, stop and step must be integers")
        if step <= 0:
            raise LumosError(f"frames {what}: the step must be at least 1")
        if start < 0 or stop < 0:
            raise LumosError(f"frames {what}: frame numbers count from 0 ({have})")
        if stop > n:
            raise LumosError(f"{_source(scene)}: frames {what} are outside the animation: {have}")
        frames = list(range(start, stop, step))
        if not frames:
            raise LumosError(f"frames {what}: selects no frames; {have}")
        return frames
    try:
        frames = list(frames)
    except TypeError:
        raise LumosError(f"frames: expected a frame number, a range, a slice or a list, got "
                         f"{type(frames).__name__}") from None
    if not frames:
        raise LumosError("frames: the list of frames is empty")
    for k in frames:
        if not isinstance(k, numbers.Integral) or isinstance(k, bool):
            raise LumosError(f"frames {what}: frame numbers are integers, got {k!r}")
        if not 0 <= k < n:
            raise LumosError(f"{_source(scene)}: frame {k} is outside the animation: {have}")
    return [int(k) for k in frames]


def render_at(scene, t: float, solution=None, progress=False, **settings) -> "Image":
    """The scene at time `t` rendered: `lumos.render(scene_at(scene, t))`, or, with the animation's
    `motion_samples` N > 1 and the camera's shutter open, the mean of N renders of the scene at the times
    t + open + (i + ½)/N · (close − open), each with the shutter closed (an accumulation buffer, Haeberli and
    Akeley 1990): every track — rotations, scales, the camera, lights, materials — blurs along its own curve, at
    N renders' cost. The AOVs are the middle sub-frame's; stats gain `motion_samples`."""
    import numpy as np

    from .api import render
    from .image import Image

    n = scene.animation.motion_samples if scene.animation is not None else 1
    shutter = tuple(scene.camera.shutter)
    if n <= 1 or shutter[1] <= shutter[0]:
        return render(scene_at(scene, t), progress=progress, solution=solution, **settings)
    closed = scene.model_copy(update={"camera": scene.camera.model_copy(update={"shutter": (0.0, 0.0)})})
    total, middle, rays, render_s = None, None, 0, 0.0
    for i in range(n):
        part = None if not callable(progress) else (lambda f, i=i: progress((i + f) / n))
        image = render(scene_at(closed, t + shutter[0] + (i + 0.5) / n * (shutter[1] - shutter[0])),
                       progress=part or False, solution=solution, **settings)
        total = image.array.astype(np.float64) if total is None else total + image.array
        rays += int(image.stats.get("rays", 0))
        render_s += float(image.stats.get("render_s", 0.0))
        if i == n // 2:
            middle = image
    stats = {**middle.stats, "rays": rays, "render_s": render_s, "motion_samples": n}
    return Image((total / n).astype(np.float32), aovs=middle.aovs, stats=stats, exposure=middle.exposure)


def render_frame(scene, frame: int, solution=None, progress=False, **settings) -> "Image":
    """Frame `frame` of the scene's animation: `lumos.render(scene_at(scene, frame / fps), **settings)`.
    `solution` (method radiosity): a Solution (or a saved one's path) to draw instead of solving; `progress` as
    `lumos.render`'s. The Image's
    stats gain `frame`, `time` (seconds) and `radiosity_solves` (the solves this frame took: 0 or 1)."""
    scene = _scene(scene)
    frame_indices(scene, [frame])
    t = frame_time(scene, frame)
    image = render_at(scene, t, progress=progress, solution=solution, **settings)
    solved = image.stats.get("method") == "radiosity" and solution is None
    image.stats.update(frame=frame, time=t, radiosity_solves=1 if solved else 0)
    return image


def solves_once(scene, method: str) -> bool:
    """Whether an animation of `scene` rendered with `method` needs one radiosity solve for all its frames:
    method radiosity and no track touches geometry, lights or materials (only the camera moves)."""
    return method == "radiosity" and animated_kinds(_scene(scene)) <= {"camera"}


class SharedSolutions:
    """The radiosity solutions of the frames of a camera-only animation, one per distinct scene digest: one solve
    in all, unless the camera goes into a solid (whose inside then becomes patches: another digest). `get(scene)`
    with the scene at a frame's time gives (its solution, solves it took: 0 or 1); a cluster driver can solve
    here once and hand the solution to every `render_frame`."""

    def __init__(self, settings):
        """settings: the resolved RenderSettings of the render (`api.resolve_settings`)."""
        self.settings = settings
        self.bounds = None
        self.by_digest: dict[str, object] = {}

    def digest(self, scene) -> Optional[str]:
        from .compile.patches import patch_sides
        from .scene.digest import scene_digest

        if self.bounds is None:
            return None
        return scene_digest(scene, patch_sides(scene, self.bounds, self.settings.tessellation))

    def get(self, scene) -> tuple[object, int]:
        """(solution for `scene`, solves it took: 0 or 1)."""
        from .compile import compile_scene, patches
        from .methods.common import set_threads
        from .radiosity.solve import solve_compiled

        digest = self.digest(scene)
        if digest is not None and digest in self.by_digest:
            return self.by_digest[digest], 0
        compiled = compile_scene(scene)
        patches.attach(compiled, scene, self.settings)
        set_threads(self.settings.threads)
        solution = solve_compiled(compiled, self.settings)
        self.bounds = compiled.bounds if self.bounds is None else self.bounds
        self.by_digest[compiled.digest] = solution
        return solution, 1


def render_frames(scene, frames=None, progress: bool | Callable[[float], None] = False, solution=None,
                  client=None, checkpoint=None, resume: bool = False, **settings) -> Iterator["Image"]:
    """Yield one Image per frame of `frames` (None: every frame; an int, a range, a slice or a list of frame
    numbers), in that order: frame k is `render_frame(scene, k, **settings)`, bit for bit.

    Every selected frame's scene is made (and checked) before the first is rendered, so bad input stops the
    generator before any image. Method radiosity with only the camera animated solves once (see the module
    doc); `solution` draws every frame from a given Solution instead. `progress=True` shows one bar over all
    frames; a callable receives the finished fraction of them.

    `client` (a `distributed.Client`): the frames are rendered on its Dask workers, one task per frame (the
    scene scattered once; a camera-only radiosity animation solved here, once, and its solution scattered), and
    yielded in frame order, each the same image as here. `checkpoint` (a folder): every finished frame is kept
    there (`frame-NNNNNN.npz`), and with `resume=True` the frames found there are not rendered again."""
    from . import api

    scene = _scene(scene)
    indices = frame_indices(scene, frames)
    cfg = api.resolve_settings(scene, settings)  # bad settings fail here, before any frame
    times = [frame_time(scene, k) for k in indices]
    scenes = [scene_at(scene, t) for t in times]  # every frame's values checked before the first render
    if isinstance(solution, (str, os.PathLike)) and cfg.method == "radiosity":
        from .radiosity.solution import Solution

        solution = Solution.load(solution)  # read once; each frame's render checks that it matches
    shared = None
    if solution is None and len(indices) > 1 and solves_once(scene, cfg.method):
        shared = SharedSolutions(cfg)
    store = FrameStore(checkpoint, resume) if checkpoint is not None else None
    if client is not None or store is not None:
        return _frames_in_pieces(client, store, scene, indices, times, scenes, shared, solution, progress, settings)
    return _frames(scene, indices, times, scenes, shared, solution, progress, settings)


def frame_piece(scene, frame: int, solution, settings: dict):
    """A Dask worker's task: frame `frame` of `scene` on the worker's threads (`render_frame`)."""
    from .cluster import worker_threads

    threads = worker_threads()
    return render_frame(scene, frame, solution=solution, **{**settings, "threads": threads or settings.get("threads")})


def _frames_in_pieces(client, store, scene, indices, times, scenes, shared, solution, progress, settings):
    """The generator of `render_frames` on a cluster or with a checkpoint folder: frames already in the folder are
    read back, the others rendered (on the workers: all submitted at once, in frame order) and yielded in frame
    order."""
    from .image import Image
    from .progress import make_progress

    n = len(indices)
    solutions = [solution] * n
    solves = [0] * n
    if shared is not None:  # solved here (once per distinct set of patches), drawn by every worker
        for i, frame_scene in enumerate(scenes):
            solutions[i], solves[i] = shared.get(frame_scene)
    saved = [store.load(k) if store is not None else None for k in indices]
    with make_progress(progress) as report:
        futures = {}
        if client is not None:
            todo = [i for i in range(n) if saved[i] is None]
            if todo:
                shipped = client.scatter(scene, broadcast=True, hash=False)
                distinct = {id(s): s for s in solutions if s is not None}
                solution_of = {key: client.scatter(s, broadcast=True, hash=False) for key, s in distinct.items()}
                for i in todo:
                    given = solution_of.get(id(solutions[i])) if solutions[i] is not None else None
                    futures[i] = client.submit(frame_piece, shipped, indices[i], given, settings, pure=False)
        try:
            for i, k in enumerate(indices):
                if saved[i] is not None:
                    image = Image(saved[i]["array"], aovs=saved[i]["aovs"], stats=saved[i]["stats"],
                                  exposure=saved[i]["exposure"])
                else:
                    if i in futures:
                        image = futures.pop(i).result()
                    else:
                        image = render_frame(scene, k, solution=solutions[i], **settings)
                    if solutions[i] is not None and shared is not None:
                        image.stats["radiosity_solves"] = solves[i]
                    if store is not None:
                        store.save(k, image)
                if report is not None:
                    report((i + 1) / n)
                yield image
        finally:
            if futures:
                client.cancel(list(futures.values()))


class FrameStore:
    """A checkpoint folder of finished frames: `frame-NNNNNN.npz` (the image, its AOVs, exposure and stats)."""

    def __init__(self, folder, resume: bool):
        from .cluster import PieceFolder

        self.pieces = PieceFolder(folder, resume, "frame")

    def save(self, frame: int, image) -> None:
        import json

        import numpy as np

        arrays = {"array": image.array, "exposure": np.array(image.exposure),
                  "stats": np.array(json.dumps(image.stats, default=str))}
        arrays.update({f"aov_{k}": v for k, v in image.aovs.items()})
        self.pieces.save_arrays((frame,), arrays)

    def load(self, frame: int):
        """The saved frame as {array, aovs, exposure, stats}, or None (not there, damaged, or not resuming)."""
        import json

        data = self.pieces.load_arrays((frame,))
        if data is None or "array" not in data:
            return None
        return {"array": data["array"], "exposure": float(data["exposure"]),
                "stats": {**json.loads(str(data["stats"])), "resumed": True},
                "aovs": {k[4:]: v for k, v in data.items() if k.startswith("aov_")}}


def _frames(base, indices, times, scenes, shared, solution, progress, settings) -> Iterator["Image"]:
    """The generator of `render_frames`, once its input is checked."""
    from .api import render
    from .progress import make_progress

    n = len(indices)
    with make_progress(progress) as report:
        for i, (k, t, frame_scene) in enumerate(zip(indices, times, scenes)):
            part = None if report is None else (lambda f, i=i: report((i + f) / n))
            solves = 0
            given = solution
            if shared is not None:
                given, solves = shared.get(frame_scene)
            if base.animation is not None and base.animation.motion_samples > 1:
                image = render_at(base, t, progress=part or False, solution=given, **settings)
            else:
                image = render(frame_scene, progress=part or False, solution=given, **settings)
            if given is None and image.stats.get("method") == "radiosity":
                solves = 1
            image.stats.update(frame=k, time=t, radiosity_solves=solves)
            if report is not None:
                report((i + 1) / n)
            yield image


def frames_of(images: Iterable["Image"]) -> Iterator:
    """The 8-bit sRGB pixels (H, W, 3) of each image (after its exposure), as video encoders take them."""
    from .tonemap import to_png8

    for image in images:
        yield to_png8(image.array, image.exposure)
