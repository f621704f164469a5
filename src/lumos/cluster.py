"""Rendering on a Dask cluster, with the same image, bit for bit, as one machine renders.

    lumos render scene.yaml --cluster local:2              # a LocalCluster of 2 worker processes
    lumos render scene.yaml --cluster tcp://HOST:8786      # a running `dask scheduler`
    lumos.render(scene, client=dask_client)

The scene is compiled once, here, and what the method reads (the scene's arrays and BVH, the camera, the
settings) is scattered once to every worker (`Client.scatter(..., broadcast=True)`); every worker loads its kernels
with one small piece of the image before the real work is handed out. The work is cut per method:

- **path**: pieces are (sample block, band of rows): `methods.path.SAMPLE_BLOCK` samples of every pixel of the band,
  summed from zero on a worker (`methods.path.render_block`), or runs of whole blocks when there are many. The pieces are added here in block order (all bands
  of block 0, then of block 1, …), never in the order they finish: the additions a local render makes, in the
  same order, so the image is the same to the bit for any number of workers and any order of completion.
- **raycast, whitted**: pieces are bands of rows (tiles); every pixel is computed by itself, so a band's pixels are
  the whole image's.
- **raster, radiosity**: one piece, the whole image (a still raster image takes milliseconds and a radiosity
  solution is one global solve); animations spread their frames over the workers instead (`lumos.animate`).

A worker that dies has its pieces run again by Dask; pieces are pure functions of their inputs, so the image does
not change. With a checkpoint folder every finished piece is kept on disk (`.npz`, written whole or not at all),
and a run given `resume=True` loads them and renders only the rest.

Dask moves pickled data between the machines: a cluster must be a trusted network, or use Dask's TLS settings
(`tls://` addresses, with the certificates in Dask's configuration), see docs/cluster.md.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np

from .errors import LumosError

#: Seconds to wait for a scheduler to answer before saying it cannot be reached.
CONNECT_TIMEOUT_S = 10
#: Pieces per worker a path render aims for (bands × blocks), so the last pieces even out the workers' loads.
PIECES_PER_WORKER = 8
#: Bands of rows a render in this process with a checkpoint folder is cut into (what a killed run can lose).
LOCAL_BANDS = 16
#: The checkpoint folder's manifest: what render its pieces belong to.
MANIFEST = "lumos-checkpoint.json"


# ------------------------------------------------------------------------------------------------ connecting


def connect(spec: str):
    """A `distributed.Client` for `spec`: `local` or `local:N` (a LocalCluster of N worker processes with one
    thread each; N defaults to the cores), or a scheduler's address (`tcp://HOST:PORT`, `tls://…`). Returns
    (client, close): call close() when done (it also stops a LocalCluster started here)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise LumosError("--cluster: needs Dask's distributed scheduler: pip install 'lumos[cluster]'") from None
    if spec == "local" or spec.startswith("local:"):
        import os

        count = spec.partition(":")[2]
        if count and not (count.isdigit() and int(count) > 0):
            raise LumosError(f"--cluster {spec}: local:N takes a number of worker processes N ≥ 1")
        n = int(count) if count else (os.cpu_count() or 1)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0")
        client = Client(cluster)

        def close():
            client.close()
            cluster.close()

        return client, close
    if "://" not in spec:
        raise LumosError(f"--cluster {spec}: give local, local:N or a scheduler address such as tcp://HOST:8786")
    try:
        client = Client(spec, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError) as exc:
        reason = " ".join(str(exc).split())[:120] or type(exc).__name__
        raise LumosError(f"--cluster {spec}: no Dask scheduler answers there ({reason})") from None
    except ValueError as exc:  # a malformed address
        raise LumosError(f"--cluster {spec}: {' '.join(str(exc).split())[:160]}") from None
    return client, client.close


def workers_of(client) -> list[str]:
    """The addresses of the client's workers (waits for one if none has joined yet)."""
    client.wait_for_workers(1)
    return sorted(client.scheduler_info()["workers"])


# ------------------------------------------------------------------------------------------- what workers run


def worker_threads() -> int | None:
    """The threads this Dask worker was started with (None, all of Numba's, outside a worker)."""
    try:
        from distributed import get_worker

        import numba

        return min(int(get_worker().state.nthreads), numba.config.NUMBA_NUM_THREADS)
    except (ImportError, ValueError, AttributeError):
        return None


def _worker_name() -> str:
    try:
        from distributed import get_worker

        return str(get_worker().address)
    except (ImportError, ValueError):
        return "local"


