//! Validation of [`SynthParams`] and the plan the synthesis runs: the
//! output and padded (periodic) shapes as `[z, y, x]`, the spectral slope,
//! the filter's amplitude, the anchor and the Taylor terms of a k-fBm.

use super::{Anchor, SynthParams};
use fgf_core::ParamError;
use std::f64::consts::PI;

/// Columns per gathered block of the strided FFT passes: 128-256
/// contiguous bytes per row read.
pub(super) const B: usize = 16;

/// Validated synthesis plan.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    /// Number of axes of the request (1 to 3).
    pub(super) d: usize,
    /// Output shape as `[z, y, x]`, 1 for missing leading axes.
    pub(super) out: [usize; 3],
    /// Shape of the periodic domain, `[z, y, x]` likewise.
    pub(super) pad: [usize; 3],
    /// Spectral slope `s = H + d/2`.
    pub(super) s: f64,
    pub(super) dx: f64,
    /// `sqrt(S_w / dx^d) / N`: the filter's amplitude (see the module docs).
    pub(super) amp: f64,
    /// True for k-fBm: Nyquist modes are dropped so that the band-limited
    /// interpolant (whose derivatives we subtract) is real and unique.
    pub(super) zero_nyquist: bool,
    pub(super) anchor: Option<[usize; 3]>,
    /// Multi-indices `[az, ay, ax]` of the Taylor terms, `|a| <= k-1`.
    pub(super) terms: Vec<[u32; 3]>,
}

/// Smallest `m >= n` whose prime factors are all in {2, 3, 5, 7}: fast sizes
/// for the mixed-radix FFT.
pub(super) fn next_smooth(n: usize) -> usize {
    let mut m = n.max(1);
    loop {
        let mut r = m;
        for p in [2, 3, 5, 7] {
            while r % p == 0 {
                r /= p;
            }
        }
        if r == 1 {
            return m;
        }
        m += 1;
    }
}

