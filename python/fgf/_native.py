"""Which build of the native module ``fgf._core`` this process loads.

A wheel made by ``scripts/build_wheel.sh`` carries two builds of the module:
the portable one (``_core.<suffix>``, baseline x86-64, which any x86-64 CPU
runs) and one compiled for x86-64-v3 (``_core-x86_64_v3.<suffix>``: AVX2,
FMA and the rest of that level), which renders a mesh lit by an environment
map about 1.6 times as fast (docs/benchmarks.md, "One wheel, two builds").
The name's hyphen keeps the second file from being imported by name.

:func:`load` picks the x86-64-v3 build when the file is there and the CPU and
its operating system run it, else the portable one, and loads the choice
under the name ``fgf._core``, so that every ``from . import _core`` gets it.
The CPU is asked through ``fgf_runs_x86_64_v3``, a plain C function of the
portable build, called through :mod:`ctypes` before either build is imported.
``FGF_PORTABLE=1`` in the environment loads the portable build whatever the
CPU. The builds give the same results bit for bit (the wheel's smoke test
checks it), only the speed differs, so workers of a cluster on different
CPUs still render the same image.

A build made for the machine it runs on (``scripts/setup.sh``, or
``maturin develop``) has no second file: then the module is imported as
usual.
"""

from __future__ import annotations

import ctypes
import importlib.machinery
import importlib.util
import os
import sys
from collections.abc import Callable, Mapping
from types import ModuleType

#: The base name of the x86-64-v3 build, which replaces ``_core`` in the
#: portable build's file name.
V3_STEM = "_core-x86_64_v3"


def v3_path(portable: str) -> str:
    """The file of the x86-64-v3 build beside the portable build ``portable``
    (which may not exist)."""
    where, name = os.path.split(portable)
    assert name.startswith("_core."), name
    return os.path.join(where, V3_STEM + name[len("_core") :])


def choose(portable: str, v3_exists: bool, forced: bool, runs_v3: Callable[[], bool]) -> str:
    """The file to load: the x86-64-v3 build if it is there, not turned off
    (``forced``: the portable one is asked for), and the CPU runs it
    (``runs_v3`` is asked only then); else the portable build."""
    if v3_exists and not forced and runs_v3():
        return v3_path(portable)
    return portable


def forced_portable(environ: Mapping[str, str] = os.environ) -> bool:
    """Whether ``FGF_PORTABLE`` asks for the portable build (set, and not
    ``0`` or empty)."""
    return environ.get("FGF_PORTABLE", "") not in ("", "0")


def cpu_runs_v3(portable: str) -> bool:
    """Whether this CPU runs the x86-64-v3 build, as the portable build's
    ``fgf_runs_x86_64_v3`` says (no build that lacks the function: no)."""
    try:
        fn = ctypes.CDLL(portable).fgf_runs_x86_64_v3
    except (OSError, AttributeError):
        return False
    fn.restype = ctypes.c_int
    fn.argtypes = []
    return bool(fn())


def load() -> ModuleType:
    """Import ``fgf._core`` from the build :func:`choose` picks."""
    name = f"{__package__}._core"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.find_spec(name)
    portable = spec.origin if spec is not None else None
    if portable is None or not os.path.basename(portable).startswith("_core."):
        return importlib.import_module(name)
    path = choose(
        portable,
        os.path.exists(v3_path(portable)),
        forced_portable(),
        lambda: cpu_runs_v3(portable),
    )
    if path == portable:
        return importlib.import_module(name)
    loader = importlib.machinery.ExtensionFileLoader(name, path)
    spec = importlib.util.spec_from_file_location(name, path, loader=loader)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    setattr(sys.modules[__package__], "_core", module)
    return module
