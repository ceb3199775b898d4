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
# --- field (issue 3) ---
# --- render (issue 4/5) ---
