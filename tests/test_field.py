"""Field synthesis, exact samplers, estimators, exports and ``fgf field``: fast tests.

The statistical ensemble tests are in ``test_field_stats.py`` (slow step).
"""

from __future__ import annotations

import doctest
import os
import subprocess
import sys

import numpy as np
import pytest

import fgf
import fgf.field


def test_docstring_examples_run():
    res = doctest.testmod(fgf.field, optionflags=doctest.ELLIPSIS)
    assert res.attempted > 5 and res.failed == 0


@pytest.mark.parametrize(
    "shape,hurst",
    [((100,), -0.3), ((37, 50), -0.6), ((12, 10, 9), -1.2), ((31,), 0.4), ((20, 21), 1.6), ((9, 8, 7), 2.3)],
)
def test_shapes_dtypes_and_determinism(shape, hurst):
    a = fgf.synthesize(shape, hurst=hurst, seed=4, progress=False)
    assert a.shape == shape and a.dtype == np.float32 and a.flags.c_contiguous
    assert np.all(np.isfinite(a))
    b = fgf.synthesize(shape, hurst=hurst, seed=4, progress=False)
    assert np.array_equal(a, b)
    c = fgf.synthesize(shape, hurst=hurst, seed=5, progress=False)
    assert not np.array_equal(a, c)
    d = fgf.synthesize(shape, hurst=hurst, seed=4, dtype=np.float64, progress=False)
    assert d.dtype == np.float64
    np.testing.assert_allclose(a, d, rtol=0, atol=1e-5 * np.abs(d).max())


def _digest_in_subprocess(threads: int) -> str:
    code = (
        "import fgf, hashlib;"
        "f = fgf.synthesize((24, 30, 33), hurst=1.4, seed=9, anchor='center', progress=False);"
        "g = fgf.synthesize((64, 50), hurst=-0.4, seed=9, progress=False);"
        "t = fgf.sample_optical_depth(7, 40, 1.0, -0.2, seed=9, progress=False);"
        "print(hashlib.sha256(f.tobytes() + g.tobytes() + t.tobytes()).hexdigest())"
    )
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    return subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True, text=True).stdout


def test_bit_identical_for_any_thread_count():
    assert _digest_in_subprocess(1) == _digest_in_subprocess(2) == _digest_in_subprocess(3)


def _taylor_numpy(g: np.ndarray, anchor, k: int, spacing: float) -> np.ndarray:
    """Taylor polynomial of degree k-1 at `anchor` of the trigonometric
    interpolant of the periodic array `g`, derivatives by numpy FFT."""
    d = g.ndim
    spec = np.fft.fftn(g) / g.size
    ks = np.meshgrid(*[2 * np.pi * np.fft.fftfreq(n, d=spacing) for n in g.shape], indexing="ij")
    phase = np.exp(1j * sum(kk * a * spacing for kk, a in zip(ks, anchor)))
    coords = np.meshgrid(*[(np.arange(n) - a) * spacing for n, a in zip(g.shape, anchor)], indexing="ij")
    poly = np.zeros(g.shape)
    import itertools
    from math import factorial

    for alpha in itertools.product(range(k), repeat=d):
        if sum(alpha) >= k:
            continue
        mono = np.ones(g.shape, dtype=complex)
        for kk, a in zip(ks, alpha):
            mono = mono * (1j * kk) ** a
        deriv = np.real(np.sum(spec * mono * phase))
        term = np.full(g.shape, deriv)
        for x, a in zip(coords, alpha):
            term = term * x**a / factorial(a)
        poly += term
    return poly