def _timed(run: Callable[[], Any], rays_of: Callable[[Any], int]):
    started = time.perf_counter()
    result = run()
    return result, {"worker": _worker_name(), "seconds": time.perf_counter() - started, "rays": rays_of(result)}


def path_piece(job, b0: int, b1: int, y0: int, y1: int):
    """A worker's path piece: ([methods.path.PathSums of block b over rows y0 … y1−1 for b in b0 … b1−1], its
    figures). Each block's sums are kept apart: adding them here would add in another order than a local render."""
    from .methods.path import render_block

    threads = worker_threads()
    return _timed(lambda: [render_block(job, b, y0, y1, threads=threads) for b in range(b0, b1)],
                  lambda parts: sum(int(p.rays_per_row.sum()) for p in parts))


def tile_piece(shipped, y0: int, y1: int):
    """A worker's band of rows y0 … y1−1 of a raycast or whitted image (the whole image for the other methods):
    (the `Film`'s radiance and AOVs cut to those rows, its ray counts), its figures."""
    render, compiled, camera, settings = shipped
    settings = settings.model_copy(update={"threads": worker_threads()})
    whole = settings.method not in TILED_METHODS

    def run():
        film = render(compiled, camera, settings) if whole else render(compiled, camera, settings, rows=(y0, y1))
        rows = slice(y0, y1)
        return {"radiance": film.radiance[rows].copy(), "aovs": {k: v[rows].copy() for k, v in film.aovs.items()},
                "rays": int(film.rays), "primary_rays": int(film.primary_rays), "extra": dict(film.extra)}

    return _timed(run, lambda part: part["rays"])


#: Methods whose pieces are bands of rows (`rows=` in their entry points).
TILED_METHODS = ("raycast", "whitted")


# ------------------------------------------------------------------------------------------- the render itself


@dataclass
class ClusterStats:
    """What a cluster render did: pieces, the workers' figures, bytes shipped."""

    pieces: int = 0
    resumed: int = 0
    scatter_bytes: int = 0
    result_bytes: int = 0
    workers: dict = field(default_factory=dict)  # address -> {"tasks", "seconds", "rays"}
    dashboard: str = ""

    def record(self, figures: dict, nbytes: int) -> None:
        w = self.workers.setdefault(figures["worker"], {"tasks": 0, "seconds": 0.0, "rays": 0})
        w["tasks"] += 1
        w["seconds"] += figures["seconds"]
        w["rays"] += figures["rays"]
        self.result_bytes += nbytes

    def as_dict(self) -> dict:
        return {"cluster_pieces": self.pieces, "cluster_resumed_pieces": self.resumed,
                "cluster_scatter_bytes": self.scatter_bytes, "cluster_result_bytes": self.result_bytes,
                "cluster_workers": self.workers, "cluster_dashboard": self.dashboard}


def render_pieces(client, render, compiled, camera, settings, progress=None, checkpoint=None, resume=False):
    """Render `compiled` through `camera` with `settings` piece by piece: on the Dask `client`'s workers, or with
    client None in this process (one piece after another, each on all threads: what a local render with a
    checkpoint folder does). `render` is the method's entry point (`api.entry_point`; path's pieces call
    `methods.path.render_block` instead). Returns the method's `Film` (the same as a local render's, to the bit)
    with the figures of the pieces in its `extra`."""
    from .methods.capabilities import check_settings

    check_settings(settings)
    if settings.time_limit is not None:
        raise LumosError("render.time_limit: a render on a cluster or with a checkpoint folder takes all its "
                         "samples (a time limit is for a render in this process)")
    stats = ClusterStats(dashboard=str(getattr(client, "dashboard_link", "") or ""))
    store = Checkpoint(Path(checkpoint), resume) if checkpoint is not None else None
    n_workers = 1 if client is None else len(workers_of(client))
    if settings.method == "path":
        film = _render_path(client, compiled, camera, settings, n_workers, progress, store, stats)
    else:
        film = _render_tiles(client, (render, compiled, camera, settings), n_workers, progress, store, stats)
    film.extra.update(stats.as_dict())
    return film


def _scatter(client, data, stats: ClusterStats):
    """Ship `data` once to every worker; returns its future (`data` itself without a client)."""
    import pickle

    if client is None:
        return data
    stats.scatter_bytes = len(pickle.dumps(data, protocol=pickle.HIGHEST_PROTOCOL))
    return client.scatter(data, broadcast=True, hash=False)


def _warm(client, piece: Callable, shipped, args: tuple) -> None:
    """Run one small piece on every worker (loads the kernels there) before the real work is handed out."""
    if client is None:
        return
    futures = [client.submit(piece, shipped, *args, workers=[w], allow_other_workers=False, pure=False)
               for w in workers_of(client)]
    client.gather(futures)


