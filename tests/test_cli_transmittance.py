"""`fgf transmittance` as a user runs it: the real command in a subprocess."""

from __future__ import annotations

import csv
import subprocess
import sys

import numpy as np
import pytest

import fgf

BASE = ["--sigma-t", "4", "--hurst", "-0.1", "--sw", "4"]


def run(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "fgf", "transmittance", *args],
        capture_output=True, text=True, cwd=cwd, timeout=120,
    )


def test_help():
    r = run("--help")
    assert r.returncode == 0
    for flag in ("--sigma-t", "--hurst", "--sw", "--length", "--t-max", "-o"):
        assert flag in r.stdout


def test_prints_table_matching_the_api():
    r = run(*BASE, "--t-max", "2", "--rows", "5")
    assert r.returncode == 0, r.stderr
    lines = [ln for ln in r.stdout.splitlines() if ln and not ln.startswith("#")]
    assert lines[0].split() == ["t", "Tr", "Tr_exp", "pdf", "alpha"]
    rows = np.array([[float(v) for v in ln.split()] for ln in lines[1:]])
    assert rows.shape == (5, 5)
    m = fgf.Fgf(4.0, hurst=-0.1, sw=4.0)
    np.testing.assert_allclose(rows[:, 0], np.linspace(0, 2, 5))
    np.testing.assert_allclose(rows[:, 1], m.tr(rows[:, 0]), rtol=1e-5)
    np.testing.assert_allclose(rows[:, 2], np.exp(-4.0 * rows[:, 0]), rtol=1e-5)
    assert "pink noise" in r.stdout


@pytest.mark.parametrize("ext", [".png", ".pdf", ".svg"])
def test_writes_plot(tmp_path, ext):
    out = tmp_path / f"tr{ext}"
    r = run(*BASE, "-o", str(out), "-q")
    assert r.returncode == 0, r.stderr
    assert r.stdout == "" and r.stderr == ""
    assert out.stat().st_size > 1000
    head = out.read_bytes()[:8]
    assert {".png": head.startswith(b"\x89PNG"), ".pdf": head.startswith(b"%PDF"),
            ".svg": b"<svg" in out.read_bytes()[:2000]}[ext]
    assert [p.name for p in tmp_path.iterdir()] == [out.name]  # no temp files left


def test_writes_csv_for_kfbm(tmp_path):
    out = tmp_path / "tr.csv"
    r = run("--sigma-t", "4", "--hurst", "1.2", "--sw", "34", "--length", "1",
            "--points", "50", "-o", str(out))
    assert r.returncode == 0, r.stderr
    with open(out) as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 50
    t = np.array([float(r["t"]) for r in rows])
    tr = np.array([float(r["tr"]) for r in rows])
    m = fgf.Fgf(4.0, hurst=1.2, sw=34.0, length=1.0)
    np.testing.assert_array_equal(tr, m.tr(t))
    assert "wrote" in r.stderr


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--sigma-t", "4", "--hurst", "0", "--sw", "4"], "hurst"),
        (["--sigma-t", "4", "--hurst", "2", "--sw", "4", "--length", "1"], "hurst"),
        (["--sigma-t", "4", "--hurst", "-0.7", "--sw", "4"], "hurst"),
        (["--sigma-t", "-1", "--hurst", "-0.1", "--sw", "4"], "sigma_t"),
        (["--sigma-t", "nan", "--hurst", "-0.1", "--sw", "4"], "sigma_t"),
        (["--sigma-t", "4", "--hurst", "-0.1", "--sw", "0"], "sw"),
        (["--sigma-t", "4", "--hurst", "1.2", "--sw", "4"], "length"),
        (["--sigma-t", "4", "--hurst", "1.2", "--sw", "4", "--length", "-2"], "length"),
        (["--sigma-t", "4", "--hurst", "-0.1", "--sw", "4", "--length", "1"], "length"),
        ([*BASE, "--t-max", "0"], "--t-max"),
        ([*BASE, "--t-max", "inf"], "--t-max"),
        ([*BASE, "--rows", "1"], "--rows"),
        ([*BASE, "-o", "out.txt"], "extension"),
        ([*BASE, "-o", "/nonexistent-dir/x.png"], "does not exist"),
    ],
)
def test_bad_input_exits_2_with_one_line(args, needle, tmp_path):
    r = run(*args, cwd=tmp_path)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert r.stderr.startswith("fgf transmittance: error:")
    assert needle in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert r.stdout == ""
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args", [[], ["--sigma-t", "x", "--hurst", "-0.1", "--sw", "4"]])
def test_argparse_errors_exit_2(args):
    r = run(*args)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr and "usage:" in r.stderr
