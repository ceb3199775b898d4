"""The whole CLI under a 2 GB address-space limit (``ulimit -v 2000000``) on
hostile inputs: every run ends with exit code 0, 2 or 130 — never a signal
(SIGABRT from a failed allocation, SIGSEGV), a panic or a traceback.

Slow step only (scripts/test.sh): each case starts the CLI afresh.
"""

from __future__ import annotations

import shlex
import struct
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[1]
SCENE = REPO / "scenes" / "reference" / "cube-homogeneous.xml"
LIMIT_KB = 2_000_000


def _limited(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    cmd = " ".join(shlex.quote(a) for a in [sys.executable, "-m", "fgf", *args])
    return subprocess.run(
        ["bash", "-c", f"ulimit -v {LIMIT_KB}; exec {cmd}"], capture_output=True, text=True, cwd=cwd, timeout=600
    )


def _files(tmp: Path) -> None:
    big = "x" * (1 << 20)
    attrs = " ".join(f'a{i}="$v$v$v$v"' for i in range(6000))
    (tmp / "grow.xml").write_text(f'<scene version="3.0.0"><default name="v" value="{big}"/><bsdf type="diffuse" {attrs}/></scene>')
    (tmp / "loop.xml").write_text('<scene version="3.0.0"><include filename="loop.xml"/></scene>')
    (tmp / "dtd.xml").write_text('<!DOCTYPE scene [<!ENTITY a "aaaa">]><scene version="3.0.0">&a;</scene>')
    deep = "<shape type=\"sphere\">" * 5000 + "</shape>" * 5000
    (tmp / "deep.xml").write_text(f'<scene version="3.0.0">{deep}</scene>')
    hdr = b"VOL" + bytes([3]) + struct.pack("<5i", 1, 1 << 20, 1 << 20, 1 << 20, 1) + struct.pack("<6f", 0, 0, 0, 1, 1, 1)
    (tmp / "huge.vol").write_bytes(hdr + b"\0" * 64)
    inf = b"VOL" + bytes([3]) + struct.pack("<5i", 1, 1, 1, 1, 1) + struct.pack("<6f", 0, 0, 0, float("inf"), 1, 1) + b"\0" * 4
    (tmp / "inf.vol").write_bytes(inf)
    (tmp / "huge.ply").write_text("ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n")
    (tmp / "huge.obj").write_text("v 0 0 0\n" * 10 + "f " + " ".join(str(i) for i in range(1, 200000)) + "\n")
    for name, ref in (("vol", "huge.vol"), ("inf", "inf.vol")):
        (tmp / f"s_{name}.xml").write_text(
            SCENE.read_text().replace(
                "</scene>",
                '<shape type="sphere"><bsdf type="null"/><medium name="interior" type="heterogeneous">'
                f'<volume name="sigma_t" type="gridvolume"><string name="filename" value="{ref}"/></volume>'
                "</medium></shape></scene>",
            )
        )
    for name in ("ply", "obj"):
        (tmp / f"s_{name}.xml").write_text(
            SCENE.read_text().replace(
                "</scene>", f'<shape type="{name}"><string name="filename" value="huge.{name}"/></shape></scene>'
            )
        )


CASES = [
    ["render", "grow.xml", "-o", "o.exr"],
    ["render", "loop.xml", "-o", "o.exr"],
    ["render", "dtd.xml", "-o", "o.exr"],
    ["render", "deep.xml", "-o", "o.exr"],
    ["render", "s_vol.xml", "-o", "o.exr", "--spp", "1", "-D", "res=4"],
    ["render", "s_inf.xml", "-o", "o.exr", "--spp", "1", "-D", "res=4"],
    ["render", "s_ply.xml", "-o", "o.exr", "--spp", "1", "-D", "res=4"],
    ["render", "s_obj.xml", "-o", "o.exr", "--spp", "1", "-D", "res=4"],
    ["render", str(SCENE), "-o", "o.exr", "-D", "res=100000", "--spp", "1"],
    ["render", str(SCENE), "-o", "o.exr", "--spp", "4294967295", "-D", "res=1", "--threads", "4096", "--quiet"],
    ["ensemble", str(REPO / "scenes" / "fgf-cube-pink.xml"), "-n", "2", "--resolution", "65536", "-o", "o.exr", "--spp", "1"],
    ["field", "--shape", "100000", "100000", "--hurst", "-0.2", "-o", "f.npy"],
    ["field", "--shape", "1024", "1024", "512", "--hurst", "1.5", "-o", "f.npy"],
    ["field", "--shape", str(2**40), str(2**40), "--hurst", "-0.2", "-o", "f.npy"],
    ["transmittance", "--sigma-t", "1", "--hurst", "-0.2", "--sw", "1", "--points", "10000000", "-o", "t.csv", "-q"],
]


@pytest.mark.parametrize("args", CASES, ids=[" ".join(c[:2]) + f"#{i}" for i, c in enumerate(CASES)])
def test_no_abort_under_2gb_limit(tmp_path, args):
    _files(tmp_path)
    r = _limited(args, tmp_path)
    assert r.returncode in (0, 2, 130), (r.returncode, r.stderr[-2000:])
    assert "panicked" not in r.stderr and "Traceback" not in r.stderr, r.stderr[-2000:]
