#!/usr/bin/env python3
"""Mitsuba 3's ``llvm_ad_rgb`` with narrower vectors: a scene rendered in one process, as
its CLI renders it, with Dr.Jit's kernels eight lanes wide and without AVX-512.

    python benchmarks/mitsuba_narrow.py SCENE OUT.exr [-D name=value]... [--threads N]
                                        [--width 8|16|0] [--embree-isa avx2] [--verbose]

What for: on a CPU with AVX-512, Mitsuba's LLVM backend runs sixteen paths per
instruction and Embree picks its AVX-512 kernels. This renders the same scene as an
AVX2-only CPU of the same make would, so that ``bench_render.py --narrow-mitsuba`` can say,
on one machine, how much of Mitsuba's speed the wide vectors give (docs/benchmarks.md,
"What AVX-512 gives Mitsuba on an Intel Xeon").

- ``--width`` (default 8): the vector width of Dr.Jit's LLVM backend. With 8, the
  AVX-512 features are also taken off its target, so its kernels use AVX2 alone. 0
  leaves the backend as Mitsuba sets it (a control: this script against the CLI).
  Dr.Jit's Python bindings do not expose the setting; its C++ function
  ``jit_llvm_set_target`` is exported by ``libdrjit-core.so`` and called here through
  ``ctypes``.
- ``--embree-isa avx2``: Embree's kernels as well. Embree takes its ISA only from the
  configuration string that Mitsuba passes to ``rtcNewDevice``. A small shared library,
  compiled here with ``gcc`` into ``target/mitsuba-narrow/``, is put before Mitsuba's
  libraries with ``LD_PRELOAD`` and appends ``isa=…`` to that string. (Mitsuba's wheel
  builds Embree in the C++ namespace ``mitsuba``, hence the symbol's mangled name.)
  ``--verbose`` asks Embree to print the ISA it uses.

``--threads 1`` hangs, as ``mitsuba -t 1`` of the same wheel does on our machines (Mitsuba's
CLI, asked for a 16² render with `-t 1`, was still running after 30 s); two threads and
more work.

The image is the one Mitsuba's CLI renders (the same scene, parameters and seed); only
the vectors differ. Bad arguments exit with status 2 and one line.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any, NoReturn

ROOT = Path(__file__).resolve().parent.parent
LLVM19 = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
SHIM_ENV = "MITSUBA_NARROW_EMBREE"

# Appends `isa=<ISA>` (and `verbose=1` if asked) to Embree's device configuration.
SHIM_C = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
typedef void *(*new_device_fn)(const char *);
void *narrow_new_device(const char *cfg) __asm__("_ZN7mitsuba12rtcNewDeviceEPKc");
void *narrow_new_device(const char *cfg) {
    static char buf[4096];
    const char *lib = getenv("MITSUBA_NARROW_EMBREE_LIB");
    void *h = lib ? dlopen(lib, RTLD_NOW | RTLD_NOLOAD) : NULL;
    new_device_fn real = h ? (new_device_fn)dlsym(h, "_ZN7mitsuba12rtcNewDeviceEPKc") : NULL;
    if (!real) {
        fprintf(stderr, "mitsuba_narrow: Embree's rtcNewDevice not found in %s\n", lib ? lib : "(unset)");
        exit(2);
    }
    snprintf(buf, sizeof buf, "%s%sisa=%s%s", cfg ? cfg : "", cfg && *cfg ? "," : "",
             getenv("MITSUBA_NARROW_EMBREE"), getenv("MITSUBA_NARROW_VERBOSE") ? ",verbose=1" : "");
    setenv("MITSUBA_NARROW_APPLIED", buf, 1); /* for the script's check that this ran */
    return real(buf);
}
"""


def fail(msg: str) -> NoReturn:
    print(f"mitsuba_narrow: {msg}", file=sys.stderr)
    raise SystemExit(2)


