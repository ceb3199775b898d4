"""The exact truth of constant-α media (`fgf.truth`, `fgf truth`; docs/theory.md §6)."""

from __future__ import annotations

import math
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import fgf

REPO = Path(__file__).resolve().parents[1]
CUBE = REPO / "scenes" / "fgf-cube-2fbm.xml"


def fgf_cli(*args: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "fgf", *map(str, args)], capture_output=True, text=True)


def write_vol(path: Path, value: float, n: int = 2) -> None:
    """A constant 1-channel Mitsuba .vol grid on the unit cube."""
    head = b"VOL" + bytes([3]) + struct.pack("<iiiii", 1, n, n, n, 1) + struct.pack("<6f", 0, 0, 0, 1, 1, 1)
    path.write_bytes(head + struct.pack(f"<{n**3}f", *([value] * n**3)))


def medium_xml(kind: str, sigma: str = "4.0", density: str = "", **p: str) -> str:
    params = "".join(
        f'<{"string" if k in ("transmittance", "kernel") else "float"} name="{k}" value="{v}"/>' for k, v in p.items()
    )
    sig = f'<rgb name="sigma_t" value="{sigma}"/>' if "," in sigma else f'<float name="sigma_t" value="{sigma}"/>'
    vol = ""
    if density:
        vol = (
            f'<volume type="gridvolume" name="density"><string name="filename" value="{density}"/>'
            '<transform name="to_world"><translate value="-0.5, -0.5, -0.5"/></transform></volume>'
        )
    return f'<medium type="{kind}" id="m">{sig}<rgb name="albedo" value="0"/>{params}{vol}</medium>'


def through_cube_scene(tmp_path: Path, medium: str, name: str = "s.xml", second: str = "") -> Path:
    """A narrow camera looking through the unit cube [-0.5, 0.5]^3 at a
    uniform environment of radiance 1: with albedo 0 each pixel is the
    transmittance of a path of length 1 (to 1.5e-4: the rays are within 1°
    of the axis)."""
    extra = ""
    if second:
        extra = (
            f'<shape type="sphere"><point name="center" x="0" y="3" z="0"/><float name="radius" value="0.2"/>'
            f'<bsdf type="null"/>{second}</shape>'
        )
    xml = f"""<scene version="3.0.0">
  <integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="2"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>
      <rfilter type="box"/></film>
  </sensor>
  {medium}
  <shape type="cube"><transform name="to_world"><scale value="0.5"/></transform>
    <bsdf type="null"/><ref name="interior" id="m"/></shape>
  {extra}
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>
"""
    path = tmp_path / name
    path.write_text(xml)
    return path


def test_plan_nodes_integrate_gamma_moments_exactly():
    plan = fgf.truth_plan(CUBE)
    a, x, w = plan.alpha, np.array(plan.x), np.array(plan.weights)
    assert plan.auto_nodes and plan.nodes >= 8
    assert plan.closed_form_error <= 1e-4
    assert abs(w.sum() - 1.0) < 1e-13
    for k in range(2 * plan.nodes):
        exact = math.prod((a + j) / a for j in range(k))
        assert np.dot(w, x**k) == pytest.approx(exact, rel=1e-9), k


def test_node_count_adapts_to_alpha_and_optical_depth():
    counts = [fgf.truth_plan(CUBE, defines={"sw": repr(sw)}).nodes for sw in (8.5, 34.0, 136.0)]
    assert counts == sorted(counts) and counts[0] < counts[-1], counts  # smaller alpha, more nodes
    assert fgf.truth_plan(CUBE, nodes=5).nodes == 5
    with pytest.raises(fgf.ParameterError, match="nodes"):
        fgf.truth_plan(CUBE, nodes=0)


