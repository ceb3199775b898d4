"""The calibrated ensemble (gamma copula, ``docs/theory.md`` §1.8).

Fast: the macro density multiplies the whole extinction (fluctuations
included), for both marginals; the report carries the grid's exact
line-average variance next to the model's; bad options are one clear line.
The spectral sum itself is checked against Monte Carlo in the Rust tests of
``fgf_field::line_variance`` and ``fgf_field::copula``.
Slow: model against ensemble on the pink cube where the model and the
exponential differ most (docs/validation.md, ensemble section).
"""

from __future__ import annotations

import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import fgf

ROOT = Path(__file__).resolve().parents[1]
PINK = ROOT / "scenes" / "fgf-cube-pink.xml"


def _constant_density_scene(tmp_path: Path, rho: float) -> Path:
    vol = tmp_path / "rho.vol"
    n = 2
    head = b"VOL" + bytes([3]) + struct.pack("<iiiii", 1, n, n, n, 1)
    head += struct.pack("<6f", -0.5, 0.25, -0.5, 0.5, 1.25, 0.5)
    vol.write_bytes(head + np.full(n**3, rho, "<f4").tobytes())
    text = PINK.read_text()
    tag = '<phase type="isotropic"/>'
    assert tag in text
    text = text.replace(
        tag,
        tag + f'<volume type="gridvolume" name="density"><string name="filename" value="{vol}"/>'
        '<boolean name="use_grid_bbox" value="true"/></volume>',
        1,
    )
    path = tmp_path / "pink-density.xml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("marginal", ["gamma", "gaussian"])
def test_density_multiplies_the_whole_field(tmp_path, marginal):
    """With ρ = 0.5 everywhere and the same seed, every voxel is half of the
    ρ = 1 voxel: the mean extinction halves exactly, the fluctuation
    measured without ρ is unchanged and the clamped fraction too. An
    additive ρσ_m + σ_u would clamp more and not halve the mean."""
    kw = dict(realizations=2, resolution=12, spp=1, seed=3, defines={"res": 8}, progress=False, marginal=marginal, return_info=True)
    _, _, full = fgf.ensemble(PINK, **kw)
    _, _, half = fgf.ensemble(_constant_density_scene(tmp_path, 0.5), **kw)
    f, h = full["media"][0], half["media"][0]
    assert h["model_mean_sigma_t"] == pytest.approx(0.5 * f["model_mean_sigma_t"], rel=1e-6)
    assert h["mean_sigma_t"] == pytest.approx(0.5 * f["mean_sigma_t"], rel=1e-5)
    assert h["realized_variance"] == f["realized_variance"]
    assert h["clamped_fraction"] == f["clamped_fraction"]
    assert f["marginal"] == marginal
    if marginal == "gamma":
        assert f["clamped_fraction"] == 0.0


def test_report_has_exact_variances_and_calibration():
    _, _, info = fgf.ensemble(PINK, realizations=1, resolution=16, spp=1, defines={"res": 8, "sw": "16"}, progress=False, return_info=True)
    (m,) = info["media"]
    assert m["marginal"] == "gamma" and m["padded_shape"] == [64, 64, 64]
    assert len(m["lengths"]) == len(m["model_variances"]) == len(m["grid_variances"]) >= 5
    assert m["lengths"][0] == pytest.approx(1 / 16) and m["lengths"][-1] == pytest.approx(1.0)
    ratio = np.array(m["grid_variances"]) / np.array(m["model_variances"])
    # The calibration's residual on this grid (docs/validation.md reports it
    # at the resolution of the comparison): within a factor 1.3 everywhere.
    assert np.all((ratio > 1 / 1.3) & (ratio < 1.3)), ratio
    assert 0 < m["alpha_voxel"] < 10 and -1.5 < m["hurst_field"] < 1


def test_cli_rejects_bad_padding_and_marginal(tmp_path):
    for args, word in ((["--padding", "0.5"], "padding"), (["--marginal", "lognormal"], "marginal")):
        r = subprocess.run(
            [sys.executable, "-m", "fgf", "ensemble", str(PINK), "-n", "2", "-o", str(tmp_path / "m.exr"), "-D", "res=8", *args],
            capture_output=True, text=True, timeout=300,
        )
        assert r.returncode == 2, r.stderr
        assert word in r.stderr and "Traceback" not in r.stderr
    with pytest.raises(fgf.ParameterError, match="marginal"):
        fgf.ensemble(PINK, realizations=1, resolution=8, spp=1, defines={"res": 8}, progress=False, marginal="x")  # type: ignore[arg-type]


#: docs/validation.md (ensemble section): model − ensemble on the pink cube
#: (σ_m = 4, S_w = 16, H = -0.1; 64² pixels, 64³ grids padded to 256³, 128
#: realizations at 16 spp, seed 11), region means of the RGB mean, with the
#: standard error of the difference.
DOCUMENTED_MODEL_MINUS_ENSEMBLE = {"brighter": (0.0306, 0.0046), "darker": (0.0393, 0.0068), "image": (0.0085, 0.0006)}


@pytest.mark.slow
def test_pink_cube_ensemble_can_tell_and_replicates_the_documented_discrepancy():
    """An independent replicate (seed 23, 64 realizations) of the documented
    study. Every bound is 4.5 standard errors (about 12 comparisons: family
    error rate < 1e-4):

    * the ensemble's standard error is below a fifth of |model − exponential|
      in the regions where they differ, and the ensemble is not the
      exponential (|exponential − ensemble| > 4.5 SE): it can tell;
    * model − ensemble agrees with the documented value within 4.5 SE of the
      difference of the two estimates (the discrepancy is real and stable);
    * the ensemble lies between the reciprocal and the energy-conserving
      kernels' renders (within 4.5 SE), as the constant-α truth does;
    * the calibration's variance residual stays within a factor 1.2.
    """
    from fgf.figures.ensemble import pink_ensemble_study

    r = pink_ensemble_study(PINK, res=64, realizations=64, resolution=64, spp=16, model_spp=256, seed=23)
    ratio = np.array(r["medium"]["variance_ratio"])
    assert np.all(np.abs(np.log(ratio)) < np.log(1.2)), ratio
    for name, (doc, doc_se) in DOCUMENTED_MODEL_MINUS_ENSEMBLE.items():
        st = r["regions"][name]
        se = st["model_minus_ensemble_se"]
        print(name, {k: round(v, 4) for k, v in st.items()})
        if name != "image":
            assert st["ensemble_se"] < abs(st["model_minus_exponential"]) / 5, st
            assert abs(st["exponential_minus_ensemble"]) > 4.5 * np.hypot(st["ensemble_se"], st["exponential_se"]), st
        assert abs(st["model_minus_ensemble"] - doc) <= 4.5 * np.hypot(se, doc_se), (name, st["model_minus_ensemble"], doc)
        lo, hi = sorted((st["model_reciprocal"], st["model"]))
        assert lo - 4.5 * st["ensemble_se"] <= st["ensemble"] <= hi + 4.5 * st["ensemble_se"], (name, lo, st["ensemble"], hi)
