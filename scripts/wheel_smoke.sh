#!/usr/bin/env bash
# Build the wheel (scripts/build_wheel.sh: the portable module and, on
# x86-64, its x86-64-v3 build) and smoke-test it in a fresh virtual
# environment, with each build it carries.
#
# The wheel runs on any x86-64 / aarch64: no target-cpu=native in it (the
# native build stays the default of scripts/setup.sh). tests/wheel_smoke.py
# asks each build for the vectors it was compiled for: `sse2` for the
# portable one, `avx2` for the x86-64-v3 one. (Cargo's fingerprint records
# are no witness: a build that reuses artifacts made earlier with the same
# flags leaves newer records of other flags as they were.)
# Usage: bash scripts/wheel_smoke.sh   (after scripts/setup.sh --test)
set -euo pipefail
cd "$(dirname "$0")/.."
REPO=$PWD
. .venv/bin/activate
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
start=$(date +%s)
wheel=$(bash scripts/build_wheel.sh "$WORK/dist")
[ -f "$wheel" ] || { echo "wheel_smoke: build_wheel.sh made no wheel" >&2; exit 1; }
built=$(date +%s)
# A fresh venv that sees nothing of .venv: the wheel and its dependencies
# from the package index (pip's cache makes this quick after the first time).
python -m venv "$WORK/venv"
"$WORK/venv/bin/python" -m pip install --quiet --disable-pip-version-check "$wheel"
# Run from outside the repository so that `import fgf` cannot find python/fgf;
# once with the build the CPU picks, once with the portable one.
(cd "$WORK" && "$WORK/venv/bin/python" "$REPO/tests/wheel_smoke.py")
(cd "$WORK" && FGF_PORTABLE=1 "$WORK/venv/bin/python" "$REPO/tests/wheel_smoke.py")
# Every build renders the same images, bit for bit (tests/image_digests.py):
# the wheel's two and the native, profile-guided build of .venv.
python benchmarks/make_mesh_envmap.py >/dev/null
(cd "$WORK" && "$WORK/venv/bin/python" "$REPO/tests/image_digests.py" "$REPO") >"$WORK/wheel.txt"
(cd "$WORK" && FGF_PORTABLE=1 "$WORK/venv/bin/python" "$REPO/tests/image_digests.py" "$REPO") >"$WORK/portable.txt"
python tests/image_digests.py "$REPO" >"$WORK/native.txt"
diff "$WORK/wheel.txt" "$WORK/native.txt" >&2 \
    || { echo "wheel_smoke: the wheel and the native build of .venv render different images (above)" >&2; exit 1; }
diff "$WORK/portable.txt" "$WORK/native.txt" >&2 \
    || { echo "wheel_smoke: the wheel's portable build and the native build of .venv render different images (above)" >&2; exit 1; }
echo "wheel_smoke: the wheel (its $("$WORK/venv/bin/python" -c 'import fgf; print(fgf._core.simd)') build and, with FGF_PORTABLE=1, its portable one) and the native build agree on $(wc -l <"$WORK/native.txt") digests"
echo "wheel_smoke: $(basename "$wheel"): build $((built - start)) s, install + smoke tests $(($(date +%s) - built)) s"
