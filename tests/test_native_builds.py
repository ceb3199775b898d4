"""Which build of the native module ``import fgf`` loads (fgf/_native.py).

A wheel carries the portable build and an x86-64-v3 one; scripts/wheel_smoke.sh
installs one and checks that each is loaded where it should be and that both
render the same images. These tests cover the choice itself, and the CPU
question against the kernel's own list of the CPU's features.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys

import pytest

import fgf
from fgf import _native

SO = "_core.cpython-311-x86_64-linux-gnu.so"


def test_the_v3_build_sits_beside_the_portable_one_under_a_name_no_import_finds() -> None:
    path = _native.v3_path(os.path.join("/site", "fgf", SO))
    assert path == os.path.join("/site", "fgf", "_core-x86_64_v3.cpython-311-x86_64-linux-gnu.so")
    assert not os.path.basename(path).split(".")[0].isidentifier()


@pytest.mark.parametrize(
    ("v3_exists", "forced", "runs_v3", "want_v3", "asked"),
    [
        (True, False, True, True, True),
        (True, False, False, False, True),
        # FGF_PORTABLE=1, or no second build: the CPU is not even asked.
        (True, True, True, False, False),
        (False, False, True, False, False),
    ],
)
def test_choose_takes_the_v3_build_only_when_it_is_there_allowed_and_runnable(
    v3_exists: bool, forced: bool, runs_v3: bool, want_v3: bool, asked: bool
) -> None:
    portable = os.path.join("/site", "fgf", SO)
    calls = []

    def ask() -> bool:
        calls.append(1)
        return runs_v3

    got = _native.choose(portable, v3_exists, forced, ask)
    assert got == (_native.v3_path(portable) if want_v3 else portable)
    assert len(calls) == int(asked)


@pytest.mark.parametrize(
    ("environ", "forced"),
    [({}, False), ({"FGF_PORTABLE": ""}, False), ({"FGF_PORTABLE": "0"}, False), ({"FGF_PORTABLE": "1"}, True)],
)
def test_fgf_portable_forces_the_portable_build(environ: dict[str, str], forced: bool) -> None:
    assert _native.forced_portable(environ) is forced


def test_the_cpu_question_agrees_with_the_kernels_feature_list() -> None:
    """``fgf_runs_x86_64_v3`` of the loaded build against /proc/cpuinfo's
    flags (the kernel's names: ``abm`` is LZCNT, ``pni`` SSE3, ``cx16``
    CMPXCHG16B; it lists AVX only where the OS saves the AVX state)."""
    runs = _native.cpu_runs_v3(fgf._core.__file__)
    if platform.machine() != "x86_64":
        assert runs is False
        return
    if not os.path.exists("/proc/cpuinfo"):
        pytest.skip("no /proc/cpuinfo to check the CPU's features against")
    with open("/proc/cpuinfo") as fh:
        flags = next(line for line in fh if line.startswith("flags")).split(":", 1)[1].split()
    v3 = {"avx", "avx2", "bmi1", "bmi2", "cx16", "f16c", "fma", "abm", "movbe", "popcnt"}
    v3 |= {"pni", "sse4_1", "sse4_2", "ssse3", "xsave"}
    assert runs is v3.issubset(flags), sorted(v3 - set(flags))


def test_a_build_for_this_machine_carries_no_second_build() -> None:
    """scripts/setup.sh's build (``maturin develop``) sits alone, and
    ``import fgf`` imported it as usual."""
    where, name = os.path.split(fgf._core.__file__)
    assert name.startswith("_core."), name
    assert not os.path.exists(_native.v3_path(fgf._core.__file__))
    assert fgf._core.simd in ("avx512", "avx2", "sse2", "neon", "scalar"), fgf._core.simd


def test_version_names_the_build() -> None:
    out = subprocess.run(
        [sys.executable, "-m", "fgf", "--version"], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert out == f"fgf {fgf.__version__} ({fgf._core.simd})", out