@pytest.mark.parametrize(
    "kind, params, density, sigma_eff",
    [
        # k-fBm: H = 1.2, S_w = 34, L = 1 is Davis with alpha = 2.0026 (docs/theory.md §3.5).
        ("fgf", {"hurst": "1.2", "sw": "34", "length": "1"}, None, 4.0),
        ("nonexponential", {"transmittance": "davis", "alpha": "0.7"}, None, 4.0),
        # A density 0.5 halves the mean extinction: sigma = X sigma_m rho (docs/theory.md §6.5).
        ("nonexponential", {"transmittance": "davis", "alpha": "1.5"}, 0.5, 2.0),
    ],
)
def test_truth_of_direct_transmission_is_the_closed_form(tmp_path, kind, params, density, sigma_eff):
    dens = ""
    if density is not None:
        write_vol(tmp_path / "rho.vol", density)
        dens = "rho.vol"
    scene = through_cube_scene(tmp_path, medium_xml(kind, density=dens, **params))
    alpha = fgf.truth_plan(scene).alpha
    img, se = fgf.truth(scene, spp=256, seed=3, progress=False, return_stderr=True)
    mean = float(img.mean())
    # SE of the image mean: the pixels (and channels, which share the paths
    # of a grey medium) are averaged; take the pixels as independent and a
    # channel's SE for the pixel's.
    se_mean = float(np.sqrt((se[..., 0] ** 2).sum()) / se[..., 0].size)
    want = (1.0 + sigma_eff / alpha) ** (-alpha)
    # Path lengths exceed 1 by at most 1.5e-4 (1° off axis).
    bias = 1.5e-4 * sigma_eff * want
    assert abs(mean - want) <= 4.0 * se_mean + bias, (mean, want, se_mean)
    # And it is not the exponential medium's e^-sigma (the test can tell).
    assert abs(mean - math.exp(-sigma_eff)) > 20 * se_mean


def test_truth_is_deterministic_and_node_renders_sum_to_it(tmp_path):
    scene = through_cube_scene(tmp_path, medium_xml("nonexponential", transmittance="davis", alpha="2"))
    a = fgf.truth(scene, spp=4, seed=7, progress=False)
    b = fgf.truth(scene, spp=4, seed=7, progress=False, threads=1)
    np.testing.assert_array_equal(a, b)
    plan = fgf.truth_plan(scene)
    acc = np.zeros(a.shape, dtype=np.float64)
    for i, w in enumerate(plan.weights):
        img, _ = fgf.truth_render_node(scene, i, nodes=plan.nodes, spp=4, seed=7)
        acc += w * img.astype(np.float64)
    np.testing.assert_array_equal(acc.astype(np.float32), a)
    assert not np.array_equal(fgf.truth(scene, spp=4, seed=8, progress=False), a)


def test_progress_counts_every_node_sample(tmp_path):
    scene = through_cube_scene(tmp_path, medium_xml("nonexponential", transmittance="davis", alpha="2"))
    calls: list[tuple[int, int]] = []
    fgf.truth(scene, spp=2, nodes=3, progress=lambda d, t: calls.append((d, t)))
    assert calls and calls[-1] == (3 * 64 * 2, 3 * 64 * 2)


@pytest.mark.parametrize(
    "medium, second, words",
    [
        (medium_xml("fgf", hurst="-0.1", sw="1"), "", "pink noise) has no constant alpha"),
        (medium_xml("fgf", hurst="-0.5", sw="1"), "", "white noise) has no constant alpha"),
        (
            medium_xml("nonexponential", transmittance="davis_weinstein", h="0.8", c="1"),
            "",
            "Davis-Weinstein medium with h = 0.8 < 1 has no constant alpha",
        ),
        (
            medium_xml("fgf", sigma="1, 2, 4", hurst="1.2", sw="34", length="1"),
            "",
            "RGB sigma_t channels have different alpha",
        ),
        (
            medium_xml("nonexponential", transmittance="davis", alpha="2"),
            '<medium type="nonexponential" name="interior"><string name="transmittance" value="davis"/>'
            '<float name="alpha" value="3"/><float name="sigma_t" value="1"/></medium>',
            "media 0 and 1 have different alpha",
        ),
        ('<medium type="homogeneous" id="m"><float name="sigma_t" value="1"/></medium>', "", "no constant-alpha medium"),
    ],
)
def test_unsupported_scenes_are_refused_in_one_line(tmp_path, medium, second, words):
    scene = through_cube_scene(tmp_path, medium, second=second)
    with pytest.raises(fgf.SceneError, match=words.replace("(", r"\(").replace(")", r"\)")) as e:
        fgf.truth(scene, spp=1, progress=False)
    assert "\n" not in str(e.value)
    r = fgf_cli("truth", scene, "-o", tmp_path / "t.exr", "--quiet")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "Traceback" not in r.stderr, r.stderr
    assert words in r.stderr
    assert not (tmp_path / "t.exr").exists()


