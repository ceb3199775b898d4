"""`fgf render` from the command line: outputs, errors, Ctrl-C."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
REFERENCE = Path(__file__).resolve().parents[1] / "scenes" / "reference"


def fgf_cli(*args, **kw):
    return subprocess.run([sys.executable, "-m", "fgf", *map(str, args)], capture_output=True, text=True, **kw)


def test_render_writes_exr_png_and_variance(tmp_path):
    out = tmp_path / "img.exr"
    r = fgf_cli(
        "render", REFERENCE / "cube-homogeneous.xml", "-o", out, "--spp", 2, "-D", "res=16", "--variance", tmp_path / "var.exr"
    )
    assert r.returncode == 0, r.stderr
    assert out.exists() and (tmp_path / "img.png").exists() and (tmp_path / "var.exr").exists()
    assert "16x16, 2 spp" in r.stderr


def test_render_quiet_and_png_path(tmp_path):
    r = fgf_cli(
        "render", REFERENCE / "cube-homogeneous.xml", "-o", tmp_path / "a.exr", "--png", tmp_path / "p.png",
        "--spp", 1, "-D", "res=8", "--quiet",
    )
    assert r.returncode == 0 and r.stderr == ""
    assert (tmp_path / "p.png").exists()


def test_bad_scene_exits_2_with_message_and_no_traceback(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text('<scene version="3.0.0">\n  <bsdf type="principledthin"/>\n</scene>\n')
    r = fgf_cli("render", bad, "-o", tmp_path / "o.exr")
    assert r.returncode == 2
    assert "principledthin" in r.stderr and "bad.xml" in r.stderr
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "o.exr").exists()
    r = fgf_cli("render", tmp_path / "missing.xml", "-o", tmp_path / "o.exr")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    r = fgf_cli("render", REFERENCE / "cube-homogeneous.xml", "-o", tmp_path / "o.exr", "-D", "novalue")
    assert r.returncode == 2 and "name=value" in r.stderr


def test_ctrl_c_writes_partial_image(tmp_path):
    out = tmp_path / "partial.exr"
    p = subprocess.Popen(
        [sys.executable, "-m", "fgf", "render", str(REFERENCE / "cube-heterogeneous.xml"), "-o", str(out),
         "--spp", "100000", "-D", "res=32", "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    # Let it finish at least one pass (a pass is 64 spp at 32x32: well under
    # a second), then interrupt it.
    time.sleep(4.0)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert "interrupted" in err and "samples per pixel" in err
    spp_done = int(err.split("image of ")[1].split(" samples")[0])
    assert 0 < spp_done < 100000
    assert out.exists() and out.with_suffix(".png").exists()
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    img = np.array(mi.Bitmap(str(out)))
    assert img.shape[:2] == (32, 32) and np.isfinite(img).all() and img.max() > 0
