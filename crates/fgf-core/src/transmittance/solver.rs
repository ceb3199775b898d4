//! The root finder of the pink-noise samplers (`docs/theory.md` §7): a
//! safeguarded Newton/Halley/Householder iteration on `s = ln t` for an
//! increasing function, with bisection as the fallback inside the bracket,
//! and the tolerances the samplers stop at.

/// Stopping tolerance of the pink-noise surface sampler, on the step in
/// `s = ln t` (so relative on `t`). Its iteration is Householder's
/// third-order method (fourth-order convergence): the error left after a
/// final step `δ` is about `K δ⁴` with `K ≲ 0.1` here, so a step below 1e-3
/// leaves a relative error ≲ 1e-13 on `t` (checked by the round-trip tests
/// to 1e-11 on `-ln Tr`).
pub const SURFACE_TOL: f64 = 1e-3;
/// Stopping tolerance of the pink-noise medium sampler (Halley's method,
/// cubic convergence) on the step in `ln t`: the error left after a final
/// step `δ` is about `K δ³` with `K ≲ 1`, so ≲ 3e-14 relative on `t`.
pub const MEDIUM_TOL: f64 = 3e-5;
/// Width of the bracket in `ln t` at which the bisection fallback stops
/// (relative error ≤ 5e-13 on `t`); reached only when Newton/Halley steps
/// keep leaving the bracket.
pub const BISECT_TOL: f64 = 1e-12;
/// Iteration cap of the root finders: bisection alone needs at most
/// `log2(1460 / 1e-12) ≈ 51` halvings of the widest bracket
/// `[S_MIN, S_MAX]`, plus at most 11 doubling steps to find it, so 100
/// bounds every case; typical samples take one evaluation from the fitted
/// starts (`StartGuess`, `MediumGuess`), 2–5 without them.
pub const SAMPLE_MAX_ITER: u32 = 100;
/// `ln t` below which `t` underflows to 0 and above which it overflows.
const S_MIN: f64 = -745.2;
const S_MAX: f64 = 709.78;

/// Safeguarded Newton-type iteration for an increasing `φ(s)` given by
/// `f(s) = [φ, φ', φ'', φ''']` (zeros for unknown higher derivatives),
/// started at `s0` inside the bracket `(lo, hi)` (either end may be ±inf:
/// unknown).
///
/// Each evaluation shrinks the bracket by the sign of `φ`. The step is
/// [`householder_step`] (Newton when the higher derivatives are 0). A step
/// whose size is below `tol` ends the iteration (tested before the
/// bracket, since at the root rounding may put the step on an end); a step
/// that leaves the bracket, or is not finite, is replaced by bisection (or
/// by doubling steps while one end is still unknown), which stops when the
/// bracket is narrower than [`BISECT_TOL`]. Returns `s`, or `±inf` when the
/// root is beyond `t`'s range. Never loops more than [`SAMPLE_MAX_ITER`]
/// times.
#[inline]
pub(crate) fn solve_increasing(
    f: impl Fn(f64) -> [f64; 4],
    s0: f64,
    mut lo: f64,
    mut hi: f64,
    tol: f64,
) -> f64 {
    lo = lo.max(S_MIN);
    hi = hi.min(S_MAX);
    if !(lo < hi) {
        return 0.5 * (lo + hi);
    }
    let mut s = s0.clamp(lo, hi);
    let mut expand = 1.0;
    for _ in 0..SAMPLE_MAX_ITER {
        let d = f(s);
        let phi = d[0];
        if phi == 0.0 {
            return s;
        }
        // The root lies beyond the range of t: overflow to inf / underflow to 0.
        if phi < 0.0 && s >= S_MAX {
            return f64::INFINITY;
        }
        if phi > 0.0 && s <= S_MIN {
            return f64::NEG_INFINITY;
        }
        if phi < 0.0 {
            lo = s;
        } else {
            hi = s;
        }
        let step = householder_step(d);
        if step.abs() <= tol {
            return s + step;
        }
        let candidate = s + step;
        let next = if candidate.is_finite() && candidate > lo && candidate < hi {
            candidate
        } else if lo > S_MIN && hi < S_MAX {
            0.5 * (lo + hi)
        } else if phi < 0.0 {
            // Root above s, upper end unknown: step up, doubling.
            expand *= 2.0;
            (s + expand).min(S_MAX)
        } else {
            expand *= 2.0;
            (s - expand).max(S_MIN)
        };
        if hi - lo <= BISECT_TOL {
            return 0.5 * (lo + hi);
        }
        s = next;
    }
    0.5 * (lo + hi)
}

/// Householder's third-order step from `[f, f', f'', f''']`:
/// `δ = -(6 f f'² - 3 f² f'') / (6 f'³ - 6 f f' f'' + f² f''')`, which reduces
/// to Halley's (`f''' = 0`) and Newton's (`f'' = f''' = 0`) steps. Far from
/// the root the higher-order terms can dominate and even reverse the step;
/// so it falls back to Newton's step unless the denominator is safely
/// positive (`≥ 3 f'³`) and the step has Newton's sign and at most twice
/// its length.
#[inline]
pub(crate) fn householder_step(d: [f64; 4]) -> f64 {
    let [f, f1, f2, f3] = d;
    let newton = -f / f1;
    let f1_2 = f1 * f1;
    let num = 6.0 * f * f1_2 - 3.0 * f * f * f2;
    let den = 6.0 * f1_2 * f1 - 6.0 * f * f1 * f2 + f * f * f3;
    if den >= 3.0 * f1_2 * f1 {
        let step = -num / den;
        if step * newton > 0.0 && step.abs() <= 2.0 * newton.abs() {
            return step;
        }
    }
    newton
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solver_finds_root_of_a_line_and_handles_overflow() {
        let s = solve_increasing(
            |s| [s - 3.0, 1.0, 0.0, 0.0],
            0.0,
            f64::NEG_INFINITY,
            f64::INFINITY,
            1e-9,
        );
        assert!((s - 3.0).abs() < 1e-12);
        // Root beyond t's range: +inf.
        let s = solve_increasing(
            |s| [s - 1e6, 1e-9, 0.0, 0.0],
            0.0,
            f64::NEG_INFINITY,
            f64::INFINITY,
            1e-9,
        );
        assert_eq!(s, f64::INFINITY);
        // A flat derivative (Newton useless) still terminates by bisection.
        let s = solve_increasing(
            |s| [(s - 1.0).powi(3), 0.0, 0.0, 0.0],
            0.0,
            -10.0,
            10.0,
            1e-9,
        );
        assert!((s - 1.0).abs() < 1e-3);
    }
}
