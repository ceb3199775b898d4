//! `<spectrum value="λ₁:v₁, λ₂:v₂, …">` (wavelengths in nm) to linear
//! sRGB, as Mitsuba 3's RGB variants convert it when they load a scene.
//!
//! The spectrum is the piecewise-linear interpolant of the pairs, zero
//! outside `[λ₁, λₙ]`. Its tristimulus values are a Riemann sum over 1000
//! wavelengths evenly spaced on `[360, 830]` nm (both ends included),
//! `XYZ = Σ s(λ)·w(λ)·(x̄, ȳ, z̄)(λ) · 470 nm · K / 1000` with `K` the ȳ
//! normalisation, where `w` is the D65 illuminant for reflectances and
//! other non-emissive quantities and 1 for emission. XYZ goes to linear
//! sRGB by the IEC 61966-2-1 matrix, and the result is clamped: to
//! `[0, 1]` for bounded quantities (reflectances, albedos, and — as in
//! Mitsuba 3.9.1 — a medium's `sigma_t`), to `≥ 0` for unbounded ones
//! (emission, a conductor's `eta` and `k`).

use super::cie::{CIE1931_XYZ, D65, Y_NORMALIZATION};

const CIE_MIN: f64 = 360.0;
const CIE_MAX: f64 = 830.0;
const STEPS: usize = 1000;

/// How a parameter's spectrum is converted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SpectrumUse {
    /// Reflectances, albedos, extinction: D65-weighted, clamped to [0, 1].
    Bounded,
    /// A conductor's `eta`, `k`: D65-weighted, clamped to ≥ 0.
    Unbounded,
    /// Emission: unweighted, clamped to ≥ 0.
    Emission,
}

/// Parse `"400:0.1, 500:0.5"` (commas and/or spaces between pairs) into
/// wavelengths and values; `Err` is the problem, for the caller to place.
pub(crate) fn parse_pairs(s: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
    let mut w = Vec::new();
    let mut v = Vec::new();
    for tok in s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
    {
        let (a, b) = tok
            .split_once(':')
            .ok_or_else(|| format!("'{tok}' is not a wavelength:value pair"))?;
        let num = |x: &str| -> Result<f64, String> {
            x.trim()
                .parse::<f64>()
                .ok()
                .filter(|y| y.is_finite())
                .ok_or_else(|| format!("cannot parse '{x}' in '{tok}' as a number"))
        };
        let (lambda, value) = (num(a)?, num(b)?);
        if let Some(&prev) = w.last() {
            if lambda <= prev {
                return Err(format!(
                    "wavelengths must increase ({lambda} nm follows {prev} nm)"
                ));
            }
        }
        w.push(lambda);
        v.push(value);
    }
    if w.len() < 2 {
        return Err("a spectrum needs at least two wavelength:value pairs".into());
    }
    Ok((w, v))
}

/// Linear interpolation in a table with nodes every `step` nm from 360 nm.
fn table<const N: usize, T: Copy>(
    t: &[T; N],
    step: f64,
    lambda: f64,
    get: impl Fn(T) -> [f64; 3],
) -> [f64; 3] {
    let x = (lambda - CIE_MIN) / step;
    if !(0.0..=(N - 1) as f64).contains(&x) {
        return [0.0; 3];
    }
    let i = (x.floor() as usize).min(N - 2);
    let f = x - i as f64;
    let (a, b) = (get(t[i]), get(t[i + 1]));
    [0, 1, 2].map(|k| a[k] * (1.0 - f) + b[k] * f)
}

/// The linear sRGB of the spectrum given by `pairs` (increasing wavelengths).
pub(crate) fn to_srgb(w: &[f64], v: &[f64], usage: SpectrumUse) -> [f64; 3] {
    let d65 = usage != SpectrumUse::Emission;
    let mut xyz = [0.0f64; 3];
    let (first, last) = (w[0], w[w.len() - 1]);
    for i in 0..STEPS {
        let lambda = CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
        if lambda < first || lambda > last {
            continue;
        }
        // The last pair's interval for lambda == last.
        let j = w.partition_point(|&x| x <= lambda).clamp(1, w.len() - 1) - 1;
        let t = (lambda - w[j]) / (w[j + 1] - w[j]);
        let s = v[j] * (1.0 - t) + v[j + 1] * t;
        let weight = if d65 {
            table(&D65, 5.0, lambda, |d| [d; 3])[0]
        } else {
            1.0
        };
        let cmf = table(&CIE1931_XYZ, 1.0, lambda, |c| c);
        for k in 0..3 {
            xyz[k] += cmf[k] * s * weight;
        }
    }
    let scale = (CIE_MAX - CIE_MIN) * Y_NORMALIZATION / STEPS as f64;
    let [x, y, z] = xyz.map(|c| c * scale);
    let rgb = [
        3.240479 * x - 1.537150 * y - 0.498535 * z,
        -0.969256 * x + 1.875991 * y + 0.041556 * z,
        0.055648 * x - 0.204043 * y + 1.057311 * z,
    ];
    match usage {
        SpectrumUse::Bounded => rgb.map(|c| c.clamp(0.0, 1.0)),
        _ => rgb.map(|c| c.max(0.0)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_reflectance_of_one_is_white_and_emission_is_equal_energy() {
        let (w, v) = parse_pairs("360:1, 830:1").unwrap();
        let r = to_srgb(&w, &v, SpectrumUse::Bounded);
        assert!(r.iter().all(|c| (c - 0.999).abs() < 2e-3), "{r:?}");
        let e = to_srgb(&w, &v, SpectrumUse::Emission);
        assert!(
            (e[0] - 1.2049).abs() < 2e-3 && (e[2] - 0.9093).abs() < 2e-3,
            "{e:?}"
        );
    }

    #[test]
    fn malformed_pairs_are_errors() {
        assert!(parse_pairs("400:0.1").is_err());
        assert!(parse_pairs("500:0.1, 400:0.2").is_err());
        assert!(parse_pairs("400-0.1, 500:0.2").is_err());
        assert!(parse_pairs("400:x, 500:0.2").is_err());
    }
}
