//! # fgf-field
//!
//! Realizations of fractional Gaussian fields (`docs/theory.md` §1): spectral
//! synthesis on 1D/2D/3D grids ([`synthesize`]), exact 1D samplers
//! ([`sample_optical_depth`], [`sample_kfbm_1d`]), estimators
//! ([`estimators`]) and file exports ([`export`]).
//!
//! ## Conventions
//!
//! * **Index order.** Grids are C-order arrays with shape `[x]`, `[y, x]` or
//!   `[z, y, x]`; sample `(z, y, x)` is `data[(z*ny + y)*nx + x]`, x varies
//!   fastest (the order of numpy and of Mitsuba's `.vol`).
//! * **Units.** Sample `i` along an axis sits at `i · spacing` from the
//!   origin corner; `spacing` (`dx`) is in scene units, the same on every
//!   axis. It represents the cell `[i dx, (i+1) dx)` (the noise is
//!   cell-averaged white noise). Wavenumbers are angular, `k = 2π m/(n dx)`
//!   in rad per scene unit.
//! * **Spectrum.** `P(k) = S_w |k|^(-2s)` with `s = H + d/2`, for the Fourier
//!   convention `f̂(k) = ∫ f(x) e^{-ik·x} dx` and covariance
//!   `∫ P(k) e^{ik·r} dk/(2π)^d`; this makes `cov = C(H,d) S_w |r|^(2H)`
//!   with `docs/theory.md`'s `C(H,d)`.
//! * **FFT normalisation.** Forward transforms are unnormalised
//!   (`X_m = Σ_j x_j e^{-2πi jm/n}`), inverse transforms are unnormalised
//!   too and the `1/N` is folded into the spectral filter, as in RustFFT.
//!   Frequency order along each complex axis is RustFFT's: `m = 0, 1, …,
//!   n/2, …, -1`; along x only `m = 0 … n/2` (the real-to-complex half
//!   spectrum) is stored.
//! * **Grid variance.** The variance of a grid field is the discrete spectral
//!   sum ([`discrete_spectral_variance`]), not the continuum value: in 3D
//!   the difference is large (`docs/theory.md` §1, caveat for 3D grids). To give
//!   a 3D field the 1D statistics of the rendering model along every ray,
//!   use `S_w3` from [`sw_3d_for_ray_statistics`].
//! * **Determinism.** All noise comes from counter-based streams indexed by
//!   `(seed, row)`, and no floating-point reduction depends on scheduling:
//!   the same parameters give bit-identical output for any thread count.
//!
//! ## Example: a 3D density for the renderer's ground-truth ensemble
//!
//! ```
//! use fgf_field::{synthesize, sw_3d_for_ray_statistics, SynthParams};
//! let (hurst, sw_1d, sigma_m) = (-0.1, 1.0, 2.0);
//! let mut p = SynthParams::new(&[16, 16, 16], hurst);
//! p.spacing = 1.0 / 16.0;
//! p.sw = sw_3d_for_ray_statistics(hurst, sw_1d).unwrap();
//! p.seed = 3;
//! let f = synthesize(&p, &fgf_core::NoProgress).unwrap();
//! let sigma_t: Vec<f32> = f.data.to_f32().iter().map(|&u| (sigma_m + u).max(0.0)).collect();
//! assert_eq!(sigma_t.len(), 16 * 16 * 16);
//! ```

pub mod copula;
mod error;
pub mod estimators;
pub mod exact;
pub mod export;
pub mod line_variance;

mod noise;
pub mod synth;

pub use error::{mem_available, FieldError};
pub use exact::{sample_kfbm_1d, sample_optical_depth, Samples1d, MAX_CHOLESKY_STEPS};
pub use synth::{
    check_synthesis_memory, discrete_spectral_variance, estimate_memory, padded_shape,
    sw_3d_for_ray_statistics, synthesize, work_units, Anchor, Field, FieldData, Precision, Real,
    SynthParams,
};
