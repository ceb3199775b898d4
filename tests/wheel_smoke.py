"""Smoke test of an installed fgf wheel, run by scripts/wheel_smoke.sh in a fresh venv.

Not collected by pytest (no ``test_`` prefix): it must run outside the
repository, against the installed package. Exits non-zero on failure.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

import numpy as np


def check_build(where: str) -> str:
    """The wheel carries the portable module and, on x86-64, its x86-64-v3
    build; ``import fgf`` loaded the one this CPU runs, or the portable one
    under ``FGF_PORTABLE=1`` (fgf/_native.py). Returns what was loaded."""
    import platform

    import fgf
    from fgf import _native

    builds = sorted(f for f in os.listdir(where) if f.startswith("_core") and not f.endswith(".pyi"))
    (portable,) = [os.path.join(where, f) for f in builds if f.startswith("_core.")]
    if platform.machine() != "x86_64":
        assert len(builds) == 1, builds
        assert fgf._core.__file__ == portable, fgf._core.__file__
        return f"the portable build ({fgf._core.simd})"
    assert builds == sorted([os.path.basename(portable), os.path.basename(_native.v3_path(portable))]), builds
    v3 = _native.cpu_runs_v3(portable) and not _native.forced_portable()
    want = _native.v3_path(portable) if v3 else portable
    assert fgf._core.__file__ == want, (fgf._core.__file__, want)
    assert fgf._core.simd == ("avx2" if v3 else "sse2"), fgf._core.simd
    # `from fgf import _core` anywhere in the package is the same module.
    render = sys.modules["fgf.render"]
    assert render._core is fgf._core and sys.modules["fgf._core"] is fgf._core, render._core
    if v3:
        return "the x86-64-v3 build (avx2)"
    why = "FGF_PORTABLE=1" if _native.forced_portable() else "this CPU does not run x86-64-v3"
    return f"the portable build (sse2; {why})"


def main() -> int:
    import fgf

    where = os.path.dirname(fgf.__file__)
    assert "site-packages" in where, f"fgf imported from {where}, not from the installed wheel"
    assert fgf._core.__file__.startswith(where), fgf._core.__file__
    build = check_build(where)

    # Tr values: an exponential medium is exp(-sigma_t t); FGF lies above it
    # for t > 0 (positively correlated extinction) and starts at 1.
    t = np.array([0.0, 0.25, 0.5, 1.0])
    np.testing.assert_allclose(fgf.Exponential(sigma_t=2.0).tr(t), np.exp(-2.0 * t), rtol=1e-12)
    tr = fgf.Fgf(sigma_t=2.0, hurst=-0.1, sw=4.0).tr(t)
    assert tr[0] == 1.0 and np.all(np.diff(tr) < 0) and np.all(tr[1:] > np.exp(-2.0 * t[1:])), tr

    # A tiny render of a scene written here: a sphere of FGF medium lit by
    # a constant environment, 8x8 pixels.
    scene = """<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="sphere">
        <bsdf type="null"/>
        <medium type="fgf" name="interior">
            <float name="sigma_t" value="3"/><rgb name="albedo" value="0.8"/>
            <float name="hurst" value="-0.1"/><float name="sw" value="4"/>
        </medium>
    </shape>
</scene>
"""
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "smoke.xml")
        with open(path, "w") as fh:
            fh.write(scene)
        img = fgf.render(path, spp=4, seed=1, progress=False)
        assert img.shape == (8, 8, 3) and np.isfinite(img).all(), img.shape
        # Corner pixels miss the sphere and see the unit environment (up to
        # the film's reconstruction-filter weighting, 0.2 %); through the
        # centre, an optically thick (tau = 6 across) sphere that absorbs
        # 20 % per scattering is clearly darker (radiance about 0.5; the
        # 4 spp estimate's error is ~0.1 per pixel, fixed seed).
        assert np.isfinite(img).all() and img.min() > 0.0, img.min()
        np.testing.assert_allclose(img[0, 0], 1.0, rtol=0.01)
        assert img[2:6, 2:6].mean() < 0.9, img[2:6, 2:6].mean()

    # The wheel's metadata declares the extras.
    from importlib.metadata import metadata

    md = metadata("fgf")
    extras = set(md.get_all("Provides-Extra") or [])
    assert {"cluster", "mitsuba", "vdb"} <= extras, extras
    requires = " ".join(md.get_all("Requires-Dist") or [])
    assert "dask[distributed]" in requires and "mitsuba==3.9.1" in requires and "tinyvdb" in requires, requires

    # The `fgf` console script of the venv prints the package version.
    exe = os.path.join(os.path.dirname(sys.executable), "fgf")
    out = subprocess.run([exe, "--version"], capture_output=True, text=True, check=True).stdout.strip()
    assert out == f"fgf {fgf.__version__} ({fgf._core.simd})", out
    print(f"wheel smoke test passed: {out}, imported from {where}, {build}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