impl Plan {
    pub(crate) fn new(p: &SynthParams) -> Result<Plan, ParamError> {
        let d = p.shape.len();
        if !(1..=3).contains(&d) {
            return Err(ParamError::new(
                "shape",
                format!("{:?}", p.shape),
                "must have 1, 2 or 3 axes",
                "shape = (nx,), (ny, nx) or (nz, ny, nx)",
            ));
        }
        let total = p
            .shape
            .iter()
            .try_fold(1usize, |acc, &n| acc.checked_mul(n));
        if total.is_none() && !p.shape.contains(&0) {
            return Err(ParamError::new(
                "shape",
                format!("{:?}", p.shape),
                "the grid has more than 2^64 samples (the product of the axes overflows)",
                "product of the axes < 2^64 (and within the available memory)",
            ));
        }
        if p.shape.contains(&0) || total.unwrap_or(0) < 2 {
            return Err(ParamError::new(
                "shape",
                format!("{:?}", p.shape),
                "every axis needs >= 1 sample and the grid >= 2 samples",
                "each n >= 1, product >= 2",
            ));
        }
        let dx = ParamError::check_positive("spacing", p.spacing)?;
        let sw = ParamError::check_positive("sw", p.sw)?;
        let h = p.hurst;
        let hmin = -(d as f64) / 2.0;
        if !h.is_finite() || h < hmin || h >= 3.0 || (h >= 0.0 && h.fract() == 0.0) {
            return Err(ParamError::new(
                "hurst",
                h,
                format!("outside the range of a {d}D field (white noise at -d/2, pink noise below 0, k-fBm in (k-1, k) for k = 1, 2, 3)"),
                format!("{hmin} <= hurst < 3, hurst not 0, 1 or 2"),
            ));
        }
        let kfbm = if h > 0.0 { h.ceil() as u32 } else { 0 };
        let padding = match p.padding {
            None => {
                if kfbm > 0 {
                    2.0
                } else {
                    1.0
                }
            }
            Some(x) if x.is_finite() && x >= 1.0 => x,
            Some(x) => {
                return Err(ParamError::new(
                    "padding",
                    x,
                    "the periodic domain cannot be smaller than the grid",
                    "1 <= padding < inf",
                ))
            }
        };
        let mut out = [1usize; 3];
        out[3 - d..].copy_from_slice(&p.shape);
        let mut pad = out;
        for ax in 3 - d..3 {
            if padding > 1.0 {
                let want = (out[ax] as f64 * padding).ceil();
                if want > 1e12 {
                    return Err(ParamError::new(
                        "padding",
                        padding,
                        "padded grid too large",
                        "1 <= padding, padded axis < 1e12",
                    ));
                }
                pad[ax] = next_smooth(want as usize);
            }
        }
        let anchor = if kfbm == 0 {
            None
        } else {
            match &p.anchor {
                Anchor::None => None,
                Anchor::Corner => Some([0, 0, 0]),
                Anchor::Center => Some([out[0] / 2, out[1] / 2, out[2] / 2]),
                Anchor::Index(idx) => {
                    if idx.len() != d || idx.iter().zip(&p.shape).any(|(i, n)| i >= n) {
                        return Err(ParamError::new(
                            "anchor",
                            format!("{idx:?}"),
                            format!("must be one index per axis inside the grid {:?}", p.shape),
                            "0 <= anchor[i] < shape[i]",
                        ));
                    }
                    let mut a = [0usize; 3];
                    a[3 - d..].copy_from_slice(idx);
                    Some(a)
                }
            }
        };
        let mut terms = Vec::new();
        if anchor.is_some() {
            let used = |ax: usize| ax >= 3 - d;
            for az in 0..kfbm {
                for ay in 0..kfbm {
                    for ax in 0..kfbm {
                        if az + ay + ax < kfbm
                            && (az == 0 || used(0))
                            && (ay == 0 || used(1))
                            && (ax == 0 || used(2))
                        {
                            terms.push([az, ay, ax]);
                        }
                    }
                }
            }
        }
        let n_pad: f64 = pad.iter().map(|&n| n as f64).product();
        Ok(Plan {
            d,
            out,
            pad,
            s: h + d as f64 / 2.0,
            dx,
            amp: (sw / dx.powi(d as i32)).sqrt() / n_pad,
            zero_nyquist: kfbm > 0,
            anchor,
            terms,
        })
    }

    /// Bytes the synthesis allocates at its peak (the one buffer holding
    /// the padded half spectrum, later the output; not scratch).
    pub(crate) fn bytes(&self, elem: usize) -> Option<u64> {
        let [n0, n1, n2] = self.pad;
        (n0 as u64)
            .checked_mul(n1 as u64)?
            .checked_mul(2 * (n2 as u64 / 2 + 1))?
            .checked_mul(elem as u64)
    }

    /// Work units reported to [`Progress`](fgf_core::Progress).
    pub(crate) fn work_units(&self) -> u64 {
        let [n0, n1, n2] = self.pad;
        let nblk = (n2 / 2 + 1).div_ceil(B);
        let y_pass = |nz: usize| if n1 > 1 { (nz * nblk) as u64 } else { 0 };
        (n0 * n1) as u64
            + y_pass(n0)
            + n1 as u64
            + y_pass(self.out[0])
            + (self.out[0] * self.out[1]) as u64
    }

    /// Signed wavenumber of index `i` on an axis of `n` samples.
    pub(super) fn wavenumber(&self, i: usize, n: usize) -> f64 {
        let m = if i <= n / 2 {
            i as f64
        } else {
            i as f64 - n as f64
        };
        2.0 * PI * m / (n as f64 * self.dx)
    }

    pub(super) fn is_nyquist(i: usize, n: usize) -> bool {
        n % 2 == 0 && n > 1 && i == n / 2
    }
}
