//! Fitted starting points of the pink-noise samplers (`docs/theory.md` §7):
//! Chebyshev interpolants of the root, made once per model at construction
//! and evaluated by Estrin's scheme, so that a typical sample needs a single
//! evaluation of its equation. They only move the start of the safeguarded
//! iteration ([`solve_increasing`]), never its result's accuracy.

use super::kernels::pink_terms;
use super::solver::solve_increasing;

/// Power-basis coefficients of `Σ c_k T_k(ξ)` (`T_k` the Chebyshev
/// polynomials), by the recurrence `T_k = 2 ξ T_(k-1) - T_(k-2)`.
fn cheb_to_power<const N: usize>(c: &[f64; N]) -> [f64; N] {
    let mut p = [0.0; N];
    let mut t_prev = [0.0; N];
    let mut t_cur = [0.0; N];
    t_prev[0] = 1.0; // T_0
    p[0] = c[0];
    if N < 2 {
        return p;
    }
    t_cur[1] = 1.0; // T_1
    for i in 0..N {
        p[i] += c[1] * t_cur[i];
    }
    for ck in c.iter().skip(2) {
        let mut t_next = [0.0; N];
        for i in 0..N {
            let shifted = if i > 0 { 2.0 * t_cur[i - 1] } else { 0.0 };
            t_next[i] = shifted - t_prev[i];
        }
        for i in 0..N {
            p[i] += ck * t_next[i];
        }
        t_prev = t_cur;
        t_cur = t_next;
    }
    p
}

/// Chebyshev coefficients `c_k` (with `c_0` halved) of the interpolant
/// through `d_j = f(cos(π (j + 1/2) / N))`.
fn cheb_coefficients<const N: usize>(d: &[f64; N]) -> [f64; N] {
    let n = N as f64;
    let mut c = [0.0; N];
    for (k, ck) in c.iter_mut().enumerate() {
        let mut sum = 0.0;
        for (j, dj) in d.iter().enumerate() {
            sum += dj * (std::f64::consts::PI * k as f64 * (j as f64 + 0.5) / n).cos();
        }
        *ck = 2.0 * sum / n;
    }
    c[0] *= 0.5;
    c
}

/// `Σ p_i ξ^i` for `N = 12` or `14` coefficients by Estrin's scheme: pairs
/// `p_i + p_(i+1) ξ`, then pairs of those with `ξ²`, `ξ⁴` and `ξ⁸` (an
/// unpaired last term is carried up as it is), a dependency depth of 4
/// instead of Horner's chain of `N`. Written out for the two sizes the fits
/// use, so that it compiles to straight-line code.
#[inline]
fn estrin<const N: usize>(p: &[f64; N], xi: f64) -> f64 {
    const { assert!(N == 12 || N == 14) };
    let x2 = xi * xi;
    let x4 = x2 * x2;
    let x8 = x4 * x4;
    let q = |i: usize| p[i] + p[i + 1] * xi;
    let r0 = q(0) + q(2) * x2;
    let r1 = q(4) + q(6) * x2;
    let r2 = q(8) + q(10) * x2;
    let high = if N == 14 { r2 + q(12) * x4 } else { r2 };
    (r0 + r1 * x4) + high * x8
}

/// Number of Chebyshev coefficients of [`StartGuess`] (see [`estrin`]).
const GUESS_N: usize = 14;

/// Starting point of the pink surface sampler: a Chebyshev interpolant of
/// `D(z) = s* - s_lo`, the distance in `ln t` from the exponential guess
/// `s_lo = ln(y/σ)` to the root, as a function of `z = ln x(e^s_lo)`. It
/// depends on `e` only, and is fitted at construction on the window of `z`
/// that `u ∈ [1e-3, 1 - 1e-3]` reaches, `z_c + [-8, 3]` with
/// `z_c = ln k - e ln σ` (14 nodes; the error is ≲ 1e-3 for `e ≲ 0.9`).
/// With it most samples need a single evaluation: the first step is then
/// below [`SURFACE_TOL`](super::SURFACE_TOL). Outside the window, the sampler starts at `s_lo`.
/// It only moves the start: the safeguarded iteration decides the result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StartGuess {
    mid: f64,
    inv_half: f64,
    /// Power-basis coefficients in `ξ = (z - mid) / half ∈ [-1, 1]`.
    p: [f64; GUESS_N],
}

impl StartGuess {
    /// No fit (white noise, k-fBm, exponential, or a failed fit): `eval`
    /// sees `ξ = ±inf` or NaN (`0 · inf`) and returns `None`. A sentinel
    /// instead of an `Option` saves the 8-byte tag (see
    /// `models_are_copy_and_small`); not NaN, so `PartialEq` stays reflexive.
    pub(crate) const NONE: StartGuess = StartGuess {
        mid: 0.0,
        inv_half: f64::INFINITY,
        p: [0.0; GUESS_N],
    };

