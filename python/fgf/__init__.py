"""fgf: fractional Gaussian fields for modeling and rendering spatially-correlated media.

The package is numpy-first: every function takes and returns numpy arrays.
The heavy lifting happens in the Rust core (``fgf._core``), with the GIL
released.

Areas:

* transmittance models and FGF statistics: :class:`Fgf`, :class:`Exponential`,
  :class:`Davis`, :class:`DavisWeinstein`;
* field synthesis: :func:`synthesize`, :func:`sample_optical_depth`;
* rendering Mitsuba 3 XML scenes: :func:`render`, and the explicit-realization
  ground truth :func:`ensemble`, and the exact truth of constant-α media
  :func:`truth` (:func:`truth_plan`, :func:`truth_render_node`);
* volumes for other renderers: :func:`write_vdb`, :func:`read_vdb` (OpenVDB)
  and :func:`pbrt_uniformgrid` (pbrt-v4).
"""

from ._core import FgfError, ParameterError, SceneError, __version__

__all__ = ["FgfError", "ParameterError", "SceneError", "__version__"]

# Each area's module lists its public names in its own ``__all__``; the
# package re-exports exactly those.
from . import ensemble as _ensemble  # noqa: E402
from . import field as _field  # noqa: E402
from . import render as _render  # noqa: E402
from . import transmittance as _transmittance  # noqa: E402
from . import truth as _truth  # noqa: E402
from . import vdb as _vdb  # noqa: E402
from .ensemble import *  # noqa: E402,F401,F403
from .field import *  # noqa: E402,F401,F403
from .render import *  # noqa: E402,F401,F403
from .transmittance import *  # noqa: E402,F401,F403
from .truth import *  # noqa: E402,F401,F403
from .vdb import *  # noqa: E402,F401,F403

for _area in (_transmittance, _field, _render, _ensemble, _truth, _vdb):
    __all__ += _area.__all__
del _area
