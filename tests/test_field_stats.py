"""Ensemble statistics of the field synthesis and the exact 1D samplers (slow step).

Every check is ``|estimate - expected| <= Z * SE`` with the standard error
estimated from the independent replicates (seeds or rays) of that check,
fixed seeds, and ``Z = 4`` (two-sided p = 6.3e-5 per comparison). There are
fewer than 50 comparisons in this file, so the family-wise error rate is
below 0.3 %. Expected values are closed forms computed here with scipy, or
the discrete spectral sum for grid fields (``docs/theory.md`` §1: grid fields are
validated against the discrete sum, not the continuum).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import binom, gamma

import fgf

pytestmark = pytest.mark.slow

Z = 4.0


def _check(samples: np.ndarray, expected: float, what: str) -> None:
    samples = np.asarray(samples, dtype=np.float64)
    se = samples.std(ddof=1) / np.sqrt(len(samples))
    est = samples.mean()
    assert abs(est - expected) <= Z * se, f"{what}: {est:.6g} vs {expected:.6g} (SE {se:.3g})"


@pytest.mark.parametrize(
    "shape,hurst,spacing,padding,anchor",
    [
        ((4096,), -0.3, 1 / 4096, None, None),
        ((48, 40), -0.6, 0.02, None, None),
        ((24, 20, 18), -0.4, 1 / 20, None, None),
        ((24, 20, 18), -1.5, 1 / 20, None, None),  # white noise in 3D
        ((40, 36), 1.3, 0.05, 1.0, None),  # periodic 2-fBm, no anchor
        ((20, 18, 16), 0.7, 0.05, 1.5, None),  # padded 1-fBm, cropped
    ],
)
def test_ensemble_mean_zero_and_variance_is_the_discrete_spectral_sum(shape, hurst, spacing, padding, anchor):
    m = 200
    sw = 1.7
    fields = [
        fgf.synthesize(shape, hurst=hurst, sw=sw, spacing=spacing, padding=padding, anchor=anchor, seed=1000 + i, dtype=np.float64, progress=False)
        for i in range(m)
    ]
    want = fgf.discrete_spectral_variance(shape, hurst, sw=sw, spacing=spacing, padding=padding)
    # Each seed's spatial mean of f^2 has expectation var (stationary field);
    # seeds are independent, so their spread gives the SE.
    _check([np.mean(f**2) for f in fields], want, f"variance {shape} H={hurst}")
    corner = tuple(0 for _ in shape)
    centre = tuple(n // 2 for n in shape)
    _check([f[corner] for f in fields], 0.0, "ensemble mean at the corner")
    _check([f[centre] for f in fields], 0.0, "ensemble mean at the centre")


@pytest.mark.parametrize("hurst", [-0.5, -0.2, 1.2])
def test_fitted_spectral_slope_is_minus_two_s(hurst):
    # 2D, periodic (padding 1, unanchored): E[periodogram] = S_w |k|^(-2s)
    # exactly at every mode. Fit the slope of log(mean periodogram per
    # logarithmic bin) against log(mean |k|) per seed, over bins between 8
    # fundamentals and half the Nyquist wavenumber (coarse lattice effects
    # below, none above); the seeds' spread gives the SE of the mean slope.
    n, dx, m = 128, 1 / 128, 40
    s = hurst + 1.0
    slopes = []
    for i in range(m):
        f = fgf.synthesize((n, n), hurst=hurst, spacing=dx, padding=1.0, anchor=None, seed=i, dtype=np.float64, progress=False)
        k, p, _ = fgf.radial_power_spectrum(f, spacing=dx, n_bins=30)
        sel = (k > 8 * 2 * np.pi / (n * dx)) & (k < 0.5 * np.pi / dx)
        slopes.append(np.polyfit(np.log(k[sel]), np.log(p[sel]), 1)[0])
    _check(slopes, -2 * s, f"spectral slope H={hurst}")


def s_p(h, sw):
    return sw / (gamma(2 * h + 3) * abs(np.sin(np.pi * h)))


@pytest.mark.parametrize("hurst,sw", [(-0.5, 0.8), (-0.3, 0.3), (-0.05, 2.0)])
def test_exact_optical_depth_line_average_variance(hurst, sw):
    n_rays, n_steps, t_max = 20000, 512, 4.0
    tau = fgf.sample_optical_depth(n_rays, n_steps, t_max, hurst=hurst, sw=sw, seed=11, progress=False)
    t = np.linspace(0, t_max, n_steps + 1)
    for i in (1, 8, 64, 512):
        _check((tau[:, i] / t[i]) ** 2, s_p(hurst, sw) * t[i] ** (2 * hurst), f"var[sigma_bar] t={t[i]}")
    # The covariance across distances is the fBm's, Hurst h = H + 1.
    h = hurst + 1
    i, j = 100, 300
    want = 0.5 * s_p(hurst, sw) * (t[i] ** (2 * h) + t[j] ** (2 * h) - abs(t[j] - t[i]) ** (2 * h))
    _check(tau[:, i] * tau[:, j], want, "cov tau(t1) tau(t2)")


def kfbm_point_variance(h, sw, x):
    k = int(np.ceil(h))
    c1 = -1.0 / (2.0 * gamma(2 * h + 1) * np.sin(np.pi * h))
    return 2 * c1 * sw * (-1) ** k * binom(2 * h - 1, k - 1) * abs(x) ** (2 * h)


@pytest.mark.parametrize("hurst", [0.3, 0.85, 1.2, 1.8, 2.5])
def test_exact_kfbm_point_variance(hurst):
    m, n_steps, length, sw = 20000, 200, 3.0, 1.3
    vals = fgf.sample_kfbm_1d(m, n_steps, length, hurst=hurst, sw=sw, seed=5, progress=False)
    x = np.linspace(0, length, n_steps + 1)
    for i in (1, 50, 200):
        _check(vals[:, i] ** 2, kfbm_point_variance(hurst, sw, x[i]), f"k-fBm var H={hurst} x={x[i]}")


def test_grid_line_average_second_moment_matches_the_discrete_expectation():
    # 1D periodic pink noise: the mean of L consecutive samples has variance
    # (S_w/dx)(1/N) sum_{m != 0} |k_m|^(-2s) |D_L(m)|^2 with the Dirichlet
    # factor D_L(m) = (1/L) sum_{j<L} e^{2 pi i m j / N}. Each seed's
    # estimate (a mean over all non-overlapping segments) is unbiased.
    n, dx, h, sw, m = 4096, 1 / 4096, -0.3, 0.8, 200
    lengths = [1, 4, 64, 512]
    est = np.array(
        [fgf.line_average_second_moment(fgf.synthesize((n,), hurst=h, sw=sw, spacing=dx, seed=i, dtype=np.float64, progress=False), lengths) for i in range(m)]
    )
    mm = np.fft.fftfreq(n) * n
    k = 2 * np.pi * mm / (n * dx)
    w = np.zeros(n)
    w[1:] = np.abs(k[1:]) ** (-2 * (h + 0.5))
    for col, L in enumerate(lengths):
        dl = np.exp(2j * np.pi * np.outer(mm, np.arange(L)) / n).mean(axis=1)
        want = sw / dx * np.sum(w * np.abs(dl) ** 2) / n
        _check(est[:, col], want, f"line average L={L}")
