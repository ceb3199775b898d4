"""Python surface of the transmittance models: shapes and types,
the numerical identities through the binding, KS tests of the samplers,
equality with the Rust core (pinned values), and parameter errors."""

from __future__ import annotations

import csv
import pathlib

import numpy as np
import pytest
from scipy import integrate, stats

import fgf

PINNED = pathlib.Path(__file__).resolve().parents[1] / "crates/fgf-core/tests/data/pinned_values.csv"


def all_models():
    return {
        "exponential": fgf.Exponential(4.0),
        "white": fgf.Fgf(4.0, hurst=-0.5, sw=4.0),
        "pink": fgf.Fgf(sigma_t=4.0, hurst=-0.1, sw=4.0),
        "pink-0.4": fgf.Fgf(2.0, hurst=-0.4, sw=10.0),
        "1-fbm": fgf.Fgf(4.0, hurst=0.2, sw=4.0, length=1.0),
        "2-fbm": fgf.Fgf(sigma_t=4.0, hurst=1.2, sw=34.0, length=1.0),
        "davis": fgf.Davis(4.0, alpha=4.0),
        "davis-0.7": fgf.Davis(1.5, alpha=0.7),
        "dw": fgf.DavisWeinstein(4.0, h=0.9, c=0.78),
        "dw-0.5": fgf.DavisWeinstein(4.0, h=0.5, c=0.78),
    }


MODELS = all_models()
METHODS = ["tr", "pdf", "surface_surface", "surface_medium", "medium_surface", "medium_medium"]


# --- API shape ------------------------------------------------------------


@pytest.mark.parametrize("name", MODELS)
def test_methods_keep_shape_and_scalars_give_floats(name):
    m = MODELS[name]
    t = np.linspace(0.0, 3.0, 12).reshape(3, 4)
    for meth in METHODS:
        out = getattr(m, meth)(t)
        assert isinstance(out, np.ndarray) and out.shape == (3, 4) and out.dtype == np.float64
        s = getattr(m, meth)(0.5)
        assert type(s) is float
        assert getattr(m, meth)(np.float32(0.5)) == pytest.approx(s, rel=1e-7)
    u = np.random.default_rng(0).random((2, 5))
    for meth in ("sample_surface", "sample_medium"):
        out = getattr(m, meth)(u)
        assert out.shape == (2, 5)
        assert type(getattr(m, meth)(0.5)) is float
    assert getattr(m, "tr")([0.0, 1.0]).shape == (2,)
    assert m.tr(np.empty(0)).shape == (0,)
    assert isinstance(m.sigma_bar, float)


def test_issue_example_runs():
    m = fgf.Fgf(sigma_t=4.0, hurst=-0.1, sw=4.0)
    t = np.linspace(0, 3, 1000)
    for a in (m.variance(t), m.alpha(t), m.tr(t), m.pdf(t), m.surface_surface(t),
              m.surface_medium(t), m.medium_surface(t), m.medium_medium(t)):
        assert a.shape == t.shape
    d = m.sample_surface(np.random.default_rng(0).random(10**6))
    assert d.shape == (10**6,) and np.all(np.isfinite(d)) and np.all(d >= 0)
    assert m.sigma_bar == 4.0
    assert m.regime == "pink" and m.k == 0 and m.length is None


def test_large_arrays_match_small_arrays():
    # Arrays above the GIL-release threshold go through the same code.
    m = MODELS["pink"]
    t = np.linspace(0.0, 3.0, 20001)
    big = m.tr(t)
    small = np.array([m.tr(x) for x in t[::1000]])
    assert np.array_equal(big[::1000], small)


def test_non_contiguous_and_integer_input():
    m = MODELS["davis"]
    t = np.linspace(0.0, 2.0, 20)[::3]
    assert np.array_equal(m.tr(t), m.tr(t.copy()))
    assert m.tr(1) == m.tr(1.0)


# --- numerical identities through the binding ---------------------------------