def _run_pieces(client, piece: Callable, shipped, todo: list[tuple], stats: ClusterStats, on_result) -> None:
    """Submit piece(shipped, *args) for each args in `todo` (in that order: Dask starts them roughly so) and call
    on_result(args, result) as each comes back, in completion order. Ctrl-C cancels what is left and re-raises."""
    import pickle

    if client is None:
        for args in todo:
            result, figures = piece(shipped, *args)
            stats.record(figures, 0)
            on_result(args, result)
        return
    from distributed import as_completed

    futures = {client.submit(piece, shipped, *args, pure=False): args for args in todo}
    try:
        for future in as_completed(futures):
            result, figures = future.result()
            stats.record(figures, len(pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL)))
            on_result(futures[future], result)
            future.release()
    except BaseException:
        client.cancel(list(futures))
        raise


def _resume(pieces: list, store, stats: ClusterStats, take) -> list:
    """Hand the pieces the checkpoint folder holds to take(args, result); returns the others, still to render."""
    todo = []
    for args in pieces:
        saved = store.load(args) if store is not None else None
        if saved is not None:
            stats.resumed += 1
            take(args, saved)
        else:
            todo.append(args)
    return todo


def _bands(height: int, count: int) -> list[tuple[int, int]]:
    from .methods.common import row_bands

    return row_bands(height, bands=max(1, min(count, height)))


