"""The ``fgf`` and ``nonexponential`` media end to end through ``fgf render``:
scenes render, and invalid parameters give one clear error line
(exit code 2, no traceback, no output file) that names the parameter and
its valid range. The physics of the media is tested in Rust
(``crates/fgf-render/tests/nonexp_*.rs``).
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
    return subprocess.run([sys.executable, "-m", "fgf", *args], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("scene", [PINK, KFBM])
@pytest.mark.parametrize("kernel", ["energy_conserving", "reciprocal"])
def test_fgf_scene_renders(tmp_path, scene, kernel):
    out = tmp_path / "img.exr"
    r = fgf_cli("render", str(scene), "-o", str(out), "--spp", "4", "-D", "res=24", "-D", f"kernel={kernel}", "--quiet")
    assert r.returncode == 0, r.stderr
    assert out.exists() and out.with_suffix(".png").exists()
    img = fgf.render(scene, spp=4, defines={"res": 24, "kernel": kernel}, progress=False)
    assert img.shape == (24, 24, 3) and np.isfinite(img).all() and img.mean() > 1e-3


@pytest.mark.parametrize(
    "scene, defines, words",
    [
        (PINK, ["hurst=0"], ["hurst", "0"]),
        (KFBM, ["hurst=1"], ["hurst", "1"]),
        (PINK, ["hurst=-0.7"], ["hurst", "-0.7"]),
        (PINK, ["sw=0"], ["sw"]),
        (PINK, ["sw=-2"], ["sw"]),
        (PINK, ["kernel=bogus"], ["kernel", "energy_conserving", "reciprocal"]),
        (KFBM, ["hurst=-0.1"], ["length"]),
        (KFBM, ["length=0"], ["length"]),
    ],
    ids=["H=0", "integer H", "H<-0.5", "sw=0", "sw<0", "unknown kernel", "length on pink", "length=0"],
)
def test_invalid_parameters_give_clear_errors(tmp_path, scene, defines, words):
    out = tmp_path / "img.exr"
    args = ["render", str(scene), "-o", str(out), "--spp", "1", "-D", "res=8", "--quiet"]
    for d in defines:
        args += ["-D", d]
    r = fgf_cli(*args)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert "Traceback" not in r.stderr and "panicked" not in r.stderr
    line = r.stderr.strip()
    assert line.count("\n") == 0, line
    assert line.startswith("fgf render: error:"), line
    assert "fgf-cube" in line, line  # names the file
    for w in words:
        assert w in line, (w, line)
    assert not out.exists()


def test_invalid_nonexponential_parameters(tmp_path):
    scene = PINK.read_text().replace(
        '<float name="hurst" value="$hurst"/>\n            <float name="sw" value="$sw"/>',
        '<string name="transmittance" value="davis_weinstein"/><float name="h" value="1.5"/><float name="c" value="1"/>',
    ).replace('type="fgf"', 'type="nonexponential"')
    path = tmp_path / "dw.xml"
    path.write_text(scene)
    r = fgf_cli("render", str(path), "-o", str(tmp_path / "x.exr"), "--spp", "1", "-D", "res=8", "--quiet")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "h" in r.stderr and "0.5" in r.stderr and "1" in r.stderr, r.stderr