    pub(crate) fn new(e: f64, z_c: f64) -> Option<Self> {
        if !(e > 0.0 && e < 1.0 && z_c.is_finite()) {
            return None;
        }
        let (za, zb) = (z_c - 8.0, z_c + 3.0);
        let mid = 0.5 * (za + zb);
        let half = 0.5 * (zb - za);
        let n = GUESS_N as f64;
        let mut d = [0.0; GUESS_N];
        for (j, dj) in d.iter_mut().enumerate() {
            let z = mid + half * (std::f64::consts::PI * (j as f64 + 0.5) / n).cos();
            // φ(D) = D + ln g(x_lo e^(e D)): φ(0) = ln g(x_lo) ≤ 0, φ' ≥ 1-e.
            let phi = |dd: f64| -> [f64; 4] {
                let (ln_g, a, b, xdb) = pink_terms(z + e * dd);
                [dd + ln_g, (1.0 - e) + e * a, e * e * b, e * e * e * xdb]
            };
            let hi = -phi(0.0)[0] / (1.0 - e);
            *dj = if hi > 0.0 {
                solve_increasing(phi, 0.0, 0.0, hi, 1e-10)
            } else {
                0.0
            };
            if !dj.is_finite() {
                return None;
            }
        }
        let c = cheb_coefficients(&d);
        // Convert Σ c_k T_k(ξ) to the power basis, so that `eval` can use
        // Estrin's scheme (depth log2 N instead of Clenshaw's chain of N
        // dependent steps). Degree 13 on [-1, 1] loses at most ~2^13 ε
        // relative, irrelevant for a starting point.
        let p = cheb_to_power(&c);
        Some(StartGuess {
            mid,
            inv_half: 1.0 / half,
            p,
        })
    }

    /// `D(z)` by Estrin's scheme, or `None` outside the window.
    #[inline]
    pub(crate) fn eval(&self, z: f64) -> Option<f64> {
        let xi = (z - self.mid) * self.inv_half;
        if !(xi.abs() <= 1.0) {
            return None;
        }
        Some(estrin(&self.p, xi))
    }
}

/// Number of coefficients of [`MediumGuess`] (see [`estrin`]).
const MEDIUM_GUESS_N: usize = 12;
/// Window of `w = ln y`, `y = -ln(1-u)`, on which [`MediumGuess`] is
/// fitted: `[-4.6, 1.6]`, i.e. `u ∈ [0.0100, 0.9930]`, 98.3% of the
/// samples; the others start as without a fit. A wider window costs
/// accuracy: with 12 coefficients `u ∈ [1e-3, 1 - 1e-3]` leaves errors
/// of 5e-6–5e-5 for `e = 0.5–0.8` instead of 5e-7–2e-6, too close to
/// [`MEDIUM_TOL`](super::MEDIUM_TOL) for a single evaluation.
pub(crate) const MEDIUM_W_MID: f64 = -1.5;
pub(crate) const MEDIUM_W_HALF: f64 = 3.1;
/// Largest error (in `ln t`) of the fit, checked at construction between
/// the nodes and at the window's ends, for which [`MediumGuess`] is kept.
/// The fit is only a starting point (any start converges), so the bar is
/// loose: within 1e-2 Halley needs at most two evaluations, which beats the
/// asymptotic start (≈ 2.7); a worse fit (e.g. small `e` with large `k`,
/// where the root bends sharply in `ln y`) is dropped.
pub(crate) const MEDIUM_GUESS_MAX_ERR: f64 = 1e-2;

/// Starting point of the pink medium sampler: a degree-11 polynomial fit
/// of the root `s* = ln t` as a function of `w = ln y` over the fixed window
/// `MEDIUM_W_MID ± MEDIUM_W_HALF`, fitted per model at construction
/// (Chebyshev interpolation at 12 nodes, converted to the power basis for
/// Estrin's scheme). Unlike the surface root, the medium root depends on
/// `k`, `e` and `σ` separately (`-ln T_ms = τ g(x) - ln q(x)` with `τ = σ t`,
/// `x = k t^e`), so the fit is over `w`, not over a one-parameter
/// variable. For the default-like parameters of the benchmark its error is
/// ≲ 1e-6, well below [`MEDIUM_TOL`](super::MEDIUM_TOL): one evaluation and one Halley step
/// per sample. Coefficients are stored as `f32` to keep [`Model`](super::Model) within
/// 256 bytes; their rounding (≲ 1e-7 relative, ≲ 1e-6 absolute on
/// the fit) is included in the construction-time check. All coefficients
/// `+inf` mark "no fit" (`eval` then gives inf or NaN, hence `None`). It
/// only moves the start: the safeguarded iteration decides the result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MediumGuess {
    /// Power-basis coefficients in `ξ = (w - MEDIUM_W_MID) / MEDIUM_W_HALF`.
    p: [f32; MEDIUM_GUESS_N],
}