def _path_layout(job, n_workers: int, local: bool):
    """How a path render is cut: (groups of consecutive blocks [b0, b1), bands of rows). About PIECES_PER_WORKER
    pieces per worker: runs of whole blocks when there are enough blocks, bands of rows of single blocks when
    there are not. In this process (a checkpoint folder): LOCAL_BANDS bands of each block."""
    blocks, height = job.blocks, int(job.height)
    target = PIECES_PER_WORKER * n_workers
    if local:
        return [(b, b + 1) for b in range(blocks)], _bands(height, LOCAL_BANDS)
    if blocks >= target:
        cuts = np.linspace(0, blocks, target + 1).round().astype(int)
        return [(int(a), int(b)) for a, b in zip(cuts[:-1], cuts[1:]) if b > a], [(0, height)]
    return [(b, b + 1) for b in range(blocks)], _bands(height, -(-target // blocks))


def _render_path(client, compiled, camera, settings, n_workers, progress, store, stats):
    from .methods.path import PathSums, film_of, path_job

    job = path_job(compiled, camera, settings)
    groups, bands = _path_layout(job, n_workers, client is None)
    if store is not None:
        layout = store.open(_fingerprint(job), {"method": "path", "groups": groups, "bands": bands})
        groups, bands = [tuple(g) for g in layout["groups"]], [tuple(b) for b in layout["bands"]]
    pieces = [(b0, b1, y0, y1) for b0, b1 in groups for y0, y1 in bands]
    stats.pieces = len(pieces)
    total = PathSums(job)
    arrived: dict[tuple, list] = {}
    state = {"next": 0, "blocks_done": 0, "work_done": 0, "samples": 0, "pieces": 0}
    work = int(job.height) * job.blocks
    started = time.perf_counter()
    note = getattr(progress, "note", None)

    def take(args, sums: list):
        arrived[args] = sums
        if store is not None:
            store.save(args, sums)
        state["work_done"] += (args[1] - args[0]) * (args[3] - args[2])
        state["pieces"] += 1
        state["samples"] += sum(int(np.diff(job.block_samples(b))[0]) for b in range(args[0], args[1])) * \
            (args[3] - args[2]) * int(job.width)
        if note is not None:
            rate = state["samples"] / max(time.perf_counter() - started, 1e-9)
            note(f"{state['pieces']}/{len(pieces)} pieces, {rate / 1e6:.2f} M samples/s")
        # add whole groups of blocks, in block order; within a block, its bands in band order
        while state["next"] < len(pieces):
            mine = pieces[state["next"]:state["next"] + len(bands)]
            if not all(p in arrived for p in mine):
                break
            b0, b1 = mine[0][:2]
            parts = [arrived.pop(p) for p in mine]
            for k in range(b1 - b0):
                for part in parts:
                    total.add(part[k], first_block=b0 + k == 0)
            state["next"] += len(bands)
            state["blocks_done"] = b1
        if progress is not None:
            progress(min(state["work_done"] / work, 1.0))

    todo = _resume(pieces, store, stats, take)
    stopped = None
    if todo:
        shipped = _scatter(client, job, stats)
        _warm(client, path_piece, shipped, (todo[0][0], todo[0][0] + 1, todo[0][2], todo[0][2] + 1))
        try:
            _run_pieces(client, path_piece, shipped, todo, stats, take)
        except KeyboardInterrupt:
            stopped = "interrupted"
    done = min(state["blocks_done"] * job.block, int(job.spp))
    if done == 0:
        raise LumosError("render: interrupted before the first block of samples was done")
    return film_of(total, done, settings, n_workers, passes=state["blocks_done"], stopped=stopped, final=True)


def _render_tiles(client, shipped, n_workers, progress, store, stats):
    from .methods.common import Film

    _, compiled, camera, settings = shipped
    h, w = settings.height, settings.width
    tiled = settings.method in TILED_METHODS
    bands = (_bands(h, LOCAL_BANDS if client is None else PIECES_PER_WORKER * n_workers) if tiled else [(0, h)])
    if store is not None:
        layout = store.open(_fingerprint((compiled.arrays, camera.model_dump(), settings.model_dump())),
                            {"method": settings.method, "bands": bands})
        bands = [tuple(b) for b in layout["bands"]]
    stats.pieces = len(bands)
    radiance = np.zeros((h, w, 3), np.float32)
    aovs: dict[str, np.ndarray] = {}
    counts = {"rays": 0, "primary_rays": 0, "rows": 0}
    extra: dict = {}

    def take(args, part):
        y0, y1 = args
        if store is not None:
            store.save(args, part)
        radiance[y0:y1] = part["radiance"]
        for name, rows in part["aovs"].items():
            if name not in aovs:
                aovs[name] = np.zeros((h,) + rows.shape[1:], rows.dtype)
            aovs[name][y0:y1] = rows
        counts["rays"] += part["rays"]
        counts["primary_rays"] += part["primary_rays"]
        counts["rows"] += y1 - y0
        extra.update(part["extra"])
        if progress is not None:
            progress(counts["rows"] / h)

    todo = _resume(bands, store, stats, take)
    if todo:
        shipped = _scatter(client, shipped, stats)
        if tiled:
            _warm(client, tile_piece, shipped, (todo[0][0], todo[0][0] + 1))
        _run_pieces(client, tile_piece, shipped, todo, stats, take)
    # the rays of a tiled render: each tile counts its own; a whole-image piece its total
    return Film(radiance, {name: aovs[name] for name in settings.aov if name in aovs}, counts["rays"],
                n_workers, primary_rays=counts["primary_rays"], extra=extra)


# -------------------------------------------------------------------------------------------- the checkpoint


def _fingerprint(obj) -> str:
    """A hash of nested tuples, dicts, dataclasses and arrays (the bytes, dtype and shape of each array)."""
    digest = hashlib.sha256()

    def walk(x):
        if isinstance(x, np.ndarray):
            digest.update(f"a{x.dtype.str}{x.shape}".encode())
            digest.update(np.ascontiguousarray(x).tobytes())
        elif isinstance(x, dict):
            digest.update(b"d")
            for k in sorted(x, key=str):
                walk(str(k))
                walk(x[k])
        elif isinstance(x, (tuple, list)):
            digest.update(f"t{len(x)}".encode())
            for v in x:
                walk(v)
        elif hasattr(x, "__dataclass_fields__"):
            walk({k: getattr(x, k) for k in x.__dataclass_fields__})
        else:
            digest.update(repr(x).encode())

    walk(obj)
    return digest.hexdigest()


class PieceFolder:
    """A checkpoint folder of finished pieces, `<kind>-<numbers>.npz` (named arrays, no pickles), each written whole
    or not at all and read back only when resuming. A folder holding pieces of an earlier run is refused unless
    resuming (a new run never writes over them)."""

    def __init__(self, folder, resume: bool, kind: str):
        self.folder, self.resume, self.kind = Path(folder), resume, kind
        if not resume and self.folder.exists() and any(self.folder.glob(f"{kind}-*.npz")):
            raise LumosError(f"--checkpoint {self.folder}: holds {kind}s of an earlier run; add --resume to go on "
                             "with it, or give an empty folder")

    def _file(self, numbers: tuple) -> Path:
        return self.folder / (self.kind + "-" + "-".join(f"{a:06d}" for a in numbers) + ".npz")

    def save_arrays(self, numbers: tuple, arrays: dict) -> None:
        from .io.atomic import write_atomically

        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise LumosError(f"--checkpoint {self.folder}: {' '.join(str(exc).split())[:120]}") from None
        write_atomically(self._file(numbers), lambda tmp: np.savez(tmp, **arrays), f"--checkpoint {self.folder}",
                         suffix=".npz")

    def load_arrays(self, numbers: tuple) -> Optional[dict]:
        """The saved piece's arrays, or None (not there, damaged — it is rendered again — or not resuming)."""
        path = self._file(numbers)
        if not self.resume or not path.is_file():
            return None
        try:
            with np.load(path, allow_pickle=False) as data:
                return {k: data[k] for k in data.files}
        except (OSError, ValueError, KeyError):
            return None


class Checkpoint(PieceFolder):
    """The pieces of one render (`piece-<args>.npz`) and a manifest naming the render they belong to."""

    def __init__(self, folder: Path, resume: bool):
        super().__init__(folder, resume, "piece")

    def open(self, fingerprint: str, layout: dict) -> dict:
        """Check (resume) or start the folder for this render; returns how to cut the render (`layout`: lists of
        bands of rows and groups of blocks): a resumed render keeps the cuts it was started with, so its pieces
        fit."""
        manifest = self.folder / MANIFEST
        layout = json.loads(json.dumps(layout))  # tuples to lists, as read back
        if self.resume:
            if not manifest.is_file():
                raise LumosError(f"--resume: {self.folder} holds no lumos checkpoint ({MANIFEST} is missing)")
            try:
                saved = json.loads(manifest.read_text())
            except (OSError, ValueError) as exc:
                raise LumosError(f"--resume: {manifest}: cannot be read ({' '.join(str(exc).split())[:100]})") from None
            if saved.get("fingerprint") != fingerprint:
                raise LumosError(f"--resume: {self.folder} holds the pieces of another render (scene or settings "
                                 "differ); use a new --checkpoint folder")
            return saved["layout"]
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            manifest.write_text(json.dumps({"fingerprint": fingerprint, "layout": layout}))
        except OSError as exc:
            raise LumosError(f"--checkpoint {self.folder}: {' '.join(str(exc).split())[:120]}") from None
        return layout

    def save(self, args: tuple, result) -> None:
        self.save_arrays(args, _to_arrays(result))

    def load(self, args: tuple):
        """The saved piece `args`, or None (not there, damaged, or not resuming)."""
        arrays = self.load_arrays(args)
        return None if arrays is None else _from_arrays(arrays)


def _to_arrays(result) -> dict:
    """A piece as named arrays (no pickles in a checkpoint)."""
    if isinstance(result, dict):  # a tile
        out = {"radiance": result["radiance"], "counts": np.array([result["rays"], result["primary_rays"]])}
        out.update({f"aov_{k}": v for k, v in result["aovs"].items()})
        out["extra"] = np.array(json.dumps(result["extra"]))
        return out
    out = {"blocks": np.array(len(result))}  # path: the sums of each block of the piece
    for k, part in enumerate(result):
        out.update({f"{k}_y0": np.array(part.y0), f"{k}_keep": np.array(part.keep)})
        out.update({f"{k}_{name}": getattr(part, name) for name in part.BUFFERS})
    return out


def _from_arrays(data: dict):
    if "blocks" in data:
        from .methods.path import PathSums

        return [PathSums.of_buffers(data[f"{k}_y0"], data[f"{k}_keep"],
                                    {name: data[f"{k}_{name}"] for name in PathSums.BUFFERS})
                for k in range(int(data["blocks"]))]
    return {"radiance": data["radiance"], "rays": int(data["counts"][0]), "primary_rays": int(data["counts"][1]),
            "aovs": {k[4:]: v for k, v in data.items() if k.startswith("aov_")},
            "extra": json.loads(str(data["extra"]))}


def describe(stats: dict) -> Optional[str]:
    """One line on a cluster render's figures for the CLI's summary (None for a local render)."""
    if "cluster_pieces" not in stats:
        return None
    workers = stats["cluster_workers"]
    if set(workers) <= {"local"}:
        line = f"{stats['cluster_pieces']} pieces in this process, kept in the checkpoint folder"
    else:
        line = (f"cluster: {stats['cluster_pieces']} pieces on {len(workers)} workers, "
                f"{_size(stats['cluster_scatter_bytes'])} scattered to each, "
                f"{_size(stats['cluster_result_bytes'])} returned")
    if stats["cluster_resumed_pieces"]:
        line += f", {stats['cluster_resumed_pieces']} resumed from the checkpoint"
    return line


def _size(nbytes: int) -> str:
    return f"{nbytes / 1e6:.1f} MB" if nbytes >= 1e6 else f"{nbytes / 1e3:.1f} kB"
