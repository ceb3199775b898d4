#!/usr/bin/env python3
"""Is one build of the renderer faster than another? Shuffled short runs, ratios within rounds.

    python benchmarks/ab_render.py [--old REV] [--new REV] [--scene XML] [--spp N]
                                   [--rounds N] [--threads N] [name=value ...]

Builds the `render_scene` example (fgf-render, no Python) of two revisions, each from
its own copy of the tree (`git archive`) into its own target directory under
`target/ab/`, with the flags of that tree's `.cargo/config.toml` (native by default).
`--new .` (the default) is the working tree as it is, uncommitted changes included;
`--old` defaults to `HEAD`. Then it runs both on the scene in rounds, in a shuffled
order each round (a fixed seed), and prints the median of the rounds' time ratios
new/old, their geometric mean with a band of two standard errors, in how many rounds
the new build was faster, each build's least time, and whether the images are
bit-identical (the hash `render_scene` prints).

Why this way: on a shared virtual machine the speed of a core drifts in phases of
tens of seconds (another tenant on the sibling hyperthread), so a few long runs, or
the least of some runs, can show a few per cent either way that is not there
(docs/benchmarks.md, "The rays of a round as streams"). Short runs (about a second)
in many shuffled rounds, compared within a round, average the phases out; even so, a
build against itself has come out 2 % apart over 20 rounds, so read only what falls
outside the band. The time
is the one `render_scene` prints: the render with its scene build (tree, tables),
without reading the scene file. For figures to report against other renderers,
time whole processes with `benchmarks/bench_render.py` instead.

Defaults: `scenes/reference/mesh-envmap.xml` at 128², 128 spp, 20 rounds, all threads.
The mesh scene needs its generated assets: `python benchmarks/make_mesh_envmap.py`.
Exit status 2 on bad arguments (a missing scene, an unknown revision), with one line.
"""

from __future__ import annotations

import argparse
import io
import math
import random
import re
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path
from typing import NoReturn

ROOT = Path(__file__).resolve().parent.parent
LINE = re.compile(r"^([0-9.]+) s .* hash ([0-9a-f]+)")


def fail(msg: str) -> NoReturn:
    print(f"ab_render: {msg}", file=sys.stderr)
    raise SystemExit(2)


def build(rev: str, work: Path) -> Path:
    """The `render_scene` binary of `rev` (`.`: the working tree), built if needed."""
    if rev == ".":
        src, name = ROOT, "worktree"
    else:
        got = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--verify", "--quiet", f"{rev}^{{commit}}"],
                             capture_output=True, text=True)
        if got.returncode != 0:
            fail(f"--old/--new: {rev!r} is not a revision of {ROOT}")
        name = got.stdout.strip()[:12]
        src = work / name
        if src.exists():  # --old and --new name the same commit
            return ROOT / "target" / "ab" / name / "release" / "examples" / "render_scene"
        src.mkdir()
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", name],
                                 capture_output=True, check=True).stdout
        with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
            tar.extractall(src, filter="data")
    target = ROOT / "target" / "ab" / name
    print(f"ab_render: building render_scene of {rev} ({name}) in {target}", file=sys.stderr)
    # The tree's own directory as the working directory: cargo reads the
    # `.cargo/config.toml` (the build flags) of the directory it runs in.
    subprocess.run(["cargo", "build", "-q", "--release", "-p", "fgf-render", "--example", "render_scene",
                    "--target-dir", str(target)], cwd=src, check=True)
    return target / "release" / "examples" / "render_scene"


def run(binary: Path, scene: Path, spp: int, threads: int, defines: list[str]) -> tuple[float, str]:
    out = subprocess.run([str(binary), str(scene), str(spp), str(threads), *defines],
                         cwd=scene.parent, capture_output=True, text=True)
    m = LINE.search(out.stdout)
    if out.returncode != 0 or m is None:
        last = (out.stderr or out.stdout).strip().splitlines()
        fail(f"{binary} {scene.name}: {last[-1] if last else f'exit {out.returncode}'}")
    return float(m.group(1)), m.group(2)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default="HEAD", help="revision to compare against (default HEAD)")
    ap.add_argument("--new", default=".", help="revision to measure ('.', the default: the working tree)")
    ap.add_argument("--scene", type=Path, default=ROOT / "scenes" / "reference" / "mesh-envmap.xml")
    ap.add_argument("--spp", type=int, default=128, help="samples per pixel, >= 1 (default 128)")
    ap.add_argument("--rounds", type=int, default=20, help="rounds, >= 2 (default 20)")
    ap.add_argument("--threads", type=int, default=0, help="render threads, 0 = all (default)")
    ap.add_argument("defines", nargs="*", help="scene defines name=value (default res=128)")
    a = ap.parse_args(argv)
    if not a.scene.is_file():
        fail(f"--scene: no file {a.scene}")
    if a.spp < 1 or a.rounds < 2 or a.threads < 0:
        fail("--spp must be >= 1, --rounds >= 2 and --threads >= 0")
    if any("=" not in d for d in a.defines):
        fail("defines are name=value")
    defines = a.defines or ["res=128"]
    scene = a.scene.resolve()
    try:
        with tempfile.TemporaryDirectory() as tmp:
            bins = {"old": build(a.old, Path(tmp)), "new": build(a.new, Path(tmp))}
        for b in bins.values():  # a first run each, not counted
            run(b, scene, a.spp, a.threads, defines)
        rnd = random.Random(1)
        ratios: list[float] = []
        times: dict[str, list[float]] = {"old": [], "new": []}
        hashes: dict[str, set[str]] = {"old": set(), "new": set()}
        for r in range(a.rounds):
            order = ["old", "new"]
            rnd.shuffle(order)
            got = {}
            for k in order:
                t, h = run(bins[k], scene, a.spp, a.threads, defines)
                got[k] = t
                times[k].append(t)
                hashes[k].add(h)
            if min(got.values()) <= 0.0:
                fail("a render took under a millisecond: raise --spp or the resolution")
            ratios.append(got["new"] / got["old"])
            print(f"round {r + 1:2}: old {got['old']:.3f} s  new {got['new']:.3f} s  new/old {ratios[-1]:.3f}",
                  file=sys.stderr)
    except KeyboardInterrupt:
        print("ab_render: interrupted", file=sys.stderr)
        return 130
    except subprocess.CalledProcessError as e:
        fail(f"{' '.join(map(str, e.cmd[:3]))} failed (exit {e.returncode})")
    except OSError as e:
        fail(f"{e.filename or ''}: {e.strerror}")
    logs = [math.log(x) for x in ratios]
    geo = math.exp(statistics.fmean(logs))
    # Two standard errors of the mean log ratio: a change inside this band is
    # not told apart from none.
    band = 2 * statistics.stdev(logs) / math.sqrt(len(logs))
    faster = sum(x < 1 for x in ratios)
    same = "bit-identical" if hashes["old"] == hashes["new"] and len(hashes["old"]) == 1 else \
        f"DIFFERENT (old {sorted(hashes['old'])}, new {sorted(hashes['new'])})"
    print(f"{scene.name} {' '.join(defines)} {a.spp} spp, {a.rounds} rounds: new/old median {statistics.median(ratios):.3f}, "
          f"geometric mean {geo:.3f} ({geo * math.exp(-band):.3f}-{geo * math.exp(band):.3f} at two standard errors), new faster in {faster} of {a.rounds}; least times old {min(times['old']):.3f} s, "
          f"new {min(times['new']):.3f} s; images {same}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
