//! [`Model`], the closed enum the renderer stores (one per RGB channel),
//! and the one forwarding layer of the [`Transmittance`] API: the gamma-core
//! models forward to their core, `Model` dispatches by `match`, both through
//! `forward_transmittance!`.

use super::api::Transmittance;
use super::davis::Davis;
use super::davis_weinstein::DavisWeinstein;
use super::exponential::Exponential;
use super::fgf::Fgf;

/// A transmittance model of any kind, dispatched by `match` (no `dyn` in the
/// renderer's inner loop). `Copy`, allocation-free; construct it from a
/// validated model with `Model::from(...)`. Its methods are those of
/// [`Transmittance`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Model {
    Exponential(Exponential),
    Fgf(Fgf),
    Davis(Davis),
    DavisWeinstein(DavisWeinstein),
}

/// `$e` with `$m` bound to the model inside the [`Model`] `$self`.
macro_rules! dispatch {
    ($self:ident, $m:ident => $e:expr) => {
        match $self {
            Model::Exponential($m) => $e,
            Model::Fgf($m) => $e,
            Model::Davis($m) => $e,
            Model::DavisWeinstein($m) => $e,
        }
    };
}

/// `$e` with `$m` bound to the gamma core of the model `$self`.
macro_rules! via_core {
    ($self:ident, $m:ident => $e:expr) => {{
        let $m = &$self.core;
        $e
    }};
}

/// Implements [`Transmittance`] for each `$ty` by handing every call to
/// `$fwd!(self, m => m.method(...))` (`surface_surface` and
/// `surface_medium` are the trait's defaults). The one list of forwarded
/// methods.
macro_rules! forward_transmittance {
    ($fwd:ident: $($ty:ty),+) => {$(
        impl Transmittance for $ty {
            #[inline]
            fn tr(&self, t: f64) -> f64 {
                $fwd!(self, m => m.tr(t))
            }
            #[inline]
            fn pdf(&self, t: f64) -> f64 {
                $fwd!(self, m => m.pdf(t))
            }
            #[inline]
            fn medium_surface(&self, t: f64) -> f64 {
                $fwd!(self, m => m.medium_surface(t))
            }
            #[inline]
            fn medium_medium(&self, t: f64) -> f64 {
                $fwd!(self, m => m.medium_medium(t))
            }
            #[inline]
            fn sigma_bar(&self) -> f64 {
                $fwd!(self, m => m.sigma_bar())
            }
            #[inline]
            fn sigma_t(&self) -> f64 {
                $fwd!(self, m => m.sigma_t())
            }
            #[inline]
            fn sample_surface(&self, u: f64) -> f64 {
                $fwd!(self, m => m.sample_surface(u))
            }
            #[inline]
            fn sample_medium(&self, u: f64) -> f64 {
                $fwd!(self, m => m.sample_medium(u))
            }
        }
    )+};
}

forward_transmittance!(via_core: Fgf, Davis, DavisWeinstein);
forward_transmittance!(dispatch: Model);

impl From<Exponential> for Model {
    fn from(m: Exponential) -> Self {
        Model::Exponential(m)
    }
}
impl From<Fgf> for Model {
    fn from(m: Fgf) -> Self {
        Model::Fgf(m)
    }
}
impl From<Davis> for Model {
    fn from(m: Davis) -> Self {
        Model::Davis(m)
    }
}
impl From<DavisWeinstein> for Model {
    fn from(m: DavisWeinstein) -> Self {
        Model::DavisWeinstein(m)
    }
}
