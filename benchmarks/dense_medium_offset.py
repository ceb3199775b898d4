"""Per-seed image means of the corpus scene test_homo_spectral_sigmat_volpathmis
and its variants, from fgf and Mitsuba, for the study in docs/compatibility.md
("Mitsuba's ray offset thins the dense medium").

    python benchmarks/dense_medium_offset.py RENDERER NAME SEED0 K SPP [key=value ...]

RENDERER is `fgf` or `mitsuba` (scalar_rgb); the keys change the scene:
`integrator=volpath`, `sigma_t=1,1,1` (the grey medium), `s=0.1` (every
length times s and sigma_t divided by s), `max_depth=4`,
`sample_emitters=false`. The K per-seed means (RGB, 32x32, SPP samples per
pixel) are saved to `OUT/RENDERER_NAME_SEED0.npy` (OUT: $OFFSET_STUDY_OUT,
default /tmp/offset_study) every 16 seeds, and

    python benchmarks/dense_medium_offset.py compare A B

prints the relative difference and Welch z per channel between two saved
runs (file stems, e.g. fgf_grey_600000 mitsuba_grey_40000). The row "fgf with
Mitsuba's offset" used a test build of fgf with `OFFSET_SCALE` in
crates/fgf-render/src/ray.rs set to 1500 * 2**-24 (Mitsuba's RayEpsilon).
"""

from __future__ import annotations

import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
CORPUS = REPO / "tests" / "corpus" / "mitsuba-data"
PM = "tests/scenes/participating_media"
OUT = Path(os.environ.get("OFFSET_STUDY_OUT", "/tmp/offset_study"))


def write_scene(root: Path, opts: dict[str, str]) -> Path:
    """The scene in a copy of the corpus at `root`, changed by `opts`."""
    pm = root / PM
    base = (pm / "include" / "test-scene-base.xml").read_text().replace('value="$res"', 'value="32"')
    text = (pm / "test_homo_spectral_sigmat_volpathmis.xml").read_text()
    s = float(opts.get("s", 1.0))
    if "max_depth" in opts:
        base = base.replace('<integer name="max_depth" value="6"/>', f'<integer name="max_depth" value="{opts["max_depth"]}"/>')
    if s != 1.0:
        xf = f'<transform name="to_world"><scale value="{s}"/></transform>'
        for a, b in [
            ('origin="0.0, 0.5, 4.0"', f'origin="0.0, {0.5 * s}, {4.0 * s}"'),
            ('target="0.0, -0.5, 0.0"', f'target="0.0, {-0.5 * s}, 0.0"'),
            ('<float name="near_clip" value="1"/>', f'<float name="near_clip" value="{s}"/>'),
            ('<float name="far_clip" value="1000"/>', f'<float name="far_clip" value="{1000 * s}"/>'),
            ('value="meshes/background.obj"/>', 'value="meshes/background.obj"/>' + xf),
        ]:
            assert base.count(a) == 1, a
            base = base.replace(a, b)
        for a, b in [
            ('<float name="scale" value="10.0"/>', f'<float name="scale" value="{10.0 / s}"/>'),
            ('value="meshes/sphere_tiny.obj"/>', 'value="meshes/sphere_tiny.obj"/>' + xf),
            ('value="meshes/sphere_base.obj"/>', 'value="meshes/sphere_base.obj"/>' + xf),
        ]:
            assert text.count(a) == 1, a
            text = text.replace(a, b)
    if "sigma_t" in opts:
        text = text.replace('value="1, 0.2, 1"', f'value="{opts["sigma_t"].replace(",", ", ")}"')
    if "integrator" in opts:
        text = text.replace('<default name="integrator" value="volpathmis"/>', f'<default name="integrator" value="{opts["integrator"]}"/>')
    if opts.get("sample_emitters") == "false":
        text = text.replace('<phase type="isotropic" />', '<phase type="isotropic" /><boolean name="sample_emitters" value="false"/>')
    (pm / "include" / "study-base.xml").write_text(base)
    out = pm / "study.xml"
    out.write_text(text.replace("include/test-scene-base.xml", "include/study-base.xml"))
    return out


def run(renderer: str, name: str, seed0: int, k: int, spp: int, opts: dict[str, str]) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    dest = OUT / f"{renderer}_{name}_{seed0}.npy"
    with tempfile.TemporaryDirectory() as tmp:
        shutil.copytree(CORPUS, Path(tmp), dirs_exist_ok=True)
        scene = write_scene(Path(tmp), opts)
        if renderer == "fgf":
            import fgf

            def one(seed: int) -> np.ndarray:
                return np.asarray(fgf.render(scene, spp=spp, seed=seed, progress=False).mean(axis=(0, 1), dtype=np.float64))

        else:
            import mitsuba as mi

            mi.set_variant("scalar_rgb")
            sc = mi.load_file(str(scene))

            def one(seed: int) -> np.ndarray:
                # (Mitsuba's stub types the seed as its UInt32; it takes an int.)
                img = np.array(mi.render(sc, seed=seed, spp=spp))  # type: ignore[arg-type]
                return np.asarray(img[..., :3].mean(axis=(0, 1), dtype=np.float64))

        t0, means = time.time(), []
        for i in range(k):
            means.append(one(seed0 + i))
            if i % 16 == 15 or i == k - 1:
                np.save(dest, np.array(means))
    print(f"{dest}: {k} seeds in {time.time() - t0:.0f} s, mean {np.mean(means, axis=0)}")


def compare(a_name: str, b_name: str) -> None:
    a, b = np.load(OUT / f"{a_name}.npy"), np.load(OUT / f"{b_name}.npy")
    ma, mb = a.mean(0), b.mean(0)
    se = np.sqrt(a.var(0, ddof=1) / len(a) + b.var(0, ddof=1) / len(b))
    rel = " ".join(f"{r:+.3%}" for r in ma / mb - 1)
    z = " ".join(f"{t:+.2f}" for t in (ma - mb) / se)
    print(f"{a_name} ({len(a)}) vs {b_name} ({len(b)}): relative {rel}, z {z}")


if __name__ == "__main__":
    if sys.argv[1] == "compare":
        compare(sys.argv[2], sys.argv[3])
    else:
        opts = {}
        for kv in sys.argv[6:]:
            m = re.match(r"([a-z_]+)=(.*)", kv)
            if m is None:
                print(f"dense_medium_offset.py: option {kv!r} is not name=value", file=sys.stderr)
                sys.exit(2)
            opts[m[1]] = m[2]
        run(sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5]), opts)
