"""Renders and ensembles in chunks, on a Dask ``LocalCluster`` of 2 worker
processes and on one machine with checkpoints (``fgf.cluster``,
``docs/cluster.md``).

Everything here is exact: fixed-point pixel sums (``docs/theory.md`` §7.17)
make a chunked render bit-identical to the single-process render for any
chunk size and worker count, so the checks are ``array_equal``, not
tolerances.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import fgf
from fgf import cluster

distributed = pytest.importorskip("distributed", reason="fgf[cluster] (dask[distributed]) is installed by the test command")

ROOT = Path(__file__).resolve().parents[1]
# A heterogeneous medium read from a .vol next to the scene: shipping the
# scene's files to the workers is exercised too.
SCENE = ROOT / "scenes" / "reference" / "cube-heterogeneous.xml"
SMALL = [("res", "12")]
PINK = ROOT / "scenes" / "fgf-cube-pink.xml"
KFBM = ROOT / "scenes" / "fgf-cube-2fbm.xml"


@pytest.fixture(scope="module")
def client():
    with cluster.open_client("local:2") as c:
        yield c


def reference(spp: int, seed: int, variance: bool = True):
    return fgf.render(SCENE, spp=spp, seed=seed, defines=dict(SMALL), progress=False, return_variance=variance)


@pytest.mark.parametrize("chunk_spp", [1, 4])
def test_cluster_render_is_bit_identical(client, chunk_spp):
    img, var = reference(6, 5)
    run = cluster.render(
        SCENE, spp=6, seed=5, defines=SMALL, progress=False, return_variance=True, client=client, chunk_spp=chunk_spp
    )
    assert run.spp_done == 6 and not run.interrupted and run.lost is None
    assert np.array_equal(run.image, img)
    assert np.array_equal(run.variance, var)


def test_fgf_render_client_keyword(client):
    img = fgf.render(SCENE, spp=3, seed=1, defines=dict(SMALL), progress=False, client=client, chunk_spp=2)
    assert np.array_equal(img, reference(3, 1, variance=False))


def test_sample_ranges_merge_in_any_order():
    prep = fgf._core.prepare_scene(str(SCENE), SMALL)
    parts = [cluster.render_chunk(prep, a, b, seed=9, variance=True) for a, b in [(3, 5), (0, 1), (5, 7), (1, 3)]]
    total = parts[0]
    for p in parts[1:]:
        total.merge(p)
    assert total.ranges == [(0, 7)]
    img, var = total.finish(7)
    ref_img, ref_var = reference(7, 9)
    assert np.array_equal(img, ref_img) and np.array_equal(var, ref_var)
    with pytest.raises(fgf.ParameterError, match="merged twice"):
        total.merge(cluster.render_chunk(prep, 2, 3, seed=9, variance=True))


@pytest.mark.parametrize("realizations", [2, 3])
def test_cluster_ensemble_is_bit_identical(client, realizations):
    args = dict(resolution=8, spp=1, seed=4, defines={"res": 8}, progress=False, return_info=True)
    mean, se, info = fgf.ensemble(PINK, realizations, **args)
    cmean, cse, cinfo = fgf.ensemble(PINK, realizations, client=client, **args)
    assert np.array_equal(mean, cmean)
    assert np.array_equal(se, cse, equal_nan=True)
    assert cinfo["realizations_done"] == realizations
    for m, c in zip(info["media"], cinfo["media"]):
        assert m["realized_variance"] == c["realized_variance"]
        assert m["clamped_fraction"] == pytest.approx(c["clamped_fraction"], rel=1e-12, abs=1e-15)


def test_ensemble_checkpoint_resumes_with_more_realizations(tmp_path):
    args = dict(resolution=8, spp=1, seed=2, defines={"res": 8}, progress=False)
    ck = tmp_path / "ens.ckpt"
    fgf.ensemble(PINK, 2, checkpoint=ck, **args)
    mean, se = fgf.ensemble(PINK, 3, checkpoint=ck, **args)
    ref_mean, ref_se = fgf.ensemble(PINK, 3, **args)
    assert np.array_equal(mean, ref_mean) and np.array_equal(se, ref_se)
    with pytest.raises(fgf.ParameterError, match="different --resolution"):
        fgf.ensemble(PINK, 3, checkpoint=ck, **dict(args, resolution=10))


@pytest.mark.parametrize("nodes", [2, 3])
def test_cluster_truth_is_bit_identical(client, nodes, tmp_path):
    args = dict(spp=2, nodes=nodes, seed=6, defines={"res": 8}, progress=False, return_stderr=True)
    img, se = fgf.truth(KFBM, **args)
    cimg, cse = fgf.truth(KFBM, client=client, checkpoint=tmp_path / "truth.ckpt", **args)
    assert np.array_equal(img, cimg) and np.array_equal(se, cse)
    # Resumed entirely from the checkpoint: the same bits again.
    rimg, rse = fgf.truth(KFBM, checkpoint=tmp_path / "truth.ckpt", **args)
    assert np.array_equal(img, rimg) and np.array_equal(se, rse)


def test_checkpoint_interrupted_and_resumed_is_identical(tmp_path):
    ck = tmp_path / "render.ckpt"
    calls = []

    def interrupt_after_first_chunk(done, total):
        # Ctrl-C once the first chunk (2 samples of 12x12 pixels) is in.
        if done > 12 * 12 * 2 and not calls:
            calls.append(done)
            os.kill(os.getpid(), signal.SIGINT)

    run = cluster.render(
        SCENE, spp=8, seed=2, defines=SMALL, progress=interrupt_after_first_chunk, return_variance=True,
        chunk_spp=2, checkpoint=ck, threads=1,
    )
    assert calls and run.interrupted and 2 <= run.spp_done < 8 and ck.exists()
    resumed = cluster.render(
        SCENE, spp=8, seed=2, defines=SMALL, progress=False, return_variance=True, chunk_spp=3, checkpoint=ck
    )
    assert resumed.resumed_spp == run.spp_done and resumed.spp_done == 8
    img, var = reference(8, 2)
    assert np.array_equal(resumed.image, img) and np.array_equal(resumed.variance, var)


def test_checkpoint_spp_may_be_raised_on_resume(tmp_path, client):
    ck = tmp_path / "render.ckpt"
    cluster.render(SCENE, spp=4, seed=3, defines=SMALL, progress=False, chunk_spp=2, checkpoint=ck)
    run = cluster.render(SCENE, spp=9, seed=3, defines=SMALL, progress=False, chunk_spp=2, checkpoint=ck, client=client)
    assert run.resumed_spp == 4
    assert np.array_equal(run.image, reference(9, 3, variance=False))


def fgf_cli(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "fgf", *args], capture_output=True, text=True, timeout=timeout)


def test_mismatched_checkpoint_is_refused(tmp_path):
    ck = tmp_path / "render.ckpt"
    base = ["render", str(SCENE), "-D", "res=12", "--spp", "2", "--checkpoint", str(ck), "--quiet"]
    assert fgf_cli(*base, "--seed", "1", "-o", str(tmp_path / "a.exr")).returncode == 0
    before = ck.read_bytes()
    r = fgf_cli(*base, "--seed", "2", "-o", str(tmp_path / "b.exr"))
    assert r.returncode == 2 and "different --seed" in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    r = fgf_cli(*[a if a != "res=12" else "res=10" for a in base], "--seed", "1", "-o", str(tmp_path / "c.exr"))
    assert r.returncode == 2 and "different scene" in r.stderr, r.stderr
    # A lower --spp than the checkpoint holds cannot be honoured.
    r = fgf_cli(*[a if a != "2" else "1" for a in base], "--seed", "1", "-o", str(tmp_path / "d.exr"))
    assert r.returncode == 2 and "must be at least" in r.stderr, r.stderr
    assert ck.read_bytes() == before
    assert not (tmp_path / "b.exr").exists() and not (tmp_path / "c.exr").exists()


def test_unreachable_scheduler_is_one_line_within_timeout(tmp_path):
    t0 = time.monotonic()
    r = fgf_cli("render", str(SCENE), "-D", "res=8", "--spp", "1", "-o", str(tmp_path / "x.exr"),
                "--cluster", "tcp://127.0.0.1:9", timeout=60)
    assert r.returncode == 2
    assert "no Dask scheduler answered" in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert time.monotonic() - t0 < 45
    assert not (tmp_path / "x.exr").exists()


def test_bad_cluster_address_and_missing_extra(tmp_path):
    r = fgf_cli("render", str(SCENE), "--spp", "1", "-o", str(tmp_path / "x.exr"), "--cluster", "localhost")
    assert r.returncode == 2 and "expected local, local:N or tcp://host:port" in r.stderr, r.stderr
    code = (
        "import sys; sys.modules['distributed'] = None\n"
        "from fgf.cli import main\n"
        f"sys.exit(main(['render', {str(SCENE)!r}, '--spp', '1', '-o', {str(tmp_path / 'y.exr')!r}, '--cluster', 'local:1']))"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "pip install 'fgf[cluster]'" in r.stderr, r.stderr


def test_cli_cluster_render_matches_threads(tmp_path, client):
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    assert fgf_cli("render", str(SCENE), "-D", "res=12", "--spp", "4", "--seed", "7", "-o", str(a), "--quiet").returncode == 0
    r = fgf_cli("render", str(SCENE), "-D", "res=12", "--spp", "4", "--seed", "7", "-o", str(b), "--quiet",
                "--cluster", client.scheduler.address, "--chunk-spp", "3")
    assert r.returncode == 0, r.stderr
    assert a.read_bytes() == b.read_bytes()


def test_worker_killed_mid_render_gives_the_same_image(client):
    pids = client.run(os.getpid)
    victim = sorted(pids.values())[0]
    killed = []

    def kill_one_worker(done, total):
        if not killed:
            killed.append(victim)
            os.kill(victim, signal.SIGKILL)

    # Enough chunks that both workers are busy when the first one returns.
    run = cluster.render(
        SCENE, spp=24, seed=11, defines=[("res", "16")], progress=kill_one_worker, return_variance=True,
        client=client, chunk_spp=1,
    )
    assert killed and run.spp_done == 24 and run.lost is None
    img, var = fgf.render(SCENE, spp=24, seed=11, defines={"res": 16}, progress=False, return_variance=True)
    assert np.array_equal(run.image, img) and np.array_equal(run.variance, var)
    assert victim not in client.run(os.getpid).values()


def test_sample_outside_the_exact_range_is_an_error_not_a_wrong_image(tmp_path):
    # A sky of radiance 1e28: 8 samples sum past 2^95 ≈ 4e28.
    scene = tmp_path / "bright.xml"
    scene.write_text("""<scene version="3.0.0">
  <integrator type="volpath"><integer name="max_depth" value="2"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="8"/></sampler>
    <film type="hdrfilm"><integer name="width" value="2"/><integer name="height" value="2"/>
      <rfilter type="box"/></film>
  </sensor>
  <emitter type="constant"><rgb name="radiance" value="1e28"/></emitter>
