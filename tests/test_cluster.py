"""Rendering on a Dask cluster (`lumos.cluster`): the same image to the bit as one process renders, with a worker
killed mid-render too; a checkpoint folder that a stopped render resumes from; one-line errors for bad input."""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

import lumos
from helpers import EXAMPLES
from lumos.errors import LumosError

distributed = pytest.importorskip("distributed")

CORNELL = str(EXAMPLES / "path" / "cornell.yaml")
SHOWCASE = str(EXAMPLES / "showcase.yaml")
#: three sample blocks, the last one short; the AOVs that read every buffer the pieces carry
PATH = dict(method="path", width=40, height=30, spp=150, aov=["variance", "albedo", "normal", "depth", "object_id"])


@pytest.fixture(autouse=True)
def small_blocks(monkeypatch):
    """Blocks of 64 samples, so that renders of a few hundred samples have several (a job carries its block size
    to the workers)."""
    from lumos.methods import path as path_method

    monkeypatch.setattr(path_method, "SAMPLE_BLOCK", 64)


@pytest.fixture(scope="module")
def client():
    from lumos.cluster import connect

    client, close = connect("local:2")
    yield client
    close()


def assert_same(a, b):
    np.testing.assert_array_equal(a.array, b.array)
    assert set(a.aovs) == set(b.aovs)
    for name in a.aovs:
        np.testing.assert_array_equal(a.aovs[name], b.aovs[name], err_msg=name)


@pytest.mark.slow
@pytest.mark.parametrize("scene, settings", [
    (CORNELL, PATH),
    (SHOWCASE, dict(method="whitted", width=48, height=36, aov=["depth", "normal"])),
    (SHOWCASE, dict(method="raycast", width=48, height=36, spp=2)),
    (SHOWCASE, dict(method="raster", width=48, height=36, shading="phong")),
], ids=["path", "whitted", "raycast", "raster"])
def test_a_cluster_render_is_the_local_render_to_the_bit(client, scene, settings):
    local = lumos.render(scene, **settings)
    remote = lumos.render(scene, client=client, **settings)
    assert_same(local, remote)
    assert remote.stats["rays"] == local.stats["rays"]
    workers = remote.stats["cluster_workers"]
    assert sum(w["tasks"] for w in workers.values()) == remote.stats["cluster_pieces"]
    if settings["method"] in ("path", "whitted", "raycast"):
        assert remote.stats["cluster_pieces"] >= 2 and len(workers) == 2  # the work was spread


@pytest.mark.slow
def test_pieces_of_several_blocks_give_the_same_image(client, monkeypatch):
    """With more blocks than pieces wanted, a piece is a run of blocks whose sums come back one by one."""
    from lumos import cluster

    monkeypatch.setattr(cluster, "PIECES_PER_WORKER", 1)
    settings = dict(PATH, width=24, height=16, spp=5 * 64 - 7)
    remote = lumos.render(CORNELL, client=client, **settings)
    assert remote.stats["cluster_pieces"] == 2
    assert_same(lumos.render(CORNELL, **settings), remote)


def test_path_blocks_and_bands_add_up_to_the_local_image_in_any_arrival_order():
    """The reduction `lumos.cluster` makes, here by hand: pieces rendered in a shuffled order and added in block
    order give the local image (more blocks than the test at the cluster, with a small SAMPLE_BLOCK)."""
    from lumos.methods import compile_for
    from lumos.methods import path as path_method
    from lumos.methods.path import PathSums, film_of, path_job, render_block

    settings = dict(PATH, spp=11, width=16, height=10)
    mp = pytest.MonkeyPatch()
    mp.setattr(path_method, "SAMPLE_BLOCK", 4)
    try:
        local = lumos.render(CORNELL, **settings)
        scene = lumos.load_scene(CORNELL)
        cfg = lumos.api.resolve_settings(scene, settings)
        job = path_job(compile_for(scene, cfg), scene.camera, cfg)
        assert job.blocks == 3 and job.block_samples(2) == (8, 11)
        pieces = [(b, y0, y1) for b in range(job.blocks) for y0, y1 in ((0, 3), (3, 10))]
        order = np.random.default_rng(1).permutation(len(pieces))
        done = {pieces[k]: render_block(job, *pieces[k]) for k in order}
        total = PathSums(job)
        for piece in pieces:
            total.add(done[piece], first_block=piece[0] == 0)
    finally:
        mp.undo()
    film = film_of(total, 11, cfg, 1, passes=3, stopped=None, final=True)
    np.testing.assert_array_equal(film.radiance, local.array)
    for name in PATH["aov"]:
        np.testing.assert_array_equal(film.aovs[name], local.aovs[name], err_msg=name)


@pytest.mark.slow
def test_a_worker_killed_mid_render_changes_nothing(client):
    pids = client.run(os.getpid)
    victim = next(iter(pids.values()))
    killed = []

    def progress(fraction):
        if not killed:  # the first piece is back: kill a worker while the others run
            os.kill(victim, signal.SIGKILL)
            killed.append(fraction)

    local = lumos.render(CORNELL, **PATH)
    remote = lumos.render(CORNELL, client=client, progress=progress, **PATH)
    assert killed and killed[0] < 1.0
    assert_same(local, remote)
    client.wait_for_workers(2)  # the nanny restarts it for the tests after this one


