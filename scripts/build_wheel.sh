#!/usr/bin/env bash
# Build fgf's wheel into OUT (default: dist/).
#
# The wheel runs on any CPU of its platform: its native module is built
# portably (RUSTFLAGS, set here, replaces the target-cpu=native of
# .cargo/config.toml). On x86-64 it also carries a second build of the
# module, compiled for x86-64-v3 (AVX2, FMA, ...), which `import fgf` loads
# where the CPU runs it (python/fgf/_native.py): a mesh lit by an environment
# map renders about 1.6 times as fast with it (docs/benchmarks.md, "One wheel,
# two builds"). The two builds give the same results bit for bit
# (scripts/wheel_smoke.sh checks it).
#
# Each build has its own target directory (target/wheel, target/wheel-v3),
# so that the flag sets do not evict each other's artifacts; a second run only
# rebuilds what changed. Needs maturin and wheel (scripts/setup.sh --test
# installs both).
# Usage: bash scripts/build_wheel.sh [OUT]
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-dist}
mkdir -p "$OUT"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
# maturin's chatter filtered, the rest to stderr: stdout is the wheel's path.
quiet() { grep -v -E '^(📦|🔗|🐍|🍹|💻|📡|🛠|✏️|🔨|Finished|Compiling)' >&2 || true; }
RUSTFLAGS= CARGO_TARGET_DIR=target/wheel maturin build --release --quiet --out "$WORK/portable" 2>&1 | quiet
wheel=$(ls "$WORK"/portable/fgf-*.whl 2>/dev/null | head -n 1)
[ -n "$wheel" ] || { echo "build_wheel: maturin build made no wheel" >&2; exit 1; }
if [ "$(uname -m)" != x86_64 ]; then
    cp "$wheel" "$OUT/"
    echo "$OUT/$(basename "$wheel")"
    exit 0
fi
# The x86-64-v3 build is profile-guided with the profile of scripts/setup.sh's
# build (ARCHITECTURE.md, "Build") when it was trained from these very
# sources: on the homogeneous cube that is 17 % less time. A few functions
# whose code differs from the native build's are compiled without it, which
# LLVM would warn of one by one. The portable build, whose lanes differ from
# the native build's throughout, is not: the profile made it 10 % slower there.
pgo=""
if [ "${FGF_PGO:-1}" != 0 ] && [ -f target/pgo/fgf.profdata ] \
    && [ "$(cat target/pgo/key 2>/dev/null)" = "$(bash scripts/pgo-key.sh)" ]; then
    pgo="-Cprofile-use=$PWD/target/pgo/fgf.profdata -Cllvm-args=-no-pgo-warn-mismatch"
    echo "build_wheel: the x86-64-v3 build is profile-guided (target/pgo/fgf.profdata)" >&2
else
    echo "build_wheel: note: no profile trained from these sources (scripts/setup.sh makes one); building without profile guidance" >&2
fi
RUSTFLAGS="-C target-cpu=x86-64-v3 $pgo" CARGO_TARGET_DIR=target/wheel-v3 \
    maturin build --release --quiet --out "$WORK/v3" 2>&1 | quiet
v3=$(ls "$WORK"/v3/fgf-*.whl 2>/dev/null | head -n 1)
[ -n "$v3" ] || { echo "build_wheel: maturin build (x86-64-v3) made no wheel" >&2; exit 1; }
# The portable wheel, unpacked, gets the x86-64-v3 build's module as
# fgf/_core-x86_64_v3.<suffix>; `wheel pack` writes its RECORD anew.
python -m wheel unpack --dest "$WORK/tree" "$wheel" >/dev/null
python - "$v3" "$WORK/tree" <<'PY'
import pathlib, sys, zipfile

v3, tree = sys.argv[1], pathlib.Path(sys.argv[2])
(root,) = [p for p in tree.iterdir() if p.is_dir()]
with zipfile.ZipFile(v3) as z:
    (member,) = [n for n in z.namelist() if n.startswith("fgf/_core.") and not n.endswith(".pyi")]
    name = pathlib.PurePosixPath(member).name
    (root / "fgf" / ("_core-x86_64_v3" + name[len("_core"):])).write_bytes(z.read(member))
PY
python -m wheel pack --dest-dir "$OUT" "$WORK"/tree/fgf-* >/dev/null
echo "$OUT/$(basename "$wheel")"
