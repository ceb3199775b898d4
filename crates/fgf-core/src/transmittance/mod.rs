//! Non-exponential transmittance models (`docs/theory.md` §3–4).
//!
//! Four models, one file each: [`Exponential`], [`Fgf`] (the gamma closure
//! of Guo et al. 2019: white, pink, k-fBm), [`Davis`] and [`DavisWeinstein`]
//! (Bitterli et al. 2018). Each implements the [`Transmittance`] trait (the
//! API: `tr`, `pdf`, the four reciprocal functions, `sigma_bar` and the two
//! samplers; its docs hold the table of their meanings). [`Model`] is the
//! closed enum the renderer stores, one per RGB channel; it implements the
//! same trait by `match`, is `Copy` and never allocates.
//!
//! # Layout
//!
//! | file | contents |
//! |---|---|
//! | `api.rs` | the [`Transmittance`] trait |
//! | `exponential.rs`, `fgf.rs`, `davis.rs`, `davis_weinstein.rs` | the four models: parameters, validation, user docs |
//! | `gamma.rs` | `GammaCore`, the gamma closure the last three share (evaluation and samplers) |
//! | `kernels.rs` | `ln_1p`, `g(x)` and its series |
//! | `solver.rs` | the safeguarded root finder and its tolerances |
//! | `start.rs` | the fitted starting points of the pink-noise samplers |
//! | `model.rs` | [`Model`] and the one forwarding layer |
//!
//! # Conventions
//!
//! Everything is in **distance units** for a given mean extinction
//! `sigma_t = σ_m` (1/length): `t` is a distance, `tr(t)` is dimensionless,
//! `pdf(t)` and the `*_medium` functions are densities in 1/length
//! (`docs/theory.md` §4 for the reciprocal functions `T_ss`, `T_sm`, `T_ms`,
//! `T_mm`).
//!
//! Domain: `t ≥ 0` including `t = +inf` (`tr = pdf = T_ms = T_mm = 0`);
//! `t < 0` or NaN gives NaN. Samplers take `u ∈ [0, 1)`; `u = 0` gives
//! `t = 0`. A sampler returns `f64::INFINITY` when the distance exceeds the
//! largest `f64` (e.g. Davis with a tiny `alpha`, where the tail is so heavy
//! that the flight escapes any scene): the renderer treats it as "no
//! collision". `medium_medium(0)` is `+inf` for pink noise and
//! Davis–Weinstein with `1/2 < h < 1`: `T_mm ~ t^(2H)` is integrably singular
//! at the origin.
//!
//! # One parametrisation for all models
//!
//! Every model is a gamma closure `Tr = (1 + x)^(-α)` whose ratio
//! `x(t) = σ_m t / α(t) = t var[σ̄_t] / σ_m` is a power of `t`:
//! `x = k t^e` with `e ∈ [0, 1]`. Then, with `τ = σ_m t` and
//! `g(x) = ln(1+x)/x` (`g(0) = 1`),
//!
//! ```text
//! ln Tr = -α ln(1+x) = -τ g(x)
//! T_sm  = σ_m Tr q(x),            q(x) = (1-e) g(x) + e/(1+x)
//! T_mm  = (σ_m Tr / σ̄) [σ_m q² + e x (-q'(x)) / t]
//! ```
//!
//! | model | `e` | `k` |
//! |---|---|---|
//! | exponential | any (`k = 0`) | 0 |
//! | white noise (`H = -1/2`), DW `h = 1/2` | 0 | `S_w/σ_m`, `c` |
//! | pink noise, DW | `1 + 2H = 2h - 1` | `S_p/σ_m = c^(2h) σ_m^(2h-1)` |
//! | k-fBm, Davis | 1 | `S_kf L^(2H)/σ_m = σ_m/α` |
//!
//! Writing `ln Tr = -τ g(x)` is the stable form of `α log1p(σ_m t/α)`: it
//! has no `0 · ∞` when `α → 0` (white/pink as `t → 0`, Davis with tiny
//! `alpha`) and reduces to `-σ_m t` when `α → ∞` (`x → 0`).

mod api;
mod davis;
mod davis_weinstein;
mod exponential;
mod fgf;
mod gamma;
mod kernels;
mod model;
mod solver;
mod start;

pub use api::Transmittance;
pub use davis::Davis;
pub use davis_weinstein::DavisWeinstein;
pub use exponential::Exponential;
pub use fgf::Fgf;
pub use model::Model;
pub use solver::{BISECT_TOL, MEDIUM_TOL, SAMPLE_MAX_ITER, SURFACE_TOL};