def shim() -> Path:
    """The preloaded library, compiled if it is missing or older than this script."""
    out = ROOT / "target" / "mitsuba-narrow" / "embree_isa.so"
    if out.exists() and out.stat().st_mtime >= Path(__file__).stat().st_mtime:
        return out
    gcc = shutil.which("gcc")
    if gcc is None:
        fail("--embree-isa needs gcc to compile its preloaded library (apt-get install -y gcc)")
    out.parent.mkdir(parents=True, exist_ok=True)
    src = out.with_suffix(".c")
    src.write_text(SHIM_C)
    tmp = out.with_suffix(".so.tmp")
    r = subprocess.run([gcc, "-O2", "-shared", "-fPIC", "-o", str(tmp), str(src), "-ldl"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"gcc could not compile {src}: {r.stderr.strip().splitlines()[-1:]}")
    tmp.replace(out)
    return out


def set_llvm_width(width: int) -> None:
    """Dr.Jit's LLVM backend at `width` lanes (without AVX-512 below 16)."""
    import drjit as dr

    dr.eval(dr.llvm.Float([1.0, 2.0]) + 1.0)  # the backend starts on first use
    lib = ctypes.CDLL(str(Path(dr.__file__).parent / "libdrjit-core.so"))
    try:
        cpu, features, get_width, set_target = (
            lib._Z19jit_llvm_target_cpuv, lib._Z24jit_llvm_target_featuresv,
            lib._Z21jit_llvm_vector_widthv, lib._Z19jit_llvm_set_targetPKcS0_j)
    except AttributeError as e:
        fail(f"this Dr.Jit does not export the function the script calls ({e}); written for Mitsuba 3.9.1")
    cpu.restype = features.restype = ctypes.c_char_p
    get_width.restype = ctypes.c_uint32
    feats = features().decode()
    if width < 16:
        feats = ",".join("-" + f[1:] if f.startswith(("+avx512", "+evex512")) else f for f in feats.split(","))
    set_target(cpu(), feats.encode(), ctypes.c_uint32(width))
    if get_width() != width:
        fail(f"Dr.Jit's LLVM backend did not take width {width} (it has {get_width()})")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("-D", dest="defines", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--width", type=int, default=8, choices=[0, 8, 16])
    ap.add_argument("--embree-isa", default=None, choices=["avx2", "avx", "sse4.2"])
    ap.add_argument("--verbose", action="store_true")
    args = ap.parse_args()
    if not args.scene.is_file():
        fail(f"{args.scene}: no such scene file")
    # (Strings, as the XML holds them; typed Any for load_file's keyword parameters.)
    params: dict[str, Any] = {}
    for d in args.defines:
        name, sep, value = d.partition("=")
        if not sep or not name:
            fail(f"-D {d!r}: expected NAME=VALUE")
        params[name] = value
    if args.threads is not None and args.threads < 1:
        fail(f"--threads {args.threads}: must be >= 1")
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM19)
    try:
        import mitsuba
    except ImportError:
        fail("needs Mitsuba 3 in this Python (scripts/setup.sh --test installs mitsuba==3.9.1)")
    if args.embree_isa and os.environ.get(SHIM_ENV) != args.embree_isa:
        # Preload the library and start again: LD_PRELOAD is read when a process starts.
        lib = shim()
        env = dict(os.environ, LD_PRELOAD=f"{lib}:{os.environ.get('LD_PRELOAD', '')}".rstrip(":"))
        env[SHIM_ENV] = args.embree_isa
        env.pop("MITSUBA_NARROW_APPLIED", None)
        env["MITSUBA_NARROW_EMBREE_LIB"] = str(Path(mitsuba.__file__).parent / "libembree3.so")
        if args.verbose:
            env["MITSUBA_NARROW_VERBOSE"] = "1"
        os.execve(sys.executable, [sys.executable, __file__, *sys.argv[1:]], env)
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    if args.threads is not None:
        dr.set_thread_count(args.threads)
    if args.width:
        set_llvm_width(args.width)
    try:
        scene = mi.load_file(str(args.scene), **params)
    except Exception as e:  # Mitsuba reports bad scenes and parameters as exceptions
        fail(f"{args.scene}: {str(e).strip().splitlines()[-1] if str(e).strip() else type(e).__name__}")
    if args.embree_isa:
        # The preloaded library marks the process when Mitsuba creates Embree's device
        # through it (at the first scene); if Mitsuba's symbol were another, Embree
        # would run at its own ISA without a word.
        libc = ctypes.CDLL(None)
        libc.getenv.restype = ctypes.c_char_p
        applied = libc.getenv(b"MITSUBA_NARROW_APPLIED")
        if not applied or f"isa={args.embree_isa}".encode() not in applied:
            fail("Embree's device was not made through the preloaded library; written for Mitsuba 3.9.1")
    image = mi.render(scene)
    mi.Bitmap(image).write(str(args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
