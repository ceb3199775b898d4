"""fgf media inside Mitsuba 3 (``docs/theory.md`` §3–4; user guide: ``docs/mitsuba.md``).

After ``import fgf.mitsuba`` a Mitsuba 3 scene can declare the media ``fgf``
and ``nonexponential`` (the parameters of fgf's own scene loader) and the
integrator ``fgf_volpath``, which samples their non-exponential free flights
with the energy-conserving or the reciprocal kernel::

    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    import fgf.mitsuba  # registers fgf, nonexponential and fgf_volpath
    scene = mi.load_file("scene.xml")
    img = mi.render(scene, spp=64)

The plugins are registered for the variant that is current at import and,
through Mitsuba's variant callbacks, for every RGB variant set afterwards;
:func:`register` does it explicitly.
"""

from __future__ import annotations

import importlib
from typing import Any, Optional

from ._params import MediumParameterError

__all__ = ["register", "registered_variants", "MediumParameterError", "MEDIA", "INTEGRATORS"]

#: The plugin names this package registers.
MEDIA = ("fgf", "nonexponential")
INTEGRATORS = ("fgf_volpath",)

_registered: set[str] = set()


def register(variant: Optional[str] = None) -> bool:
    """Register the ``fgf`` and ``nonexponential`` media and the
    ``fgf_volpath`` integrator with Mitsuba for the current variant.

    Parameters
    ----------
    variant : str, optional
        Must equal the current variant when given (a check, not a switch).

    Returns
    -------
    bool
        False when no variant is set yet or the variant is not an RGB one
        (``scalar_rgb``, ``llvm_ad_rgb``, ``cuda_ad_rgb``): nothing is
        registered. True otherwise; registering twice is harmless.
    """
    mi = _mitsuba()
    current = mi.variant()
    if current is None:
        return False
    if variant is not None and variant != current:
        raise ValueError(f"register({variant!r}): the current Mitsuba variant is {current!r}")
    if current in _registered:
        return True
    if not current.endswith("_rgb"):
        # The integrator works in RGB (three channels, hero-channel MIS).
        return False
    from ._plugins import make_plugins

    fgf_medium, nonexp_medium, integrator = make_plugins()
    mi.register_medium("fgf", fgf_medium)
    mi.register_medium("nonexponential", nonexp_medium)
    mi.register_integrator("fgf_volpath", integrator)
    _registered.add(current)
    return True


def registered_variants() -> frozenset[str]:
    """The variants for which the plugins are registered."""
    return frozenset(_registered)


def _on_variant_change(old: Optional[str], new: Optional[str]) -> None:
    if new is not None:
        register()


def _mitsuba() -> Any:
    # Imported as `Any`: Mitsuba's stubs describe one variant only.
    try:
        return importlib.import_module("mitsuba")
    except ImportError as e:
        raise ImportError(f"fgf.mitsuba needs Mitsuba 3 (pip install mitsuba==3.9.1): {e}") from e


def _install() -> None:
    mi = _mitsuba()
    mi.detail.add_variant_callback(_on_variant_change)
    register()


_install()
