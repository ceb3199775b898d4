//! Anchoring of a k-fBm (`docs/theory.md` §1, "Synthesis of k-fBm"): the
//! derivatives of the periodic field at the anchor, summed from its
//! spectrum, and the Taylor polynomial they define, which the last pass
//! subtracts.

use super::plan::Plan;
use rustfft::num_complex::Complex;

/// Per-axis `e^{i k a}` and wavenumbers for the Taylor sums.
pub(super) struct Taylor {
    pub(super) k: [Vec<f64>; 3],
    pub(super) phase: [Vec<Complex<f64>>; 3],
    terms: Vec<[u32; 3]>,
}

impl Taylor {
    pub(super) fn new(plan: &Plan, a: [usize; 3]) -> Taylor {
        let [n0, n1, n2] = plan.pad;
        let lens = [n0, n1, n2 / 2 + 1];
        let mut k: [Vec<f64>; 3] = Default::default();
        let mut phase: [Vec<Complex<f64>>; 3] = Default::default();
        for ax in 0..3 {
            for i in 0..lens[ax] {
                let kk = plan.wavenumber(i, plan.pad[ax]);
                k[ax].push(kk);
                phase[ax].push(Complex::from_polar(1.0, kk * a[ax] as f64 * plan.dx));
            }
        }
        Taylor {
            k,
            phase,
            terms: plan.terms.clone(),
        }
    }

    /// Highest derivative order along z plus one (the number of z-line sums).
    pub(super) fn kz_orders(&self) -> usize {
        self.terms
            .iter()
            .map(|t| t[0] as usize + 1)
            .max()
            .unwrap_or(0)
    }

    /// Add the z-line `(*, iy, ix)` to the derivative sums
    /// `∂^a field(anchor) = Σ_modes c · Re(F (ik)^a e^{ik·anchor})`, given
    /// `line[p] = Σ_z F e^{i kz z_a} kz^p`. `c = 2` for modes whose conjugate
    /// is not stored in the half spectrum. Splitting the sum per line keeps
    /// the per-mode work to one complex multiply-add per z-order.
    pub(super) fn add_line(&self, acc: &mut [f64], line: &[Complex<f64>], iy: usize, ix: usize) {
        let c = if ix == 0 { 1.0 } else { 2.0 };
        let lp = self.phase[1][iy] * self.phase[2][ix] * c;
        for (t, a) in self.terms.iter().zip(acc.iter_mut()) {
            let g = line[t[0] as usize]
                * lp
                * (self.k[1][iy].powi(t[1] as i32) * self.k[2][ix].powi(t[2] as i32));
            // Re(i^n g): the power of i from (ik)^a.
            *a += match (t[0] + t[1] + t[2]) % 4 {
                0 => g.re,
                1 => -g.im,
                2 => -g.re,
                _ => g.im,
            };
        }
    }
}

/// The Taylor polynomial `Σ_a D_a Π (x - x_anchor)^a / a!` at sample (z, y, x).
pub(super) struct Poly {
    pub(super) terms: Vec<([u32; 3], f64)>,
    pub(super) a: [usize; 3],
    pub(super) dx: f64,
}

impl Poly {
    #[inline]
    pub(super) fn at(&self, z: usize, y: usize, x: usize) -> f64 {
        let r = [
            (z as f64 - self.a[0] as f64) * self.dx,
            (y as f64 - self.a[1] as f64) * self.dx,
            (x as f64 - self.a[2] as f64) * self.dx,
        ];
        let mut p = 0.0;
        for (t, c) in &self.terms {
            let mut m = *c;
            for ax in 0..3 {
                m *= r[ax].powi(t[ax] as i32) / FACT[t[ax] as usize];
            }
            p += m;
        }
        p
    }
}

const FACT: [f64; 4] = [1.0, 1.0, 2.0, 6.0];
