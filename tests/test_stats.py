"""FGF statistics (docs/theory.md §1-2) through the Python API, against
independent numerical integrals computed with scipy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, special

import fgf


@pytest.mark.parametrize("hurst", [-0.45, -0.3, -0.1, -0.02])
@pytest.mark.parametrize("t", [0.2, 1.0, 5.0])
def test_pink_variance_matches_double_integral(hurst, t):
    # (1/t²) ∫∫ C(H,1) S_w |x-y|^(2H) over [0,t]², as twice the triangle
    # y < x; QUADPACK's extrapolation handles the diagonal singularity.
    sw = 3.0
    inner, _ = integrate.dblquad(
        lambda y, x: (x - y) ** (2 * hurst), 0.0, t, 0.0, lambda x: x,
        epsabs=1e-12, epsrel=1e-9,
    )
    want = 2.0 * fgf.c_const(hurst, 1) * sw * inner / t**2
    assert fgf.line_average_variance(hurst, sw, t) == pytest.approx(want, rel=1e-6)


def _spectral_point_variance(hurst: float, sw: float) -> float:
    """Anchored k-fBm variance at x = 1 from the spectrum S_w |ω|^(-2H-1):
    (S_w/π) ∫_0^∞ u^(-2H-1) |e^(iu) - Σ_{j<k} (iu)^j/j!|² du. Independent of
    C(H,d) and of the binomial closed form."""
    k = math.ceil(hurst)
    p = -2.0 * hurst - 1.0

    def remainder_sq(u):
        # Small u: the Taylor tail Σ_{j>=k} (iu)^j/j! avoids cancellation.
        if u < 2.0:
            re = im = 0.0
            for j in range(k, k + 40):
                term = u**j / math.factorial(j)
                r = j % 4
                if r == 0:
                    re += term
                elif r == 1:
                    im += term
                elif r == 2:
                    re -= term
                else:
                    im -= term
            return re * re + im * im
        a = sum((-1) ** (j // 2) * u**j / math.factorial(j) for j in range(0, k, 2))
        b = sum((-1) ** ((j - 1) // 2) * u**j / math.factorial(j) for j in range(1, k, 2))
        return (math.cos(u) - a) ** 2 + (math.sin(u) - b) ** 2

    big = 40.0
    head, _ = integrate.quad(lambda u: u**p * remainder_sq(u), 0.0, big, limit=2000,
                             epsabs=1e-13, epsrel=1e-12)
    # Tail, |R|² = 1 + A² + B² - 2 (A cos u + B sin u) with the Taylor parts
    # A (even j) and B (odd j): the smooth part in closed form, the
    # oscillatory part by QAWF (Fourier integrals of decaying powers).
    smooth = [(0, 1.0)]
    for i in range(k):
        for j in range(k):
            if (i + j) % 2 == 0:
                si = (-1) ** (i // 2) if i % 2 == 0 else (-1) ** ((i - 1) // 2)
                sj = (-1) ** (j // 2) if j % 2 == 0 else (-1) ** ((j - 1) // 2)
                smooth.append((i + j, si * sj / (math.factorial(i) * math.factorial(j))))
    tail = sum(-c * big ** (n + p + 1) / (n + p + 1) for n, c in smooth)
    for j in range(k):
        c = (-1) ** (j // 2) / math.factorial(j) if j % 2 == 0 else (-1) ** ((j - 1) // 2) / math.factorial(j)
        weight = "cos" if j % 2 == 0 else "sin"
        val, _ = integrate.quad(lambda u, j=j: u ** (j + p), big, np.inf, weight=weight, wvar=1.0)
        tail -= 2.0 * c * val
    return sw / math.pi * (head + tail)


@pytest.mark.parametrize("hurst", [0.2, 0.5, 0.85, 1.2, 1.8, 2.4])
def test_kfbm_variance_is_mean_spectral_point_variance(hurst):
    sw, length = 2.0, 1.7
    pv1 = _spectral_point_variance(hurst, sw)
    assert fgf.kfbm_point_variance(hurst, sw, 1.0) == pytest.approx(pv1, rel=1e-6)
    # Point variance scales as x^(2H) (self-similarity); mean over [0, L].
    mean, _ = integrate.quad(lambda x: pv1 * x ** (2 * hurst), 0.0, length, epsrel=1e-12)
    mean /= length
    got = fgf.line_average_variance(hurst, sw, 1.0, length=length)
    assert got == pytest.approx(mean, rel=1e-6)
    assert got == pytest.approx(fgf.s_kf(hurst, sw) * length ** (2 * hurst), rel=1e-12)


@pytest.mark.parametrize("hurst", [-0.45, -0.25, -0.1])
def test_c_const_is_the_fourier_transform_of_the_spectrum(hurst):
    # cov(1) = (S_w/π) ∫_0^∞ ω^(-2H-1) cos ω dω (QAWF on [1, ∞) + QUADPACK on [0, 1]).
    p = -2.0 * hurst - 1.0
    head, _ = integrate.quad(lambda w: w**p * math.cos(w), 0.0, 1.0, epsabs=1e-13)
    tail, _ = integrate.quad(lambda w: w**p, 1.0, np.inf, weight="cos", wvar=1.0)
    assert fgf.c_const(hurst, 1) == pytest.approx((head + tail) / math.pi, rel=1e-7)


def test_c_const_identities():
    assert fgf.c_const(0.5, 1) == pytest.approx(-0.5, rel=1e-14)
    for h in (-0.3, 0.2, 1.2):
        c1 = -1.0 / (2.0 * special.gamma(2 * h + 1) * math.sin(math.pi * h))
        assert fgf.c_const(h) == pytest.approx(c1, rel=1e-13)
        assert fgf.c_const(h, 3) == pytest.approx(c1 / (2 * math.pi * (2 * h + 1)), rel=1e-13)


def test_s_p_and_white_limit():
    h, sw = -0.1, 4.0
    assert fgf.s_p(h, sw) == pytest.approx(sw / (special.gamma(2 * h + 3) * abs(math.sin(math.pi * h))), rel=1e-13)
    assert fgf.s_p(-0.5, sw) == pytest.approx(sw, rel=1e-14)
    assert fgf.line_average_variance(-0.5, sw, 2.0) == pytest.approx(2.0, rel=1e-15)


def test_binom():
    assert fgf.binom(5.0, 2) == 10.0
    assert fgf.binom(-0.5, 3) == pytest.approx(special.binom(-0.5, 3), rel=1e-14)
    assert fgf.binom(1.4, 1) == pytest.approx(1.4)


def test_vectorised_variance():
    t = np.array([[0.5, 1.0], [2.0, 4.0]])
    v = fgf.line_average_variance(-0.1, 4.0, t)
    assert v.shape == (2, 2)
    assert v[0, 1] == pytest.approx(fgf.s_p(-0.1, 4.0))
    assert type(fgf.line_average_variance(-0.1, 4.0, 1.0)) is float


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: fgf.line_average_variance(0.0, 1.0, 1.0), "hurst"),
        (lambda: fgf.line_average_variance(-0.7, 1.0, 1.0), "hurst"),
        (lambda: fgf.line_average_variance(1.0, 1.0, 1.0, length=1.0), "hurst"),
        (lambda: fgf.line_average_variance(-0.1, 0.0, 1.0), "sw"),
        (lambda: fgf.line_average_variance(-0.1, 1.0, [1.0, 0.0]), "t"),
        (lambda: fgf.line_average_variance(-0.1, 1.0, -1.0), "t"),
        (lambda: fgf.line_average_variance(1.2, 1.0, 1.0), "length"),
        (lambda: fgf.line_average_variance(-0.1, 1.0, 1.0, length=2.0), "length"),
        (lambda: fgf.s_p(0.2, 1.0), "hurst"),
        (lambda: fgf.s_kf(-0.2, 1.0), "hurst"),
        (lambda: fgf.s_kf(1.2, -1.0), "sw"),
        (lambda: fgf.c_const(1.0), "hurst"),
        (lambda: fgf.kfbm_point_variance(-0.1, 1.0, 1.0), "hurst"),
    ],
)
def test_invalid_arguments(call, name):
    with pytest.raises(fgf.ParameterError, match=rf"invalid {name} = "):
        call()