@pytest.mark.parametrize("method", ["path", "whitted"])
def test_a_stopped_render_resumes_from_its_checkpoint_and_renders_only_the_rest(tmp_path, method):
    settings = (dict(PATH, width=24, height=16) if method == "path"
                else dict(method="whitted", width=24, height=32))
    scene = CORNELL if method == "path" else SHOWCASE
    whole = lumos.render(scene, **settings)
    calls = []
    stop = 18 if method == "path" else 2  # path: the 16 bands of block 0 and two of block 1

    def stop_after(fraction):
        calls.append(fraction)
        if len(calls) == stop:
            raise KeyboardInterrupt

    folder = tmp_path / "pieces"
    if method == "path":  # path keeps the whole blocks done, as a local render stopped by Ctrl-C does
        partial = lumos.render(scene, checkpoint=str(folder), progress=stop_after, **settings)
        assert partial.stats["stopped"] == "interrupted" and partial.stats["spp"] == 64
    else:
        with pytest.raises(KeyboardInterrupt):
            lumos.render(scene, checkpoint=str(folder), progress=stop_after, **settings)
    saved = sorted(folder.glob("piece-*.npz"))
    assert len(saved) == stop
    with pytest.raises(LumosError, match="--resume"):  # a used folder is not overwritten by a new run
        lumos.render(scene, checkpoint=str(folder), **settings)
    resumed = lumos.render(scene, checkpoint=str(folder), resume=True, **settings)
    assert resumed.stats["cluster_resumed_pieces"] == stop
    assert resumed.stats["cluster_pieces"] == (48 if method == "path" else 16)
    assert_same(whole, resumed)
    with pytest.raises(LumosError, match="another render"):  # other settings: the pieces do not fit
        lumos.render(scene, checkpoint=str(folder), resume=True, **{**settings, "seed": 99})


def test_an_unreachable_scheduler_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys):
    from lumos import cli, cluster

    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 1)
    out = tmp_path / "x.png"
    code = cli.main(["render", CORNELL, "--cluster", "tcp://127.0.0.1:9", "-o", str(out), "--spp", "1"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and not out.exists()
    assert len(err.splitlines()) == 1 and "no Dask scheduler answers" in err and "tcp://127.0.0.1:9" in err


@pytest.mark.parametrize("argv, message", [
    (["--cluster", "local:zero"], "local:N takes a number"),
    (["--cluster", "somewhere"], "give local, local:N or a scheduler address"),
    (["--resume"], "--resume goes on from a --checkpoint folder"),
    (["--checkpoint", "DIR", "--time-limit", "3"], "--time-limit is for a render in this process"),
])
def test_bad_cluster_flags_are_one_line_and_exit_2(tmp_path, capsys, argv, message):
    from lumos import cli

    out = tmp_path / "x.png"
    argv = [str(tmp_path / a) if a == "DIR" else a for a in argv]
    code = cli.main(["render", CORNELL, "-o", str(out), "--spp", "1", *argv])
    err = capsys.readouterr().err.strip()
    assert code == 2 and not out.exists() and len(err.splitlines()) == 1 and message in err, err


# ------------------------------------------------------------------------------------------------- animations

ANIMATED = {
    "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "fov": 40},
    "render": {"method": "raycast", "width": 32, "height": 24},
    "lights": [{"type": "point", "name": "key", "position": [2, 3, 4], "intensity": 1}],
    "objects": [{"type": "sphere", "name": "ball", "radius": 1, "material": {"kd": [0.8, 0.2, 0.1], "ks": 0.3}},
                {"type": "plane", "point": [0, -1, 0], "material": {"kd": 0.5}}],
    "animation": {"fps": 12, "frames": 5, "tracks": [
        {"target": "camera.position", "keys": [{"frame": 0, "value": [0, 1, 5]}, {"frame": 4, "value": [4, 2, 2]}]},
        {"target": "objects[ball].transform.translate",
         "keys": [{"frame": 0, "value": [0, 0, 0]}, {"frame": 4, "value": [0.5, 0.3, 0]}]}]},
}


@pytest.mark.slow
def test_frames_on_the_cluster_are_the_local_frames_in_frame_order(client):
    local = list(lumos.render_frames(ANIMATED))
    remote = list(lumos.render_frames(ANIMATED, client=client))
    assert [img.stats["frame"] for img in remote] == [0, 1, 2, 3, 4]
    for a, b in zip(local, remote):
        assert_same(a, b)
    assert not np.array_equal(remote[0].array, remote[4].array)


@pytest.mark.slow
def test_a_camera_only_radiosity_animation_on_the_cluster_is_solved_once_here(client):
    import yaml

    with open(CORNELL) as f:
        data = yaml.safe_load(f)
    data["render"] = {"method": "radiosity", "width": 32, "height": 24, "radiosity": {"patch_size": 0.5}}
    data["animation"] = {"fps": 24, "frames": 3, "tracks": [
        {"target": "camera.position", "keys": [{"frame": 0, "value": [0, 0, 3.9]}, {"frame": 2, "value": [0.4, 0.2, 3.5]}]}]}
    local = list(lumos.render_frames(data))
    remote = list(lumos.render_frames(data, client=client))
    assert [img.stats["radiosity_solves"] for img in remote] == [1, 0, 0]
    for a, b in zip(local, remote):
        assert_same(a, b)


def test_frames_resume_from_their_checkpoint(tmp_path):
    folder = tmp_path / "frames"
    first = list(lumos.render_frames(ANIMATED, frames=range(0, 3), checkpoint=str(folder)))
    assert sorted(p.name for p in folder.iterdir()) == ["frame-000000.npz", "frame-000001.npz", "frame-000002.npz"]
    with pytest.raises(LumosError, match="--resume"):
        lumos.render_frames(ANIMATED, checkpoint=str(folder))
    every = list(lumos.render_frames(ANIMATED, checkpoint=str(folder), resume=True))
    assert [bool(img.stats.get("resumed")) for img in every] == [True, True, True, False, False]
    for a, b in zip(first, every):
        assert_same(a, b)
    assert_same(every[4], lumos.animate.render_frame(ANIMATED, 4))