impl MediumGuess {
    pub(crate) const NONE: MediumGuess = MediumGuess {
        p: [f32::INFINITY; MEDIUM_GUESS_N],
    };

    /// Fit `root_at(w)`, the root `s*` of the medium equation at `w = ln y`
    /// (which the caller solves far more tightly than the fit's bar);
    /// `NONE` unless the fit passes the check. Only pink models
    /// (`0 < e < 1`, `0 < k < inf`) have one: the caller decides.
    pub(crate) fn fit(root_at: impl Fn(f64) -> f64) -> Self {
        let root = |xi: f64| -> f64 { root_at(MEDIUM_W_MID + MEDIUM_W_HALF * xi) };
        let n = MEDIUM_GUESS_N as f64;
        let mut d = [0.0; MEDIUM_GUESS_N];
        for (j, dj) in d.iter_mut().enumerate() {
            *dj = root((std::f64::consts::PI * (j as f64 + 0.5) / n).cos());
            if !dj.is_finite() {
                return Self::NONE;
            }
        }
        let p = cheb_to_power(&cheb_coefficients(&d));
        let guess = MediumGuess {
            p: p.map(|c| c as f32),
        };
        // Check between the nodes (where the interpolation error peaks)
        // and at both ends of the window.
        for j in 0..=MEDIUM_GUESS_N {
            let xi = (std::f64::consts::PI * j as f64 / n).cos();
            let err = match guess.eval(MEDIUM_W_MID + MEDIUM_W_HALF * xi) {
                Some(s) => (s - root(xi)).abs(),
                None => f64::INFINITY,
            };
            if !(err <= MEDIUM_GUESS_MAX_ERR) {
                return Self::NONE;
            }
        }
        guess
    }

    /// The fitted `s*(w)` by Estrin's scheme, or `None` outside the window
    /// or without a fit.
    #[inline]
    pub(crate) fn eval(&self, w: f64) -> Option<f64> {
        let xi = (w - MEDIUM_W_MID) * (1.0 / MEDIUM_W_HALF);
        if !(xi.abs() <= 1.0) {
            return None;
        }
        let s = estrin(&self.p.map(f64::from), xi);
        // No fit (infinite coefficients) fails this test.
        if s.is_finite() {
            Some(s)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Estrin's scheme sums the same polynomial as Horner's rule.
    #[test]
    fn estrin_matches_horner() {
        let horner = |p: &[f64], xi: f64| p.iter().rev().fold(0.0, |s, &c| s * xi + c);
        let p14: [f64; 14] = std::array::from_fn(|i| (i as f64 * 0.7).sin() * 3.0);
        let p12: [f64; 12] = std::array::from_fn(|i| (i as f64 * 1.3 + 0.5).cos());
        for k in 0..=40 {
            let xi = -1.0 + k as f64 / 20.0;
            assert!((estrin(&p14, xi) - horner(&p14, xi)).abs() < 1e-13, "{xi}");
            assert!((estrin(&p12, xi) - horner(&p12, xi)).abs() < 1e-13, "{xi}");
        }
    }

    /// The fitted start is within 1e-3 of the root for moderate `e` over
    /// its window (so one evaluation suffices), and absent outside it.
    #[test]
    fn start_guess_fits_the_root() {
        for e in [0.1, 0.5, 0.8] {
            let gs = StartGuess::new(e, 0.0).unwrap();
            for i in 0..=200 {
                let z = -8.0 + 11.0 * i as f64 / 200.0;
                let phi = |dd: f64| -> [f64; 4] {
                    let (ln_g, a, b, xdb) = pink_terms(z + e * dd);
                    [dd + ln_g, (1.0 - e) + e * a, e * e * b, e * e * e * xdb]
                };
                let hi = -phi(0.0)[0] / (1.0 - e);
                let d = solve_increasing(phi, 0.0, 0.0, hi, 1e-12);
                let err = (gs.eval(z).unwrap() - d).abs();
                assert!(err < 1e-3, "e = {e}, z = {z}: err {err:e}");
            }
            assert!(gs.eval(-8.1).is_none() && gs.eval(3.1).is_none());
        }
        assert!(StartGuess::new(0.0, 0.0).is_none() && StartGuess::new(1.0, 0.0).is_none());
    }
}
