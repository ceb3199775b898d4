"""Benchmark: fgf field synthesis against a straightforward numpy + scipy.fft
implementation of the same algorithm.

Cases (256^3, float32 output, spacing 1/256, S_w = 1):

* pink noise, H = -0.1 (periodic domain = the grid);
* 2-fBm, H = 1.5, padding 2 (periodic domain 512^3), anchored at the corner.

The scipy version does what ``docs/theory.md`` §1 says in the obvious way:
float32 noise from ``numpy.random.default_rng``, ``scipy.fft.rfftn``
(``workers=2``), multiply by ``sqrt(S_w/dx^3) |k|^(-s)`` (``k = 0`` and, for
k-fBm, Nyquist modes dropped), the Taylor sums of the anchored k-fBm on the
half spectrum, ``irfftn``, crop, subtract the polynomial. It runs in single
precision like ours (complex64 transforms), which is the fair comparison.

Each (case, implementation) runs in a fresh subprocess that synthesizes
``--repeats`` times; we report the best wall time and the process's peak
resident memory (``ru_maxrss``, which includes the interpreter and numpy:
about the ``baseline`` line), and that peak minus the process's resident
size after its imports, in MiB and relative to the 64 MiB output array. Run when the machine is quiet::

    python benchmarks/bench_field.py            # both cases
    python benchmarks/bench_field.py --case pink --repeats 5
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from typing import Any

N = 256
CASES = {"pink": dict(hurst=-0.1, padding=1.0), "2fbm": dict(hurst=1.5, padding=2.0)}

CHILD = r"""
import json, resource, sys, time
import numpy as np
impl, hurst, padding, repeats = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
N = %(N)d
dx = 1.0 / N

def ours(seed):
    import fgf
    return fgf.synthesize((N, N, N), hurst=hurst, sw=1.0, spacing=dx, seed=seed, padding=padding, anchor="corner", progress=False)

def scipy_version(seed):
    import scipy.fft
    d = 3
    s = hurst + d / 2
    n = int(round(N * padding))
    shape = (n, n, n)
    rng = np.random.default_rng(seed)
    w = rng.standard_normal(shape, dtype=np.float32)
    spec = scipy.fft.rfftn(w, workers=2)
    del w
    kz = (2 * np.pi * np.fft.fftfreq(n, d=dx)).astype(np.float32)
    kx = (2 * np.pi * np.fft.rfftfreq(n, d=dx)).astype(np.float32)
    k2 = kz[:, None, None] ** 2 + kz[None, :, None] ** 2 + kx[None, None, :] ** 2
    k2[0, 0, 0] = np.inf
    amp = np.float32(np.sqrt(1.0 / dx**d))
    spec *= amp * k2 ** np.float32(-s / 2)
    del k2
    if hurst > 0:
        spec[n // 2, :, :] = 0
        spec[:, n // 2, :] = 0
        spec[:, :, n // 2] = 0
        k = int(np.ceil(hurst))
        # Taylor sums at the corner anchor (phases are 1): half-spectrum
        # weights 2 except the x = 0 plane; irfftn's 1/N normalisation.
        c = np.full(kx.shape, 2.0, np.float32)
        c[0] = 1.0
        terms = [(a, b, e) for a in range(k) for b in range(k) for e in range(k) if a + b + e < k]
        coef = {}
        for a, b, e in terms:
            mono = (1j * kz[:, None, None]) ** a * (1j * kz[None, :, None]) ** b * (1j * kx[None, None, :]) ** e * c
            coef[(a, b, e)] = float(np.real(np.sum(spec * mono, dtype=np.complex128))) / n**3
    f = scipy.fft.irfftn(spec, s=shape, workers=2)
    del spec
    f = np.ascontiguousarray(f[:N, :N, :N])
    if hurst > 0:
        from math import factorial
        x = (np.arange(N) * dx).astype(np.float32)
        for (a, b, e), v in coef.items():
            f -= np.float32(v / (factorial(a) * factorial(b) * factorial(e))) * (
                x[:, None, None] ** a * x[None, :, None] ** b * x[None, None, :] ** e
            )
    return f

fn = ours if impl == "ours" else scipy_version
import fgf, scipy.fft  # imported before measuring the baseline
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
times = []
for r in range(repeats):
    t0 = time.perf_counter()
    f = fn(r)
    times.append(time.perf_counter() - t0)
    assert f.shape == (N, N, N) and f.dtype == np.float32, (f.shape, f.dtype)
    del f
rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"best": min(times), "times": times, "maxrss_mib": rss1, "extra_mib": rss1 - rss0}))
""" % {"N": N}

BASELINE = "import json, resource, numpy, scipy.fft, fgf; print(json.dumps({'maxrss_mib': resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))"


def child(impl: str, hurst: float, padding: float, repeats: int) -> dict[str, Any]:
    out = subprocess.run(
        [sys.executable, "-c", CHILD, impl, str(hurst), str(padding), str(repeats)], check=True, capture_output=True, text=True
    ).stdout
    result: dict[str, Any] = json.loads(out)
    return result


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--case", choices=sorted(CASES), action="append", help="case(s) to run (default: all)")
    ap.add_argument("--repeats", type=int, default=3, help="syntheses per subprocess; the best time is reported")
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start")
    base = json.loads(subprocess.run([sys.executable, "-c", BASELINE], check=True, capture_output=True, text=True).stdout)
    print(f"baseline (python + numpy + scipy.fft + fgf imported): {base['maxrss_mib']:.0f} MiB; output array {N**3 * 4 / 2**20:.0f} MiB")
    print(f"{'case':6s} {'impl':6s} {'best s':>8s} {'peak MiB':>9s} {'peak - imports MiB':>19s} {'/ output':>9s}")
    ok = True
    for case in args.case or sorted(CASES, reverse=True):
        cfg = CASES[case]
        res = {impl: child(impl, cfg["hurst"], cfg["padding"], args.repeats) for impl in ("ours", "scipy")}
        for impl, r in res.items():
            out_mib = N**3 * 4 / 2**20
            print(f"{case:6s} {impl:6s} {r['best']:8.3f} {r['maxrss_mib']:9.0f} {r['extra_mib']:19.0f} {r['extra_mib'] / out_mib:9.2f}")
        ratio = res["scipy"]["best"] / res["ours"]["best"]
        mem = res["ours"]["maxrss_mib"] / res["scipy"]["maxrss_mib"]
        print(f"{case:6s} speed-up {ratio:.2f}x, peak memory ours/scipy {mem:.2f}")
        ok &= ratio >= 2.0 and mem <= 1.0
    print(f"load average {os.getloadavg()[0]:.2f} at end")
    print("target (>= 2x faster at <= scipy's peak memory):", "met" if ok else "NOT met")
    return 0


if __name__ == "__main__":
    sys.exit(main())