@pytest.mark.parametrize(
    "shape,hurst,anchor",
    [((64,), 0.7, "corner"), ((30, 36), 1.5, "center"), ((12, 14, 16), 2.5, (3, 7, 11)), ((40, 33), 2.2, "corner")],
)
def test_anchoring_subtracts_the_spectral_taylor_polynomial(shape, hurst, anchor):
    # padding=1: the output is the whole periodic domain, so numpy can take
    # the spectral derivatives of the unanchored field independently.
    kw = dict(hurst=hurst, seed=2, spacing=0.05, padding=1.0, dtype=np.float64, progress=False)
    g = fgf.synthesize(shape, anchor=None, **kw)
    f = fgf.synthesize(shape, anchor=anchor, **kw)
    a = {"corner": (0,) * len(shape), "center": tuple(n // 2 for n in shape)}.get(anchor, anchor)
    k = int(np.ceil(hurst))
    poly = _taylor_numpy(g, a, k, 0.05)
    scale = np.abs(g).max()
    np.testing.assert_allclose(g - f, poly, rtol=0, atol=1e-9 * scale)
    assert abs(f[a]) < 1e-12 * scale
    # g - f equals the Taylor polynomial of g's interpolant at the anchor, so
    # f's interpolant and its derivatives up to order k-1 vanish there.


def test_padded_kfbm_vanishes_at_anchor_and_is_cropped():
    f = fgf.synthesize((50, 40), hurst=1.3, seed=1, anchor=(10, 5), dtype=np.float64, progress=False)
    assert f.shape == (50, 40)
    assert abs(f[10, 5]) < 1e-12 * np.abs(f).max()
    assert fgf.padded_shape((50, 40), hurst=1.3) == (100, 80)
    assert fgf.padded_shape((50, 40), hurst=1.3, padding=1.5) == (75, 60)
    assert fgf.padded_shape((50, 40), hurst=-0.3) == (50, 40)


def test_white_noise_variance_is_sw_over_cell_volume():
    # s = 0: every mode but k = 0 has weight 1, var = S_w/dx^d (N-1)/N.
    v = fgf.discrete_spectral_variance((16, 16), hurst=-1.0, sw=2.0, spacing=0.5)
    assert v == pytest.approx(2.0 / 0.25 * 255 / 256, rel=1e-12)


def test_discrete_spectral_variance_matches_a_numpy_sum():
    shape, h, sw, dx = (12, 10, 9), -0.4, 1.7, 0.1
    s = h + 1.5
    ks = np.meshgrid(*[2 * np.pi * np.fft.fftfreq(n, d=dx) for n in shape], indexing="ij")
    k2 = sum(k**2 for k in ks)
    k2[0, 0, 0] = np.inf
    want = sw / dx**3 * np.sum(k2 ** (-s)) / np.prod(shape)
    assert fgf.discrete_spectral_variance(shape, h, sw=sw, spacing=dx) == pytest.approx(want, rel=1e-12)


def test_sw_3d_matching_gives_the_1d_covariance_constant():
    from scipy.special import gamma

    h = -0.3

    def c_const(d):
        return gamma(-h) / (2 ** (2 * h + d) * np.pi ** (d / 2) * gamma(h + d / 2))

    sw3 = fgf.sw_3d_for_ray_statistics(h, 1.0)
    assert c_const(3) * sw3 == pytest.approx(c_const(1), rel=1e-12)


@pytest.mark.parametrize(
    "call,name",
    [
        (lambda: fgf.synthesize((8, 8), hurst=-1.5), "hurst"),
        (lambda: fgf.synthesize((8, 8), hurst=1.0), "hurst"),
        (lambda: fgf.synthesize((8, 8), hurst=3.2), "hurst"),
        (lambda: fgf.synthesize((8, 8), hurst=0.5, sw=-1), "sw"),
        (lambda: fgf.synthesize((8, 8), hurst=0.5, spacing=0), "spacing"),
        (lambda: fgf.synthesize((8, 8, 8, 8), hurst=0.5), "shape"),
        (lambda: fgf.synthesize((8, 8), hurst=0.5, padding=0.9), "padding"),
        (lambda: fgf.synthesize((8, 8), hurst=0.5, anchor=(9, 0)), "anchor"),
        (lambda: fgf.synthesize((8, 8), hurst=0.5, anchor="middle"), "anchor"),
        (lambda: fgf.synthesize((8, 8), hurst=0.5, dtype=np.int32), "dtype"),
        (lambda: fgf.sample_optical_depth(10, 10, 1.0, hurst=0.5), "hurst"),
        (lambda: fgf.sample_optical_depth(10, 10, -1.0, hurst=-0.2), "t_max"),
        (lambda: fgf.sample_kfbm_1d(10, 10, 1.0, hurst=-0.2), "hurst"),
        (lambda: fgf.sample_kfbm_1d(10, 5000, 1.0, hurst=0.2), "n_steps"),
        (lambda: fgf.sw_3d_for_ray_statistics(-0.7, 1.0), "hurst"),
        (lambda: fgf.variogram(np.zeros((4, 4)), axis=1, max_lag=4), "max_lag"),
    ],
)
def test_invalid_parameters_raise_parameter_error(call, name):
    with pytest.raises(fgf.ParameterError, match=name):
        call()


def test_impossible_request_is_refused_before_allocating():
    with pytest.raises(fgf.FgfError, match="MemAvailable"):
        fgf.synthesize((5000, 5000, 5000), hurst=-0.2, progress=False)


def test_exact_samplers_shapes_and_anchor():
    tau = fgf.sample_optical_depth(n_rays=5, n_steps=20, t_max=3.0, hurst=-0.3, sw=0.3, seed=0, progress=False)
    assert tau.shape == (5, 21) and np.all(tau[:, 0] == 0)
    w = fgf.sample_optical_depth(n_rays=4, n_steps=20, t_max=3.0, hurst=-0.5, seed=0, progress=False)
    assert np.all(np.isfinite(w))
    m = fgf.sample_kfbm_1d(n_samples=4, n_steps=30, length=2.0, hurst=2.5, seed=0, progress=False)
    assert m.shape == (4, 31) and np.all(m[:, 0] == 0)


def test_estimators_on_known_signals():
    x = np.arange(10.0)
    assert fgf.variogram(np.tile(x, (3, 1)), axis=1, max_lag=3).tolist() == [0.0, 0.5, 2.0, 4.5]
    cov = fgf.covariance(np.tile(x, (3, 1)), axis=0, max_lag=2)
    np.testing.assert_allclose(cov, np.var(x))
    sig = np.where(np.arange(12) % 2 == 0, 1.0, -1.0)
    np.testing.assert_allclose(fgf.line_average_second_moment(sig, [1, 2, 4]), [1.0, 0.0, 0.0])
    n, dx = 32, 0.25
    yy, xx = np.mgrid[0:n, 0:n]
    f = np.cos(2 * np.pi * 4 * xx / n)
    k, p, c = fgf.radial_power_spectrum(f, spacing=dx, n_bins=24)
    # The peak bin holds |k| = 2 pi 4/(n dx); its mean |k| is within the
    # bin's relative width ln(16)/24 < 12%.
    assert k[np.argmax(p)] == pytest.approx(2 * np.pi * 4 / (n * dx), rel=0.12)
    # Parseval: sum of I(k) dk^2/(2 pi)^2 over modes = mean f^2 = 1/2.
    assert np.sum(p * c) / (n * dx) ** 2 == pytest.approx(0.5)


# --- exports --------------------------------------------------------------


def test_npy_round_trip_keeps_dtype_and_values(tmp_path):
    f = fgf.synthesize((5, 6, 7), hurst=-0.2, seed=1, dtype=np.float64, progress=False)
    fgf.save_field(tmp_path / "f.npy", f)
    g = np.load(tmp_path / "f.npy")
    assert g.dtype == np.float64 and np.array_equal(f, g)
    fgf.save_field(tmp_path / "d.npy", f.astype(np.float32), mean=2.0, scale=0.5, clamp_min=1.9)
    np.testing.assert_allclose(np.load(tmp_path / "d.npy"), np.maximum(1.9, 2.0 + 0.5 * f).astype(np.float32), rtol=1e-6)


def _read_vol(path):
    b = open(path, "rb").read()
    assert b[:3] == b"VOL" and b[3] == 3
    enc, nx, ny, nz, ch = np.frombuffer(b[4:24], "<i4")
    bbox = np.frombuffer(b[24:48], "<f4")
    data = np.frombuffer(b[48:], "<f4").reshape(nz, ny, nx, ch)
    return (enc, ch), bbox, data


def test_vol_round_trip_byte_layout(tmp_path):
    f = fgf.synthesize((4, 5, 6), hurst=-0.3, seed=2, progress=False)
    s = fgf.save_field(tmp_path / "f.vol", f, spacing=0.5, mean=3.0, clamp_min=0.0)
    assert s["format"] == "vol" and s["n_negative"] == 0
    (enc, ch), bbox, data = _read_vol(tmp_path / "f.vol")
    assert (enc, ch) == (1, 1)
    np.testing.assert_array_equal(bbox, [0, 0, 0, 3.0, 2.5, 2.0])
    np.testing.assert_array_equal(data[..., 0], np.maximum(0.0, 3.0 + f.astype(np.float64)).astype(np.float32))


def test_mitsuba_reads_our_vol_with_the_same_values(tmp_path):
    mi = pytest.importorskip("mitsuba", reason="mitsuba is a test dependency (requirements-dev)")
    mi.set_variant("scalar_rgb")
    f = fgf.synthesize((6, 7, 9), hurst=-0.2, seed=3, progress=False)
    path = str(tmp_path / "f.vol")
    fgf.save_field(path, f, spacing=0.1, mean=3.0)
    nz, ny, nx = f.shape
    for filt in ("nearest", "trilinear"):
        vol = mi.load_dict({"type": "gridvolume", "filename": path, "filter_type": filt, "raw": True})
        it = mi.Interaction3f()
        for z, y, x in [(0, 0, 0), (5, 6, 8), (2, 3, 4), (4, 1, 7)]:
            # gridvolume maps the grid to the unit cube; voxel centres at (i + 1/2)/n.
            it.p = mi.Point3f((x + 0.5) / nx, (y + 0.5) / ny, (z + 0.5) / nz)
            assert vol.eval_1(it) == pytest.approx(3.0 + float(f[z, y, x]), rel=1e-6), (filt, z, y, x)


def test_exr_and_png_for_2d(tmp_path):
    mi = pytest.importorskip("mitsuba", reason="mitsuba is a test dependency (requirements-dev)")
    mi.set_variant("scalar_rgb")
    f = fgf.synthesize((40, 60), hurst=0.6, seed=1, progress=False)
    fgf.save_field(tmp_path / "f.exr", f)
    img = np.array(mi.Bitmap(str(tmp_path / "f.exr")), dtype=np.float32)
    np.testing.assert_array_equal(img.reshape(40, 60), f)
    fgf.save_field(tmp_path / "f.png", f)
    import matplotlib.image

    png = matplotlib.image.imread(tmp_path / "f.png")
    assert png.shape == (40, 60)
    lo, hi = np.percentile(f.astype(np.float64), [0.5, 99.5])
    want = np.clip(np.round((f - lo) / (hi - lo) * 255), 0, 255) / 255
    np.testing.assert_allclose(png, want, atol=1 / 255 + 1e-6)


def test_bad_exports_are_errors_and_leave_no_file(tmp_path):
    with pytest.raises(fgf.FgfError, match="2D"):
        fgf.save_field(tmp_path / "f.png", np.zeros((2, 2, 2), np.float32))
    with pytest.raises(fgf.FgfError, match="extension"):
        fgf.save_field(tmp_path / "f.tiff", np.zeros((2, 2), np.float32))
    with pytest.raises((OSError, fgf.FgfError), match="does not exist"):
        fgf.save_field(tmp_path / "missing" / "f.npy", np.zeros((2, 2), np.float32))
    assert list(tmp_path.iterdir()) == []


# --- CLI ------------------------------------------------------------------


def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "fgf", "field", *args], capture_output=True, text=True, cwd=cwd)


