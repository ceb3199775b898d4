//! Tabulated free-flight samplers for the models without a closed-form
//! inverse (pink noise, Davis–Weinstein), built once per medium and channel.
//!
//! `fgf-core` solves `-ln T(t) = y`, `y = -ln(1-u)`, by a few Newton-type
//! steps, about 100 ns per flight; that made the reciprocal kernel of a
//! pink-noise medium 1.4× as costly as an exponential render. The renderer
//! draws `u` from 2²⁴ values and uses `t` in f32, so it only needs `t` to
//! f32 accuracy: this table holds the exact solution `s = ln t` as a
//! function of `ln y` on a uniform grid, with its exact slope, and
//! interpolates with cubic Hermite polynomials.
//!
//! The table validates itself when built: it compares the interpolant with
//! the exact sampler at the midpoint of every interval and is only used if
//! the worst error on `ln t` is below [`MAX_ERROR`] (a relative error on
//! `t` of 1e-7, about one f32 ulp). Outside its range (`ln y` beyond what a
//! 24-bit `u` produces, or a model whose solution is not finite there) the
//! exact sampler answers.

use fgf_core::transmittance::{Model, Transmittance};

/// Node counts tried in turn: 1024 (16 kB) is enough for most models; 4096
/// cuts the interpolation error 256-fold for the harder ones (e.g. pink
/// noise near `H = -0.4` for medium flights, 1.4e-7 with 1024 nodes).
const NODES: [usize; 2] = [1024, 4096];
/// `ln y` range: `u = k/2²⁴` gives `y ∈ [2⁻²⁴, 24 ln 2]`, so
/// `ln y ∈ [-16.64, 2.81]`.
const LN_Y_MIN: f64 = -16.7;
const LN_Y_MAX: f64 = 2.9;
/// Largest accepted interpolation error on `ln t` at the interval midpoints.
pub const MAX_ERROR: f64 = 1e-7;

/// Which flight distribution the table inverts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flight {
    /// `1 - Tr(t)`: flights from a surface (and every flight of the
    /// energy-conserving kernel).
    Surface,
    /// `1 - T_ms(t)`: flights from a medium vertex under the reciprocal kernel.
    Medium,
}

/// `s = ln t` against `ln y` at `NODES` uniform nodes, with `ds/d ln y`.
#[derive(Debug, Clone)]
pub struct FlightTable {
    inv_h: f64,
    h: f64,
    s: Vec<f64>,
    slope: Vec<f64>,
}

impl FlightTable {
    /// Tabulate `model`'s sampler for `flight`; `None` if the model has a
    /// closed-form inverse (no gain) or the table misses [`MAX_ERROR`].
    pub fn new(model: &Model, flight: Flight) -> Option<FlightTable> {
        if !iterative(model) {
            return None;
        }
        NODES
            .iter()
            .find_map(|&nodes| Self::with_nodes(model, flight, nodes))
    }

    fn with_nodes(model: &Model, flight: Flight, nodes: usize) -> Option<FlightTable> {
        let h = (LN_Y_MAX - LN_Y_MIN) / (nodes - 1) as f64;
        let mut s = Vec::with_capacity(nodes);
        let mut slope = Vec::with_capacity(nodes);
        for i in 0..nodes {
            let (si, di) = exact(model, flight, LN_Y_MIN + i as f64 * h)?;
            s.push(si);
            slope.push(di);
        }
        let table = FlightTable {
            inv_h: 1.0 / h,
            h,
            s,
            slope,
        };
        let worst = (0..nodes - 1)
            .map(|i| {
                let ln_y = LN_Y_MIN + (i as f64 + 0.5) * h;
                match (exact(model, flight, ln_y), table.ln_t(ln_y)) {
                    (Some((want, _)), Some(got)) => (got - want).abs(),
                    _ => f64::INFINITY,
                }
            })
            .fold(0.0, f64::max);
        (worst <= MAX_ERROR).then_some(table)
    }

    /// `ln t` for `ln y`, if inside the table.
    #[inline]
    pub fn ln_t(&self, ln_y: f64) -> Option<f64> {
        let last = self.s.len() - 1;
        let x = (ln_y - LN_Y_MIN) * self.inv_h;
        if !(x >= 0.0 && x <= last as f64) {
            return None;
        }
        let i = (x as usize).min(last - 1);
        let f = x - i as f64;
        // Cubic Hermite basis on [0, 1].
        let (f2, f3) = (f * f, f * f * f);
        let h00 = 2.0 * f3 - 3.0 * f2 + 1.0;
        let h10 = f3 - 2.0 * f2 + f;
        let h01 = -2.0 * f3 + 3.0 * f2;
        let h11 = f3 - f2;
        Some(
            h00 * self.s[i]
                + h10 * self.h * self.slope[i]
                + h01 * self.s[i + 1]
                + h11 * self.h * self.slope[i + 1],
        )
    }

