"""The Python surface of the renderer: fgf.render, fgf.write_exr/write_png,
errors, progress, determinism across thread counts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import fgf

REPO = Path(__file__).resolve().parents[1]
REFERENCE = Path(__file__).resolve().parents[1] / "scenes" / "reference"
SCENE = REFERENCE / "cube-heterogeneous.xml"
SMALL = {"res": 16}


def test_render_returns_hw3_float32():
    img = fgf.render(SCENE, spp=2, seed=0, defines=SMALL, progress=False)
    assert img.shape == (16, 16, 3) and img.dtype == np.float32
    assert np.isfinite(img).all() and img.max() > 0


def test_defines_accept_dict_or_list_and_set_resolution():
    a = fgf.render(SCENE, spp=1, defines={"res": 8}, progress=False)
    b = fgf.render(SCENE, spp=1, defines=["res=8"], progress=False)
    assert a.shape == (8, 8, 3)
    np.testing.assert_array_equal(a, b)


def test_one_and_two_threads_identical():
    a = fgf.render(SCENE, spp=4, seed=3, threads=1, defines=SMALL, progress=False)
    b = fgf.render(SCENE, spp=4, seed=3, threads=2, defines=SMALL, progress=False)
    np.testing.assert_array_equal(a, b)


def test_seed_changes_the_noise():
    a = fgf.render(SCENE, spp=2, seed=1, defines=SMALL, progress=False)
    b = fgf.render(SCENE, spp=2, seed=2, defines=SMALL, progress=False)
    assert not np.array_equal(a, b)


def test_variance_is_returned_and_shrinks_with_spp():
    img, var = fgf.render(SCENE, spp=4, defines=SMALL, progress=False, return_variance=True)
    assert var.shape == img.shape and (var >= 0).all()
    _, var16 = fgf.render(SCENE, spp=16, defines=SMALL, progress=False, return_variance=True)
    # The variance of the mean scales as 1/n: 4x fewer samples, ~4x the variance.
    ratio = var.mean() / var16.mean()
    assert 2.0 < ratio < 8.0, ratio


def test_progress_callable_and_tqdm_like():
    calls = []
    fgf.render(SCENE, spp=2, defines=SMALL, progress=lambda done, total: calls.append((done, total)))
    assert calls and calls[-1] == (16 * 16 * 2, 16 * 16 * 2)

    class Bar:
        n = 0

        def update(self, k):
            self.n += k

    bar = Bar()
    fgf.render(SCENE, spp=2, defines=SMALL, progress=bar)
    assert bar.n == 16 * 16 * 2


def test_scene_errors_raise_scene_error(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text('<scene version="3.0.0"><shape type="teapot"/></scene>')
    with pytest.raises(fgf.SceneError, match="teapot"):
        fgf.render(bad, progress=False)
    with pytest.raises(OSError):
        fgf.render(tmp_path / "missing.xml", progress=False)


def test_bad_options_raise_parameter_error():
    with pytest.raises(fgf.ParameterError):
        fgf.render(SCENE, spp=0, progress=False)
    with pytest.raises(fgf.ParameterError):
        fgf.render(SCENE, threads=0, progress=False)


def test_write_exr_and_png(tmp_path):
    img = fgf.render(SCENE, spp=1, defines=SMALL, progress=False)
    fgf.write_exr(tmp_path / "a.exr", img)
    fgf.write_png(tmp_path / "a.png", img)
    assert (tmp_path / "a.exr").read_bytes()[:4] == b"\x76\x2f\x31\x01"
    assert (tmp_path / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    back = np.array(mi.Bitmap(str(tmp_path / "a.exr")))
    np.testing.assert_array_equal(back[..., :3], img)
    with pytest.raises(fgf.ParameterError):
        fgf.write_exr(tmp_path / "b.exr", np.zeros((4, 4)))


def test_default_scene_loads_and_renders_small():
    img = fgf.render(REPO / "scenes" / "default.xml", spp=1, defines={"width": 16, "height": 12}, progress=False)
    assert img.shape == (12, 16, 3) and img.max() > 0
