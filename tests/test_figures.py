"""`fgf figures --quick`: every file is made, every number is finite, and the
numbers meet the bounds the validation report states (docs/validation.md).

The quick run happens once (module fixture, through the real CLI in a
subprocess) and takes a few minutes on two cores. A figure group that could
not run (part of the fgf API missing from the build) fails its tests with
the reason — never a silent skip.

Statistical bounds (fixed seeds, so each outcome is deterministic; the
family error rates below are what a fresh seed would risk):

* variance verification: every Monte Carlo estimate of var[σ̄_t] within
  z = 4 standard errors of the closed form. About 60 estimates: by
  Bonferroni the family error rate is ≤ 60 · 6.3e-5 ≈ 0.4 %.
* quadrature against the closed form: relative error ≤ 1e-6 (QUADPACK at
  epsrel 1e-10…1e-12; the closed forms match the double integral to 8+
  digits, docs/theory.md §2).
* transmittance, white and pink noise: the ensemble average of e^(−τ) over
  exact realizations within z = 4.5 SE of the exact Gaussian average
  exp(−σ_m t + t² var/2) at every grid point with Tr ≥ 0.02 (≈ 3 × 200
  points; Bonferroni ≤ 600 · 6.8e-6 ≈ 0.4 %), and the gamma model within
  the stated 5 % relative error of the realizations in the low-variance
  regime (α = 20 at t = 1).
* renders: every image finite and not black (mean > 1e-4).
* equal models (Bitterli's Davis / Davis–Weinstein vs the FGF media they
  equal, same seed): mean relative difference ≤ 1e-3.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import pytest

GROUP_FILES = {
    "family": ["family_covariance.png", "family_2d.png"],
    "variance": ["variance.png"],
    "transmittance": ["transmittance_models.png", "transmittance_vs_realizations.png"],
    "renders": ["renders.png"],
    "comparisons": ["comparison_kernels.png", "comparison_bitterli.png"],
    "truth": ["comparison_truth.png"],
    "ensemble": ["comparison_ensemble.png"],
}

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("figures")
    # An unrelated file in the output directory must survive the run.
    (out / "keep.txt").write_text("mine")
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.run(
        [sys.executable, "-m", "fgf", "figures", "--out", str(out), "--quick", "--quiet"],
        capture_output=True,
        text=True,
        env=env,
        timeout=900,
    )
    assert "Traceback" not in proc.stderr, proc.stderr
    results = json.loads((out / "results.json").read_text(), parse_constant=_reject_constant)
    return out, proc, results


def _reject_constant(name):
    raise AssertionError(f"results.json contains {name}")


def _group(results, name):
    g = results["groups"].get(name)
    assert g is not None, f"group '{name}' missing from results.json"
    assert g["status"] == "ok", f"figure group '{name}' was not made: {g['reason']}"
    return g["results"]


def test_exit_status_and_unrelated_files_kept(quick_run):
    out, proc, results = quick_run
    missing = {n: g["reason"] for n, g in results["groups"].items() if g["status"] != "ok"}
    assert proc.returncode == (1 if missing else 0), proc.stderr
    assert (out / "keep.txt").read_text() == "mine"
    assert not list(out.glob(".*.tmp")), "temporary files left behind"
    # Outputs get the permissions of a plain open(): 0666 minus the umask.
    mask = os.umask(0o022)
    os.umask(mask)
    for f in ("results.json", "index.html", "variance.png"):
        assert (out / f).stat().st_mode & 0o777 == 0o666 & ~mask, f


@pytest.mark.parametrize("group", list(GROUP_FILES))
def test_group_files(quick_run, group):
    out, _, results = quick_run
    _group(results, group)
    page = (out / "index.html").read_text()
    for name in GROUP_FILES[group]:
        data = (out / name).read_bytes()
        assert data[:8] == PNG_MAGIC, name
        assert f'src="{name}"' in page, f"{name} not linked from index.html"
    listed = [f["file"] for f in results["groups"][group]["figures"]]
    assert listed == GROUP_FILES[group]
    assert all(f["caption"] for f in results["groups"][group]["figures"])


def test_results_finite(quick_run):
    _, _, results = quick_run

    def walk(x, where):
        if isinstance(x, dict):
            for k, v in x.items():
                walk(v, f"{where}.{k}")
        elif isinstance(x, list):
            for i, v in enumerate(x):
                walk(v, f"{where}[{i}]")
        elif isinstance(x, float):
            assert math.isfinite(x), where

    walk(results, "results")
    assert results["quick"] is True
    for name in GROUP_FILES:
        assert results["seconds"][name] >= 0.0


def test_family_covariance_matches_realizations(quick_run):
    res = _group(quick_run[2], "family")
    for key, e in res["covariance"].items():
        # The squared Frobenius error is a sum of many terms and concentrates
        # around its expectation (computed in the group); 1.5x its root is
        # far outside its sampling spread for n = 2000 paths.
        assert e["relative_frobenius_error_vs_realizations"] <= 1.5 * e["expected_relative_frobenius_error"], key
    for key, e in res["realizations_2d"].items():
        assert e["std"] > 0, key


def test_variance_within_z_se(quick_run):
    res = _group(quick_run[2], "variance")
    z = 4.0
    n = 0
    for part in ("pink", "kfbm"):
        for key, e in res[part].items():
            for zi in e["z"]:
                n += 1
                assert abs(zi) <= z, f"{part} {key}: |z| = {abs(zi):.2f} > {z}"
            if "quad_rel_error" in e:
                assert max(e["quad_rel_error"]) <= 1e-6, f"{part} {key}: quadrature"
    assert n >= 50


def test_transmittance_model_vs_realizations(quick_run):
    res = _group(quick_run[2], "transmittance")["vs_realizations"]
    z = 4.5
    for case in ("white", "pink_low"):
        e = res[case]
        for tm, mc, se, g in zip(e["tr_model"], e["tr_mc"], e["tr_mc_se"], e["tr_gaussian"]):
            if tm >= 0.02:
                assert abs(mc - g) <= z * se + 1e-12, f"{case}: realizations vs exact Gaussian average"
    for case in ("white", "pink_low"):
        assert res[case]["max_rel_error"] <= 0.05, case


def test_renders_finite_and_not_black(quick_run):
    res = _group(quick_run[2], "renders")
    assert len(res["images"]) == 4
    for label, st in res["images"].items():
        assert st["finite"], label
        assert st["mean"] > 1e-4, label


def test_comparisons(quick_run):
    res = _group(quick_run[2], "comparisons")
    for key, e in res["kernels"].items():
        for k in ("energy_conserving", "reciprocal"):
            assert e[k]["finite"] and e[k]["mean"] > 1e-4, (key, k)
    for key in ("davis", "davis_weinstein"):
        assert res["bitterli"][key]["mean_relative_error"] <= 1e-3, key


def test_ensemble(quick_run):
    res = _group(quick_run[2], "ensemble")
    for key, e in res.items():
        assert e["model"]["finite"] and e["ensemble"]["finite"], key
        assert e["model"]["mean"] > 1e-4 and e["ensemble"]["mean"] > 1e-4, key


def test_bad_group_is_a_clean_error(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "fgf", "figures", "--out", str(tmp_path), "--only", "nope"],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert "nope" in proc.stderr


def test_gallery_is_self_contained(tmp_path):
    from fgf.figures import gallery_html

    report = {
        "quick": True,
        "seed": 1,
        "seconds": {"x": 1.0},
        "groups": {
            "x": {"status": "unavailable", "reason": "fgf.render <missing>", "title": "T", "figures": [], "results": {}},
        },
    }
    page = gallery_html(report)
    assert "&lt;missing&gt;" in page and "Not made" in page
    assert "http://" not in page and "https://" not in page


def test_missing_scene_dir_is_a_usage_error(tmp_path):
    for bad in [tmp_path / "nowhere", tmp_path / "a-file"]:
        if bad.name == "a-file":
            bad.write_text("x")
        proc = subprocess.run(
            [sys.executable, "-m", "fgf", "figures", "--out", str(tmp_path / "o"), "--quick", "--quiet",
             "--only", "renders", "--scene-dir", str(bad)],
            capture_output=True,
            text=True,
        )
        assert proc.returncode == 2, proc.stderr
        assert "Traceback" not in proc.stderr
        assert "--scene-dir" in proc.stderr and str(bad) in proc.stderr
        assert not (tmp_path / "o").exists()


def test_scene_dir_without_the_scenes_is_reported(tmp_path):
    (tmp_path / "empty").mkdir()
    proc = subprocess.run(
        [sys.executable, "-m", "fgf", "figures", "--out", str(tmp_path / "o"), "--quick", "--quiet",
         "--only", "renders", "--scene-dir", str(tmp_path / "empty")],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "group 'renders' not made" in proc.stderr and "not found" in proc.stderr
    results = json.loads((tmp_path / "o" / "results.json").read_text())
    assert results["groups"]["renders"]["status"] == "unavailable"
    assert "Not made" in (tmp_path / "o" / "index.html").read_text()