def test_davis_rgb_with_one_alpha_is_accepted(tmp_path):
    scene = through_cube_scene(tmp_path, medium_xml("nonexponential", sigma="1, 2, 4", transmittance="davis", alpha="2"))
    img = fgf.truth(scene, spp=8, progress=False)
    r, g, b = img.reshape(-1, 3).mean(axis=0)
    assert r > g > b  # red is the least extinguished


def test_cli_writes_outputs_and_exit_codes(tmp_path):
    scene = through_cube_scene(tmp_path, medium_xml("nonexponential", transmittance="davis", alpha="2"))
    out = tmp_path / "t.exr"
    r = fgf_cli("truth", scene, "-o", out, "--stderr", tmp_path / "se.exr", "--spp", "2", "--nodes", "4", "--seed", "1")
    assert r.returncode == 0, r.stderr
    assert "alpha = 2, 4 nodes (--nodes" in r.stderr and "wrote" in r.stderr
    assert out.exists() and out.with_suffix(".png").exists() and (tmp_path / "se.exr").exists()
    for args, words in [
        (["--nodes", "0"], "--nodes 0: need 1 <= nodes <= 4096"),
        (["--spp", "0"], "--spp: 0 is out of range (valid: 1 to"),
        (["-D", "nosuch=1"], "nosuch"),
    ]:
        r = fgf_cli("truth", scene, "-o", tmp_path / "u.exr", *args)
        assert r.returncode == 2 and words in r.stderr and "Traceback" not in r.stderr, r.stderr
    r = fgf_cli("truth", tmp_path / "missing.xml", "-o", tmp_path / "u.exr")
    assert r.returncode == 2 and "missing.xml" in r.stderr
    assert not (tmp_path / "u.exr").exists()


def test_cli_ctrl_c_writes_nothing_and_exits_130(tmp_path):
    import signal
    import time

    scene = through_cube_scene(tmp_path, medium_xml("nonexponential", transmittance="davis", alpha="2"))
    out = tmp_path / "t.exr"
    p = subprocess.Popen(
        [sys.executable, "-m", "fgf", "truth", str(scene), "-o", str(out), "--spp", "4000000", "--quiet"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(3.0)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert "interrupted; nothing written" in err and "Traceback" not in err
    assert not out.exists()


def test_truth_of_an_rgb_davis_medium_with_density_is_the_closed_form_per_channel(tmp_path):
    # One alpha for the three channels; the density becomes a 3-channel
    # heterogeneous grid sigma_c rho, scaled by x_i.
    write_vol(tmp_path / "rho.vol", 0.5)
    medium = medium_xml("nonexponential", sigma="1, 2, 4", density="rho.vol", transmittance="davis", alpha="1.5")
    scene = through_cube_scene(tmp_path, medium)
    img, se = fgf.truth(scene, spp=256, seed=3, progress=False, return_stderr=True)
    mean = img.reshape(-1, 3).mean(axis=0)
    se_mean = np.sqrt((se.astype(np.float64) ** 2).sum(axis=(0, 1))) / (se.shape[0] * se.shape[1])
    for c, sigma in enumerate((1.0, 2.0, 4.0)):
        want = (1.0 + 0.5 * sigma / 1.5) ** -1.5
        assert abs(mean[c] - want) <= 4.0 * se_mean[c] + 1.5e-4 * sigma * want, (c, mean[c], want, se_mean[c])