    /// The flight distance for a variate `u ∈ [0, 1)`: the table inside
    /// its range, else the exact sampler.
    #[inline]
    pub fn sample(&self, model: &Model, flight: Flight, u: f64) -> f64 {
        // The renderer's u has 24 bits, so 1 - u is exact and ln(1 - u)
        // is as accurate as ln_1p(-u), at the cost of glibc's faster log.
        // (For a u where 1 - u rounds to 1, y = 0 and the exact sampler
        // answers.)
        let y = -(1.0 - u).ln();
        if y > 0.0 {
            if let Some(ln_t) = self.ln_t(y.ln()) {
                return ln_t.exp();
            }
        }
        exact_sample(model, flight, u)
    }
}

/// Models whose samplers iterate (pink noise and Davis–Weinstein): the
/// others invert in closed form and gain nothing from a table.
fn iterative(model: &Model) -> bool {
    match model {
        Model::Fgf(m) => m.regime() == fgf_core::stats::Regime::Pink,
        Model::DavisWeinstein(_) => true,
        _ => false,
    }
}

/// The exact sampler of `flight` (what the table stands in for).
pub fn exact_sample(model: &Model, flight: Flight, u: f64) -> f64 {
    match flight {
        Flight::Surface => model.sample_surface(u),
        Flight::Medium => model.sample_medium(u),
    }
}

/// The exact `(ln t, d ln t / d ln y)` at `ln y`: `t` solves
/// `-ln T(t) = y`, and `d ln y / d ln t = t·h(t)/y` with the hazard rate
/// `h = -d ln T/dt` (`pdf/Tr`, or `T_mm/T_ms` for medium flights).
fn exact(model: &Model, flight: Flight, ln_y: f64) -> Option<(f64, f64)> {
    let y = ln_y.exp();
    // u = 1 - e^-y, computed without cancellation for small y.
    let u = -(-y).exp_m1();
    let t = exact_sample(model, flight, u);
    let hazard = match flight {
        Flight::Surface => model.pdf(t) / model.tr(t),
        Flight::Medium => model.medium_medium(t) / model.medium_surface(t),
    };
    let slope = y / (t * hazard);
    (t > 0.0 && t.is_finite() && slope.is_finite() && slope > 0.0).then(|| (t.ln(), slope))
}

#[cfg(test)]
mod tests {
    use super::*;
    use fgf_core::transmittance::{Davis, DavisWeinstein, Fgf};

    /// Pink noise over a range of parameters: the table is built and agrees
    /// with the exact sampler to [`MAX_ERROR`] on `ln t` at every 24-bit
    /// variate tested (a dense sweep, not only the nodes' midpoints).
    #[test]
    fn pink_tables_match_the_exact_sampler() {
        for (sigma, hurst, sw) in [(4.0, -0.1, 4.0), (1.0, -0.4, 10.0), (20.0, -0.25, 0.5)] {
            let m = Model::from(Fgf::new(sigma, hurst, sw, None).unwrap());
            for flight in [Flight::Surface, Flight::Medium] {
                let table = FlightTable::new(&m, flight)
                    .unwrap_or_else(|| panic!("{sigma} {hurst} {sw} {flight:?}: no table"));
                let mut worst = 0.0f64;
                for k in (1..1u32 << 24).step_by(997) {
                    let u = k as f64 / (1u64 << 24) as f64;
                    let got = table.sample(&m, flight, u);
                    let want = exact_sample(&m, flight, u);
                    worst = worst.max((got / want).ln().abs());
                }
                assert!(
                    worst <= 2.0 * MAX_ERROR,
                    "{sigma} {hurst} {sw} {flight:?}: {worst:e}"
                );
                assert_eq!(table.sample(&m, flight, 0.0), 0.0);
            }
        }
        let dw = Model::from(DavisWeinstein::new(4.0, 0.9, 0.78).unwrap());
        assert!(FlightTable::new(&dw, Flight::Medium).is_some());
    }

    /// Closed-form models get no table.
    #[test]
    fn closed_forms_get_no_table() {
        let davis = Model::from(Davis::new(4.0, 2.0).unwrap());
        let kfbm = Model::from(Fgf::new(4.0, 1.2, 34.0, Some(1.0)).unwrap());
        let white = Model::from(Fgf::new(4.0, -0.5, 4.0, None).unwrap());
        for m in [davis, kfbm, white] {
            assert!(FlightTable::new(&m, Flight::Surface).is_none());
        }
    }
}