@pytest.mark.parametrize("name", MODELS)
def test_tr_one_at_zero_monotone_and_pdf_at_zero(name):
    m = MODELS[name]
    assert m.tr(0.0) == 1.0
    t = np.linspace(0.0, 10.0 / m.sigma_t, 5001)
    assert np.all(np.diff(m.tr(t)) <= 0.0)
    assert m.pdf(0.0) == pytest.approx(m.sigma_bar, rel=1e-15)
    if name not in ("white", "dw-0.5"):
        assert m.pdf(0.0) == pytest.approx(m.sigma_t, rel=1e-15)
    assert m.tr(np.inf) == 0.0 and m.pdf(np.inf) == 0.0


@pytest.mark.parametrize("name", MODELS)
def test_pdfs_integrate_to_one(name):
    # scipy's QUADPACK (independent of the Rust quadrature); T_mm's t^(2H)
    # singularity at 0 is integrable and handled by quad's extrapolation.
    m = MODELS[name]
    i_sm = integrate.quad(m.pdf, 0, np.inf, limit=500, epsabs=1e-11, epsrel=1e-11)[0]
    split = 1.0 / m.sigma_t
    i_mm = (integrate.quad(m.medium_medium, 0, split, limit=500, epsabs=1e-11)[0]
            + integrate.quad(m.medium_medium, split, np.inf, limit=500, epsabs=1e-11)[0])
    assert i_sm == pytest.approx(1.0, abs=1e-7)
    assert i_mm == pytest.approx(1.0, abs=1e-7)


@pytest.mark.parametrize("name", MODELS)
def test_derivative_identities(name):
    # Five-point differences, h = 1e-3 t: error ~1e-12 (see the Rust test).
    m = MODELS[name]
    t = np.array([1e-3, 0.05, 0.3, 1.0, 4.0]) / m.sigma_t
    h = 1e-3 * t

    def d(f):
        return (f(t - 2 * h) - 8 * f(t - h) + 8 * f(t + h) - f(t + 2 * h)) / (12 * h)

    np.testing.assert_allclose(m.surface_medium(t), -d(m.tr), rtol=1e-7)
    np.testing.assert_allclose(m.medium_surface(t), m.surface_medium(t) / m.sigma_bar, rtol=1e-14)
    np.testing.assert_allclose(m.medium_medium(t), -d(m.medium_surface), rtol=1e-7)


def test_white_noise_is_exponential_with_sigma_eff():
    sigma, sw = 4.0, 4.0
    sigma_eff = sigma**2 / sw * np.log1p(sw / sigma)
    m = fgf.Fgf(sigma, hurst=-0.5, sw=sw)
    t = np.linspace(0, 2, 50)
    np.testing.assert_allclose(m.tr(t), np.exp(-sigma_eff * t), rtol=1e-14)
    assert m.sigma_bar == pytest.approx(sigma_eff, rel=1e-15)


def test_alpha_to_infinity_is_exponential():
    t = np.linspace(0, 2, 50)
    np.testing.assert_allclose(fgf.Davis(3.0, alpha=1e14).tr(t), np.exp(-3.0 * t), rtol=1e-10)
    assert fgf.Davis(3.0, alpha=1e-12).tr(5.0) == pytest.approx(1.0, abs=1e-10)


def test_davis_equivalence():
    m = fgf.Fgf(sigma_t=4.0, hurst=1.2, sw=34.0, length=1.0)
    alpha = 16.0 / fgf.line_average_variance(1.2, 34.0, 1.0, length=1.0)
    d = fgf.Davis(4.0, alpha=alpha)
    assert isinstance(m.to_davis(), fgf.Davis)
    assert m.to_davis().alpha == pytest.approx(alpha, rel=1e-14)
    t = np.linspace(0, 5, 200)
    for meth in METHODS:
        np.testing.assert_allclose(getattr(m, meth)(t), getattr(d, meth)(t), rtol=1e-10)
    np.testing.assert_allclose(m.tr(t), (1 + 4.0 * t / alpha) ** -alpha, rtol=1e-10)


