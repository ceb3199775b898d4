//! The spectral filter of the synthesis, `amp |k|^(-s)` per stored mode
//! of the half spectrum.

use super::plan::Plan;
use std::f64::consts::PI;

/// The spectral filter `amp |k|^(-s)`, 0 at k = 0 (and at Nyquist for k-fBm).
/// On 3D grids whose axes all have the same length, `|k|²` is
/// `(2π/(n dx))²` times an integer, and the power comes from a table.
pub(super) struct Filter {
    keep: [Vec<bool>; 3],
    m2: [Vec<usize>; 3],
    k2: [Vec<f64>; 3],
    lut: Option<Vec<f64>>,
    amp: f64,
    s: f64,
}

impl Filter {
    pub(super) fn new(plan: &Plan) -> Filter {
        let [n0, n1, n2] = plan.pad;
        let lens = [n0, n1, n2 / 2 + 1];
        let mut keep: [Vec<bool>; 3] = Default::default();
        let mut m2: [Vec<usize>; 3] = Default::default();
        let mut k2: [Vec<f64>; 3] = Default::default();
        for ax in 0..3 {
            let n = plan.pad[ax];
            for i in 0..lens[ax] {
                keep[ax].push(!(plan.zero_nyquist && Plan::is_nyquist(i, n)));
                let m = if i <= n / 2 { i } else { n - i };
                m2[ax].push(m * m);
                k2[ax].push(plan.wavenumber(i, n).powi(2));
            }
        }
        let used: Vec<usize> = plan.pad[3 - plan.d..].to_vec();
        let n = used[0];
        let qmax = plan.d * (n / 2) * (n / 2);
        // The table has d·(n/2)² entries: it only pays off when it is much
        // smaller than the number of stored modes (3D grids, not 1D/2D).
        let modes = lens.iter().product::<usize>();
        let lut = if used.iter().all(|&m| m == n) && plan.s != 0.0 && 4 * (qmax + 1) <= modes {
            let unit = (2.0 * PI / (n as f64 * plan.dx)).powi(2);
            Some(
                (0..=qmax)
                    .map(|q| {
                        if q == 0 {
                            0.0
                        } else {
                            plan.amp * (unit * q as f64).powf(-plan.s / 2.0)
                        }
                    })
                    .collect(),
            )
        } else {
            None
        };
        Filter {
            keep,
            m2,
            k2,
            lut,
            amp: plan.amp,
            s: plan.s,
        }
    }

    #[inline]
    pub(super) fn at(&self, iz: usize, iy: usize, ix: usize) -> f64 {
        if !(self.keep[0][iz] && self.keep[1][iy] && self.keep[2][ix]) {
            return 0.0;
        }
        match &self.lut {
            Some(lut) => lut[self.m2[0][iz] + self.m2[1][iy] + self.m2[2][ix]],
            None => {
                let k2 = self.k2[0][iz] + self.k2[1][iy] + self.k2[2][ix];
                if k2 == 0.0 {
                    0.0
                } else if self.s == 0.0 {
                    self.amp
                } else {
                    self.amp * k2.powf(-self.s / 2.0)
                }
            }
        }
    }
}