def test_cli_writes_every_format(tmp_path):
    r = _cli("--shape", "64", "48", "--hurst", "0.85", "--seed", "1", "-o", str(tmp_path / "f.png"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "f.png").stat().st_size > 100
    r = _cli("--shape", "64", "48", "--hurst", "0.85", "--seed", "1", "-q", "-o", str(tmp_path / "f.npy"))
    assert r.returncode == 0 and r.stderr == ""
    np.testing.assert_array_equal(np.load(tmp_path / "f.npy"), fgf.synthesize((64, 48), hurst=0.85, seed=1, progress=False))
    r = _cli("--shape", "8", "9", "10", "--hurst", "-0.1", "--mean", "4", "--clamp-min", "0", "-q", "-o", str(tmp_path / "f.vol"))
    assert r.returncode == 0, r.stderr
    _, _, data = _read_vol(tmp_path / "f.vol")
    assert data.shape == (8, 9, 10, 1) and data.min() >= 0
    r = _cli("--shape", "32", "32", "--hurst", "-0.4", "-q", "-o", str(tmp_path / "f.exr"))
    assert r.returncode == 0 and (tmp_path / "f.exr").exists()


@pytest.mark.parametrize(
    "args,msg",
    [
        (["--shape", "8", "8", "--hurst", "0.5", "-o", "f.tif"], "extension"),
        (["--shape", "8", "8", "8", "--hurst", "0.5", "-o", "f.png"], "2D"),
        (["--shape", "8", "8", "--hurst", "2.0", "-o", "f.npy"], "hurst"),
        (["--shape", "8", "8", "--hurst", "0.5", "--anchor", "x", "-o", "f.npy"], "anchor"),
        (["--shape", "5000", "5000", "5000", "--hurst", "-0.2", "-o", "f.npy"], "MemAvailable"),
    ],
)
def test_cli_errors_are_one_line_exit_2(tmp_path, args, msg):
    r = _cli(*args, cwd=tmp_path)
    assert r.returncode == 2
    assert msg in r.stderr and "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_cli_warns_about_negative_density(tmp_path):
    r = _cli("--shape", "8", "8", "8", "--hurst", "-0.1", "-o", str(tmp_path / "f.vol"))
    assert r.returncode == 0 and "negative" in r.stderr


def test_progress_callback_is_called_and_its_error_cancels_the_job():
    calls = []
    fgf.synthesize((64, 64, 64), hurst=-0.2, progress=lambda done, total: calls.append((done, total)))
    assert calls and calls[-1][0] == calls[-1][1]  # the last report is complete

    def stop(done, total):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        fgf.synthesize((160, 160, 160), hurst=-0.2, progress=stop)