def test_davis_weinstein_equivalence():
    m = fgf.Fgf(sigma_t=4.0, hurst=-0.1, sw=4.0)
    c = fgf.s_p(-0.1, 4.0) ** (1 / 1.8) / 4.0
    dw = fgf.DavisWeinstein(4.0, h=0.9, c=c)
    mapped = m.to_davis_weinstein()
    assert isinstance(mapped, fgf.DavisWeinstein)
    assert mapped.h == pytest.approx(0.9) and mapped.c == pytest.approx(c, rel=1e-13)
    t = np.linspace(1e-4, 5, 200)
    for meth in METHODS:
        np.testing.assert_allclose(getattr(m, meth)(t), getattr(dw, meth)(t), rtol=1e-10)
    # Independent formula in optical depth (Bitterli 2018).
    tau = 4.0 * t
    alpha = tau ** (2 - 2 * 0.9) / c ** (2 * 0.9)
    np.testing.assert_allclose(m.tr(t), (1 + tau / alpha) ** -alpha, rtol=1e-10)
    np.testing.assert_allclose(m.alpha(t), alpha, rtol=1e-10)


# --- samplers ----------------------------------------------------------------

# Each KS test rejects at p < 1e-4; 2 samplers x 10 models = 20 tests, so the
# family-wise false-alarm rate is at most 0.2% (Bonferroni). Fixed seeds.
KS_P = 1e-4


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("start", ["surface", "medium"])
def test_samplers_ks(name, start):
    m = MODELS[name]
    rng = np.random.default_rng(list(MODELS).index(name) * 2 + (start == "medium"))
    u = rng.random(50_000)
    if start == "surface":
        x, cdf = m.sample_surface(u), lambda t: 1.0 - m.tr(t)
    else:
        x, cdf = m.sample_medium(u), lambda t: 1.0 - m.medium_surface(t)
    assert np.all(np.isfinite(x)) and np.all(x >= 0)
    assert stats.kstest(x, cdf).pvalue > KS_P


@pytest.mark.parametrize("name", MODELS)
def test_samplers_invert_cdfs(name):
    m = MODELS[name]
    u = np.linspace(0.0, 0.999, 400)
    y = -np.log1p(-u)
    tol = 1e-11 * y + 4 * np.finfo(float).eps
    assert np.all(np.abs(-np.log(m.tr(m.sample_surface(u))) - y) <= tol)
    assert np.all(np.abs(-np.log(m.medium_surface(m.sample_medium(u))) - y) <= tol)


@pytest.mark.parametrize("bad", [-0.1, 1.0, 1.5, np.nan])
def test_sampler_rejects_bad_variates(bad):
    with pytest.raises(fgf.ParameterError, match="u"):
        MODELS["pink"].sample_surface(np.array([0.5, bad]))


# --- Python == Rust ----------------------------------------------------------


def _pinned_rows():
    with open(PINNED) as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    return [r for r in rows if r]


def test_pinned_values_equal_rust():
    rows = _pinned_rows()
    assert len(rows) == 19
    for kind, sigma, p1, p2, p3, fn, x, want in rows:
        sigma = float(sigma)
        if kind == "fgf":
            m = fgf.Fgf(sigma, hurst=float(p1), sw=float(p2), length=float(p3) if p3 else None)
        elif kind == "davis":
            m = fgf.Davis(sigma, alpha=float(p1))
        elif kind == "davis_weinstein":
            m = fgf.DavisWeinstein(sigma, h=float(p1), c=float(p2))
        else:
            m = fgf.Exponential(sigma)
        got = getattr(m, fn)(float(x))
        assert got == float(want), (kind, fn, x, got, want)


