"""fgf: fractional Gaussian fields for modeling and rendering spatially-correlated media.

The package is numpy-first: every function takes and returns numpy arrays.
The heavy lifting happens in the Rust core (``fgf._core``), with the GIL
released.

Areas:

* transmittance models and FGF statistics: :class:`Fgf`, :class:`Exponential`,
  :class:`Davis`, :class:`DavisWeinstein`;
* field synthesis: :func:`synthesize`, :func:`sample_optical_depth`;
* rendering Mitsuba 3 XML scenes: :func:`render`.
"""

from ._core import FgfError, ParameterError, SceneError, __version__

__all__ = ["FgfError", "ParameterError", "SceneError", "__version__"]

# Each area appends its public names below (one import block per area).
# --- transmittance (issue 2) ---
from .transmittance import (  # noqa: E402
    Davis,
    DavisWeinstein,
    Exponential,
    Fgf,
    TransmittanceModel,
    binom,
    c_const,
    kfbm_point_variance,
    line_average_variance,
    s_kf,
    s_p,
)

__all__ += [
    "Exponential",
    "Fgf",
    "Davis",
    "DavisWeinstein",
    "TransmittanceModel",
    "line_average_variance",
    "c_const",
    "s_p",
    "s_kf",
    "binom",
    "kfbm_point_variance",
]
# --- field (issue 3) ---
from .field import (  # noqa: E402
    covariance,
    discrete_spectral_variance,
    line_average_second_moment,
    padded_shape,
    radial_power_spectrum,
    sample_kfbm_1d,
    sample_optical_depth,
    save_field,
    sw_3d_for_ray_statistics,
    synthesize,
    variogram,
)

__all__ += [
    "synthesize",
    "sample_optical_depth",
    "sample_kfbm_1d",
    "sw_3d_for_ray_statistics",
    "discrete_spectral_variance",
    "padded_shape",
    "variogram",
    "covariance",
    "radial_power_spectrum",
    "line_average_second_moment",
    "save_field",
]
# --- render (issue 4/5) ---
from .render import render, write_exr, write_png  # noqa: E402

__all__ += ["render", "write_exr", "write_png"]
# --- ensemble (issue 5) ---
from .ensemble import ensemble  # noqa: E402

__all__ += ["ensemble"]
