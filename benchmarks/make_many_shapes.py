"""A scene of many small shapes, for timing the loading of large scene files.

    python benchmarks/make_many_shapes.py [--count 20000] [--out many-shapes.xml]

Writes a Mitsuba 3 scene of ``--count`` shapes, cubes and rectangles in turn,
each scaled by 0.1 and placed at a pseudo-random point of ``[-10, 10]³``
(a fixed seed: every run writes the same bytes), under a constant
environment, seen by a 64 × 64 camera at 1 spp. Its time is nearly all in
reading the XML and preparing the shapes, as in scenes exported from a
modelling tool with one element per object. Both renderers read it as it is::

    fgf render many-shapes.xml -o f.exr --quiet
    mitsuba -m llvm_ad_rgb -o m.exr many-shapes.xml

Results: docs/benchmarks.md, section "Large scenes on a Zen 4 without AVX-512".
"""

from __future__ import annotations

import argparse
import random
import sys
from pathlib import Path

HEADER = """<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="60"/>
        <transform name="to_world">
            <lookat origin="0, 0, 30" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="1"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="64"/>
            <integer name="height" value="64"/>
        </film>
    </sensor>
    <emitter type="constant"/>
"""


def scene(count: int) -> str:
    """The scene's XML text with ``count`` shapes."""
    rng = random.Random(1)
    lines = [HEADER]
    for i in range(count):
        x, y, z = (rng.uniform(-10.0, 10.0) for _ in range(3))
        kind = "cube" if i % 2 else "rectangle"
        lines.append(
            f'    <shape type="{kind}"><transform name="to_world"><scale value="0.1"/>'
            f'<translate x="{x:.3f}" y="{y:.3f}" z="{z:.3f}"/></transform></shape>\n'
        )
    lines.append("</scene>\n")
    return "".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=20_000, help="shapes (1 to 1,000,000)")
    ap.add_argument("--out", type=Path, default=Path("many-shapes.xml"), help="the scene file to write")
    args = ap.parse_args()
    if not 1 <= args.count <= 1_000_000:
        print(f"make_many_shapes: --count {args.count}: expected 1 to 1,000,000", file=sys.stderr)
        return 2
    try:
        args.out.write_text(scene(args.count))
    except OSError as e:
        print(f"make_many_shapes: cannot write {args.out}: {e.strerror}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
