"""Non-exponential media benchmark: the cost of the fgf medium
against the classical exponential one on the same scene.

    python benchmarks/bench_nonexp.py [--res 256] [--spp 64] [--threads N] [--repeat 2]

Takes ``scenes/reference/cube-homogeneous.xml`` and swaps its medium (sigma_t 4, albedo 0.8) for:

* ``homogeneous`` (the exponential baseline),
* ``nonexponential`` with ``transmittance="exponential"`` (the same
  transport through the non-exponential code path: its overhead alone),
* ``fgf`` pink noise, H = -0.1, S_w = 4,
* ``fgf`` 2-fBm, H = 1.2, S_w = 34, L = 1 (Davis with alpha = 2.00),

the fgf media under both kernels. Each render is warmed up once, then timed
``--repeat`` times (best kept) and reported as samples per second (pixels x spp / wall time)
and as its cost relative to the exponential render (the target:
within 1.3x). Non-exponential media also change the paths themselves
(heavier-tailed free flights, so a different number of scattering events
per path), so the ratio measures whole-render cost, not only the per-flight
overhead; the ``nonexponential exponential`` row isolates the overhead of
the code path on identical paths.
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
from pathlib import Path

REFERENCE = Path(__file__).resolve().parents[1] / "scenes" / "reference"

COMMON = '<float name="sigma_t" value="4.0"/><rgb name="albedo" value="0.8"/><phase type="isotropic"/>'
MEDIA = {
    "homogeneous (exponential)": f'<medium type="homogeneous" name="interior">{COMMON}</medium>',
    "nonexponential exponential": '<medium type="nonexponential" name="interior">'
    f'<string name="transmittance" value="exponential"/>{COMMON}</medium>',
}
for kernel in ["energy_conserving", "reciprocal"]:
    MEDIA[f"fgf pink H=-0.1 ({kernel})"] = (
        '<medium type="fgf" name="interior"><float name="hurst" value="-0.1"/><float name="sw" value="4"/>'
        f'<string name="kernel" value="{kernel}"/>{COMMON}</medium>'
    )
    MEDIA[f"fgf 2-fBm H=1.2 ({kernel})"] = (
        '<medium type="fgf" name="interior"><float name="hurst" value="1.2"/><float name="sw" value="34"/>'
        f'<float name="length" value="1"/><string name="kernel" value="{kernel}"/>{COMMON}</medium>'
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    if min(args.res, args.spp, args.repeat) < 1:
        ap.error("--res, --spp and --repeat must be >= 1")

    import fgf

    src = (REFERENCE / "cube-homogeneous.xml").read_text()
    medium_re = re.compile(r'<medium type="homogeneous" name="interior">.*?</medium>', re.S)
    if len(medium_re.findall(src)) != 1:
        print("bench_nonexp: cannot find the cube's medium in cube-homogeneous.xml", file=sys.stderr)
        return 2
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, medium in MEDIA.items():
            path = Path(tmp) / "scene.xml"
            path.write_text(medium_re.sub(medium, src))
            # An untimed warm-up (thread pool, caches), so that the first
            # medium, the baseline, is not charged for the start.
            fgf.render(path, spp=args.spp, seed=1000, threads=args.threads, defines={"res": args.res}, progress=False)
            best = float("inf")
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                img = fgf.render(path, spp=args.spp, seed=0, threads=args.threads, defines={"res": args.res}, progress=False)
                best = min(best, time.perf_counter() - t0)
            rate = args.res * args.res * args.spp / best
            rows.append((label, best, rate, float(img.mean())))
    base = rows[0][1]
    print(f"cube-homogeneous.xml, {args.res}x{args.res}, {args.spp} spp, max_depth 64, best of {args.repeat}")
    print(f"| medium | time (s) | M samples/s | cost / exponential | image mean |")
    print(f"|---|---|---|---|---|")
    for label, t, rate, mean in rows:
        print(f"| {label} | {t:.2f} | {rate / 1e6:.3f} | {t / base:.2f}x | {mean:.4f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
