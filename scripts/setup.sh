#!/usr/bin/env bash
# Install everything fgf needs into ./.venv and build the native module.
# Usage: bash scripts/setup.sh [--test]   (--test adds the test dependencies)
set -euo pipefail
cd "$(dirname "$0")/.."
command -v cargo >/dev/null || { echo "setup: Rust (cargo) is required: https://rustup.rs" >&2; exit 1; }
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PY" -m venv .venv
fi
. .venv/bin/activate
python -m pip install --quiet --disable-pip-version-check --upgrade pip
if [ "${1:-}" = "--test" ]; then
    python -m pip install --quiet --disable-pip-version-check -r requirements-dev.txt
    # Mitsuba's llvm_ad_rgb variant (tests/test_mitsuba_plugin.py) needs LLVM 19:
    # Dr.Jit aborts with Debian 12's default LLVM 15.
    if [ ! -e /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 ] && command -v apt-get >/dev/null; then
        { apt-get update -qq && apt-get install -y -qq libllvm19 >/dev/null; } \
            || { echo "setup: installing libllvm19 failed (needs root); the llvm_ad_rgb tests will fail" >&2; }
    fi
else
    python -m pip install --quiet --disable-pip-version-check "maturin>=1.5,<2" "numpy>=1.24" "scipy>=1.10" "matplotlib>=3.7" "tqdm>=4.60"
fi
# Release build of the native module, installed in editable mode with the `fgf` command.
maturin develop --release --quiet 2>&1 | grep -v -E '^(📦|🔗|🐍|💻|📡|🛠|✏️|🔨|Installed|Finished|Compiling)' || true
python -c "import fgf._core" || { echo "setup: building the native module failed" >&2; exit 1; }
