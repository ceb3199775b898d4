#!/usr/bin/env bash
# Build the portable wheel and smoke-test it in a fresh virtual environment.
#
# `maturin build --release` with an empty RUSTFLAGS, which replaces the
# target-cpu=native of .cargo/config.toml: the wheel runs on any x86-64 /
# aarch64 (the native build stays the default of scripts/setup.sh). It uses
# its own target directory, target/wheel, so that the two flag sets do not
# evict each other's build artifacts; a second run only rebuilds what changed.
# Usage: bash scripts/wheel_smoke.sh   (after scripts/setup.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
REPO=$PWD
. .venv/bin/activate
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
start=$(date +%s)
RUSTFLAGS= CARGO_TARGET_DIR=target/wheel maturin build --release --quiet --out "$WORK/dist" 2>&1 \
    | grep -v -E '^(📦|🔗|🐍|💻|📡|🛠|✏️|🔨|Finished|Compiling)' || true
wheel=$(ls "$WORK"/dist/fgf-*.whl 2>/dev/null | head -n 1)
[ -n "$wheel" ] || { echo "wheel_smoke: maturin build made no wheel" >&2; exit 1; }
built=$(date +%s)
# No target-cpu=native in the wheel: cargo records each crate's flags.
python - <<'PY'
import glob, json, sys
prints = glob.glob("target/wheel/release/.fingerprint/fgf-core-*/lib-fgf_core.json")
flags = {tuple(json.load(open(p)).get("rustflags", [])) for p in prints}
if not prints or any("native" in " ".join(f) for f in flags):
    sys.exit(f"wheel_smoke: the wheel was not built portably (rustflags {flags or 'not found'})")
PY
# A fresh venv that sees nothing of .venv: the wheel and its dependencies
# from the package index (pip's cache makes this quick after the first time).
python -m venv "$WORK/venv"
"$WORK/venv/bin/python" -m pip install --quiet --disable-pip-version-check "$wheel"
# Run from outside the repository so that `import fgf` cannot find python/fgf.
(cd "$WORK" && "$WORK/venv/bin/python" "$REPO/tests/wheel_smoke.py")
# The portable wheel and the native, profile-guided build of .venv render
# the same images, bit for bit (tests/image_digests.py).
python benchmarks/make_mesh_envmap.py >/dev/null
(cd "$WORK" && "$WORK/venv/bin/python" "$REPO/tests/image_digests.py" "$REPO") >"$WORK/wheel.txt"
python tests/image_digests.py "$REPO" >"$WORK/native.txt"
diff "$WORK/wheel.txt" "$WORK/native.txt" >&2 \
    || { echo "wheel_smoke: the portable wheel and the native build of .venv render different images (above)" >&2; exit 1; }
echo "wheel_smoke: the portable wheel and the native build agree on $(wc -l <"$WORK/native.txt") digests"
echo "wheel_smoke: $(basename "$wheel"): build $((built - start)) s, install + smoke test $(($(date +%s) - built)) s"
