"""Digests of small renders of the repository's scenes and of one field, for
scripts/wheel_smoke.sh: it runs this once with the portable wheel and once
with the native, profile-guided build of ./.venv, and requires the same
output. Builds differ in speed, never in results (ARCHITECTURE.md, "Build").

Not collected by pytest (no ``test_`` prefix).

    python tests/image_digests.py REPO
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path

import numpy as np

# Scene, defines: every medium kind, the BSDF families of the repository's
# scenes, area, spot and environment lights, a 120,000-triangle mesh.
SCENES = [
    ("scenes/reference/cube-homogeneous.xml", {"res": "24"}),
    ("scenes/reference/cube-heterogeneous.xml", {"res": "24"}),
    ("scenes/reference/mesh-envmap.xml", {"res": "24"}),
    ("scenes/fgf-cube-pink.xml", {"res": "24"}),
    ("scenes/fgf-cube-pink.xml", {"res": "24", "kernel": "reciprocal"}),
    ("scenes/fgf-cube-2fbm.xml", {"res": "24"}),
    ("scenes/figures/medium_on_ground.xml", {"res": "24", "medium": "davis"}),
    ("scenes/figures/medium_on_ground.xml", {"res": "24", "medium": "davis_weinstein"}),
    ("scenes/glass-medium.xml", {"res": "24"}),
    ("scenes/spot-sphere.xml", {"res": "24"}),
]


def main() -> int:
    import fgf

    repo = Path(sys.argv[1])
    for scene, defines in SCENES:
        img = fgf.render(repo / scene, spp=8, seed=3, threads=2, defines=defines, progress=False)
        digest = hashlib.sha256(np.ascontiguousarray(img, dtype=np.float32).tobytes()).hexdigest()
        print(f"{scene} {sorted(defines.items())} {digest[:16]}")
    field = fgf.synthesize((32, 32, 32), hurst=-0.3, sw=2.0, seed=5, progress=False)
    print(f"field {hashlib.sha256(np.ascontiguousarray(field).tobytes()).hexdigest()[:16]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