</scene>
""")
    assert np.allclose(fgf.render(scene, spp=2, progress=False), 1e28, rtol=1e-6)
    r = fgf_cli("render", str(scene), "-o", str(tmp_path / "b.exr"))
    assert r.returncode == 2 and "outside the exact accumulator's range" in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "b.exr").exists()


def test_chunker_sizes_chunks_by_their_measured_time():
    from fgf.cluster._chunks import Chunker

    # 1000 pixels: before any timing, chunks are one pass of 2^18 samples.
    c = Chunker([(0, 300), (310, 320)], spp=5000, pixels=1000, seconds=2.0)
    first = c.take(slots=2)
    assert first == (300, 310)  # the gap before the checkpoint's second range, cut short
    assert c.take(slots=2) == (320, 320 + (1 << 18) // 1000)
    # 0.5 s per 100 spp: a 2-s chunk is 400 spp.
    c.observe(100, 0.5)
    a, b = c.take(slots=2)
    assert b - a == 400
    # Near the end the rest is shared among the workers (two chunks each),
    # down to a quarter of the target.
    sizes = []
    while (r := c.take(slots=2)) is not None:
        sizes.append(r[1] - r[0])
    assert sizes[:7] == [400] * 7 and sizes[7:11] == [305, 229, 171, 129]
    assert min(sizes[:-1]) == 100 and sizes[-1] <= 100 and sum(sizes) == 5000 - 982
    # An explicit chunk size wins; the ranges cover exactly what was missing.
    fixed = Chunker([(4, 6)], spp=11, pixels=10, chunk_spp=3)
    fixed.observe(3, 1.0)
    got = []
    while (r := fixed.take(slots=2)) is not None:
        got.append(r)
    assert got == [(0, 3), (3, 4), (6, 9), (9, 11)]


def test_automatic_chunk_sizes_give_the_bits_of_fine_chunks_and_of_one_render(client, monkeypatch):
    from fgf.cluster import _chunks

    # Small probes and 10-ms chunks, so that this small film is cut into
    # chunks of several sizes: probes of 2 spp, then sized by their time.
    monkeypatch.setattr(_chunks, "PROBE_SAMPLES", 2 * 12 * 12)
    monkeypatch.setattr(_chunks, "CHUNK_SECONDS", 0.01)
    taken = []
    take = _chunks.Chunker.take

    def recording(self, slots=1):
        r = take(self, slots)
        if r is not None:
            taken.append(r)
        return r

    monkeypatch.setattr(_chunks.Chunker, "take", recording)
    spp, seed = 48, 13
    auto = cluster.render(SCENE, spp=spp, seed=seed, defines=SMALL, progress=False, return_variance=True, client=client)
    sizes = [b - a for a, b in taken]
    assert sorted(taken)[0][0] == 0 and sum(sizes) == spp and len(set(sizes)) > 1, taken
    taken.clear()
    fine = cluster.render(
        SCENE, spp=spp, seed=seed, defines=SMALL, progress=False, return_variance=True, client=client, chunk_spp=1
    )
    assert len(taken) == spp
    img, var = reference(spp, seed)
    for run in (auto, fine):
        assert run.spp_done == spp and not run.interrupted
        assert np.array_equal(run.image, img) and np.array_equal(run.variance, var)
    # One machine, no cluster: the same chunking code, the same bits.
    local = cluster.render(SCENE, spp=spp, seed=seed, defines=SMALL, progress=False, return_variance=True, threads=2)
    assert np.array_equal(local.image, img) and np.array_equal(local.variance, var)


def test_checkpoint_with_holes_resumes_with_automatic_chunks(tmp_path, client, monkeypatch):
    # Chunks of different sizes finishing out of order leave a checkpoint
    # with holes: here samples [0, 2) and [5, 9) of 20. Automatic chunks
    # fill exactly the rest, and the image has the bits of one render.
    from fgf.cluster import _chunks, _film
    from fgf.cluster._ship import ScenePayload

    monkeypatch.setattr(_chunks, "PROBE_SAMPLES", 12 * 12)
    monkeypatch.setattr(_chunks, "CHUNK_SECONDS", 0.01)
    prep = fgf._core.prepare_scene(str(SCENE), SMALL)
    held = cluster.render_chunk(prep, 5, 9, seed=8, variance=True)
    held.merge(cluster.render_chunk(prep, 0, 2, seed=8, variance=True))
    assert held.ranges == [(0, 2), (5, 9)]
    meta = {"kind": "render", "scene_digest": ScenePayload.from_file(SCENE, SMALL).digest, "seed": 8,
            "variance": True, "width": 12, "height": 12}
    ck = tmp_path / "holes.ckpt"
    _film.save(ck, meta, {"sum": held.sum, "sum_sq": held.sum_sq, "ranges": np.array(held.ranges).reshape(-1, 2)})
    run = cluster.render(SCENE, spp=20, seed=8, defines=SMALL, progress=False, return_variance=True, client=client,
                         checkpoint=ck)
    assert run.resumed_spp == 6 and run.spp_done == 20
    img, var = reference(20, 8)
    assert np.array_equal(run.image, img) and np.array_equal(run.variance, var)
    _, arrays = _film.load(ck)
    assert arrays["ranges"].tolist() == [[0, 20]]


def test_local_cluster_stops_its_workers_without_leftovers():
    with cluster.open_client("local:1") as c:
        (pid,) = c.run(os.getpid).values()
        (folder,) = c.run(lambda dask_worker: dask_worker.local_directory).values()
    # The worker process is gone (killed, not restarted) and leaves no lock.
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    else:
        pytest.fail(f"worker process {pid} still running")
    assert not os.path.exists(folder) and not os.path.exists(folder + ".dirlock")


def test_scheduler_lost_mid_render_writes_what_finished(tmp_path):
    # A scheduler and a worker of our own; the scheduler is killed once the
    # checkpoint shows a finished chunk: one line, exit code 2, the image of
    # the chunks finished, and a checkpoint that resumes to the full image.
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    py = [sys.executable, "-m"]
    # Their scratch folders (which a killed process leaves) go to tmp_path.
    env = dict(os.environ, DASK_TEMPORARY_DIRECTORY=str(tmp_path))
    procs = [subprocess.Popen(py + ["distributed.cli.dask_scheduler", "--port", str(port), "--no-dashboard"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)]
    ck, out = tmp_path / "lost.ckpt", tmp_path / "lost.exr"
    try:
        procs.append(subprocess.Popen(py + ["distributed.cli.dask_worker", address, "--nworkers", "1", "--nthreads",
                                            "1", "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      env=env))
        render = subprocess.Popen(
            [sys.executable, "-m", "fgf", "render", str(SCENE), "-D", "res=16", "--spp", "200000", "--seed", "3",
             "--cluster", address, "--checkpoint", str(ck), "-o", str(out), "--quiet"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )
        procs.append(render)
        deadline = time.monotonic() + 90
        while not ck.exists() and render.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
        assert ck.exists(), "no chunk finished within 90 s"
        procs[0].kill()
        _, err = render.communicate(timeout=90)
        assert render.returncode == 2, err
        assert "lost the Dask scheduler" in err and len(err.strip().splitlines()) == 1, err
        assert out.exists()
        _, arrays = cluster._film.load(ck)
        done = int(sum(b - a for a, b in arrays["ranges"].reshape(-1, 2)))
        assert 0 < done < 200000
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait(timeout=30)
    # Resumed here (no cluster) to a few more samples: the bits of one render.
    run = cluster.render(SCENE, spp=done + 3, seed=3, defines=[("res", "16")], progress=False, checkpoint=ck)
    assert run.resumed_spp == done and run.spp_done == done + 3
    img = fgf.render(SCENE, spp=done + 3, seed=3, defines={"res": 16}, progress=False)
    assert np.array_equal(run.image, img)