# --- parameter errors ---------------------------------------------------------


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: fgf.Exponential(0.0), "sigma_t"),
        (lambda: fgf.Exponential(-1.0), "sigma_t"),
        (lambda: fgf.Exponential(np.inf), "sigma_t"),
        (lambda: fgf.Fgf(np.nan, hurst=-0.1, sw=1.0), "sigma_t"),
        (lambda: fgf.Fgf(1.0, hurst=0.0, sw=1.0), "hurst"),
        (lambda: fgf.Fgf(1.0, hurst=1.0, sw=1.0, length=1.0), "hurst"),
        (lambda: fgf.Fgf(1.0, hurst=2.0, sw=1.0, length=1.0), "hurst"),
        (lambda: fgf.Fgf(1.0, hurst=-0.6, sw=1.0), "hurst"),
        (lambda: fgf.Fgf(1.0, hurst=np.nan, sw=1.0), "hurst"),
        (lambda: fgf.Fgf(1.0, hurst=-0.1, sw=0.0), "sw"),
        (lambda: fgf.Fgf(1.0, hurst=-0.1, sw=-2.0), "sw"),
        (lambda: fgf.Fgf(1.0, hurst=-0.1, sw=np.inf), "sw"),
        (lambda: fgf.Fgf(1.0, hurst=1.2, sw=1.0), "length"),
        (lambda: fgf.Fgf(1.0, hurst=1.2, sw=1.0, length=0.0), "length"),
        (lambda: fgf.Fgf(1.0, hurst=1.2, sw=1.0, length=-1.0), "length"),
        (lambda: fgf.Fgf(1.0, hurst=1.2, sw=1.0, length=np.inf), "length"),
        (lambda: fgf.Fgf(1.0, hurst=-0.1, sw=1.0, length=1.0), "length"),
        (lambda: fgf.Davis(1.0, alpha=0.0), "alpha"),
        (lambda: fgf.Davis(1.0, alpha=-1.0), "alpha"),
        (lambda: fgf.Davis(1.0, alpha=np.nan), "alpha"),
        (lambda: fgf.Davis(0.0, alpha=1.0), "sigma_t"),
        (lambda: fgf.DavisWeinstein(1.0, h=0.4, c=1.0), "h"),
        (lambda: fgf.DavisWeinstein(1.0, h=1.1, c=1.0), "h"),
        (lambda: fgf.DavisWeinstein(1.0, h=np.nan, c=1.0), "h"),
        (lambda: fgf.DavisWeinstein(1.0, h=0.8, c=0.0), "c"),
        (lambda: fgf.DavisWeinstein(1.0, h=0.8, c=-1.0), "c"),
        (lambda: fgf.DavisWeinstein(-1.0, h=0.8, c=1.0), "sigma_t"),
    ],
)
def test_invalid_parameters_raise_parameter_error(make, name):
    with pytest.raises(fgf.ParameterError, match=rf"invalid {name} = .*valid:"):
        make()


def test_parameter_error_is_a_value_error():
    assert issubclass(fgf.ParameterError, ValueError)
    with pytest.raises(ValueError):
        fgf.Fgf(1.0, hurst=0.0, sw=1.0)


def test_keyword_only_parameters():
    with pytest.raises(TypeError):
        fgf.Fgf(4.0, -0.1, 4.0)  # hurst and sw are keyword-only
    with pytest.raises(TypeError):
        fgf.Davis(4.0, 4.0)


def test_mappings_refuse_wrong_regime():
    with pytest.raises(fgf.ParameterError):
        fgf.Fgf(1.0, hurst=-0.1, sw=1.0).to_davis()
    with pytest.raises(fgf.ParameterError):
        fgf.Fgf(1.0, hurst=1.2, sw=1.0, length=1.0).to_davis_weinstein()


def test_repr_round_trips():
    for m in MODELS.values():
        again = eval(repr(m), {"Fgf": fgf.Fgf, "Davis": fgf.Davis,
                               "DavisWeinstein": fgf.DavisWeinstein, "Exponential": fgf.Exponential})
        assert again.params == m.params


def test_docstring_examples_run():
    import doctest

    import fgf.transmittance as mod

    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 10
    assert result.failed == 0


def test_models_pickle():
    import pickle

    for m in MODELS.values():
        again = pickle.loads(pickle.dumps(m))
        assert type(again) is type(m) and again.params == m.params
        assert again.tr(0.37) == m.tr(0.37)
