"""``fgf ensemble`` / ``fgf.ensemble``: explicit-realization ground truth for
``fgf`` media.

Fast tests: the outputs exist and have the documented shapes; the result is
identical for any thread count; the report is printed; bad input is one
clear error line. The slow test compares the model with the ensemble in the
low-variance regime where the gamma closure is accurate (``docs/theory.md`` §3).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import fgf

ROOT = Path(__file__).resolve().parents[1]
PINK = ROOT / "scenes" / "fgf-cube-pink.xml"
KFBM = ROOT / "scenes" / "fgf-cube-2fbm.xml"


def fgf_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "fgf", *args], capture_output=True, text=True, timeout=600)


def test_cli_writes_mean_stderr_and_report(tmp_path):
    out, se = tmp_path / "mean.exr", tmp_path / "se.exr"
    r = fgf_cli(
        "ensemble", str(PINK), "--realizations", "3", "--resolution", "16", "--spp", "2",
        "-D", "res=16", "-o", str(out), "--stderr", str(se),
    )
    assert r.returncode == 0, r.stderr
    assert out.exists() and se.exists() and out.with_suffix(".png").exists()
    assert "grid 16x16x16" in r.stderr and "clamped voxels" in r.stderr and "realised" in r.stderr, r.stderr


def test_python_api_shapes_info_and_thread_determinism():
    kw = dict(realizations=2, resolution=12, spp=2, seed=5, defines={"res": 12}, progress=False)
    m1, se1, info = fgf.ensemble(PINK, threads=1, return_info=True, **kw)
    m2, se2 = fgf.ensemble(PINK, threads=2, **kw)
    assert m1.shape == se1.shape == (12, 12, 3) and m1.dtype == np.float32
    np.testing.assert_array_equal(m1, m2)
    np.testing.assert_array_equal(se1, se2)
    assert info["realizations_done"] == 2
    (med,) = info["media"]
    assert med["shape"] == [12, 12, 12]
    assert 0.0 <= med["clamped_fraction"] <= 1.0
    assert med["realized_variance"] > 0 and med["continuum_variance"] > 0
    # A different seed gives a different ensemble.
    m3, _ = fgf.ensemble(PINK, **{**kw, "seed": 6})
    assert not np.array_equal(m1, m3)


def test_one_realization_has_nan_stderr():
    m, se = fgf.ensemble(PINK, realizations=1, resolution=8, spp=1, defines={"res": 8}, progress=False)
    assert np.isfinite(m).all() and np.isnan(se).all()


@pytest.mark.parametrize(
    "args, words",
    [
        (["--realizations", "0"], ["realizations"]),
        (["--realizations", "2", "--resolution", "1"], ["resolution"]),
        (["--realizations", "2", "-D", "hurst=-0.5"], ["hurst", "white"]),
    ],
    ids=["no realizations", "resolution 1", "white noise"],
)
def test_cli_errors_are_one_line(tmp_path, args, words):
    out = tmp_path / "m.exr"
    r = fgf_cli("ensemble", str(PINK), "-o", str(out), "--spp", "1", "-D", "res=8", "--quiet", *args)
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr and r.stderr.strip().count("\n") == 0, r.stderr
    for w in words:
        assert w in r.stderr, (w, r.stderr)
    assert not out.exists()


def test_nonexponential_media_are_refused(tmp_path):
    scene = PINK.read_text().replace(
        '<float name="hurst" value="$hurst"/>\n            <float name="sw" value="$sw"/>',
        '<string name="transmittance" value="davis"/><float name="alpha" value="2"/>',
    ).replace('type="fgf"', 'type="nonexponential"')
    path = tmp_path / "davis.xml"
    path.write_text(scene)
    with pytest.raises(fgf.SceneError, match="nonexponential"):
        fgf.ensemble(path, realizations=2, resolution=8, spp=1, defines={"res": 8}, progress=False)


@pytest.mark.slow
@pytest.mark.parametrize("scene, sw", [(PINK, 0.25), (KFBM, 2.0)], ids=["pink", "2-fBm"])
def test_model_matches_the_ensemble_at_low_variance(scene, sw):
    """At low variance (clamping negligible, α large) the gamma closure and
    the realizations agree: the image means of the model render and of the
    ensemble agree within z = 4.5 standard errors (the ensemble's SE of the
    image mean, from the per-realization image means, plus the model's),
    2 comparisons, family error rate < 1.4e-5."""
    d = {"res": 32, "sw": sw}
    m, se, info = fgf.ensemble(scene, realizations=32, spp=32, resolution=48, defines=d, seed=1, progress=False, return_info=True)
    assert info["media"][0]["clamped_fraction"] < 1e-3
    model, var = fgf.render(scene, spp=1024, seed=2, defines=d, progress=False, return_variance=True)
    # SE of the image mean: the per-pixel SEs are correlated across pixels
    # (a realization brightens many pixels at once), so sum them (an upper
    # bound) rather than adding variances.
    se_ens = se.mean()
    se_model = np.sqrt(var).mean()
    diff = abs(model.mean() - m.mean())
    print(f"model {model.mean():.5f} ensemble {m.mean():.5f} ± {se_ens:.5f} (model ± {se_model:.5f})")
    assert diff <= 4.5 * (se_ens + se_model)
