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

import sys as _sys


def _cli_sigint_guard() -> None:
    """When run as the ``fgf`` command, make Ctrl-C during the imports below
    (numpy, the native module: the first fraction of a second) exit with
    code 130 and one line instead of a ``KeyboardInterrupt`` traceback.
    ``fgf.cli.main`` replaces this handler once it can catch the interrupt."""
    import os
    import signal

    argv0 = os.path.basename(_sys.argv[0]) if _sys.argv else ""
    orig = getattr(_sys, "orig_argv", [])
    as_module = argv0 == "-m" and any(
        a == "-m" and i + 1 < len(orig) and orig[i + 1].split(".")[0] == "fgf" for i, a in enumerate(orig)
    )
    if argv0 not in ("fgf", "fgf.exe") and not as_module:
        return
    if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        return

    def interrupted(signum: int, frame: object) -> None:
        os.write(2, b"fgf: interrupted\n")
        os._exit(130)

    signal.signal(signal.SIGINT, interrupted)


_cli_sigint_guard()

# The build of the native module that this CPU runs best (fgf/_native.py).
from . import _native  # noqa: E402

_native.load()
del _native

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
