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
    # The reference OpenVDB implementation, for Debian's /usr/bin/python3:
    # tests/test_vdb.py checks fgf's .vdb files with it.
    if ! /usr/bin/python3 -c "import pyopenvdb" 2>/dev/null; then
        if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
            export DEBIAN_FRONTEND=noninteractive
            apt-get -o DPkg::Lock::Timeout=600 update -qq >/dev/null
            apt-get -o DPkg::Lock::Timeout=600 install -y -qq python3-openvdb >/dev/null
        else
            echo "setup: note: python3-openvdb (Debian, needs root) is not installed; the OpenVDB reference checks will be skipped" >&2
        fi
    fi
else
    python -m pip install --quiet --disable-pip-version-check "maturin>=1.5,<2" "numpy>=1.24" "scipy>=1.10" "matplotlib>=3.7" "tqdm>=4.60"
fi
# Release build of the native module, installed in editable mode with the `fgf` command.
maturin develop --release --quiet 2>&1 | grep -v -E '^(📦|🔗|🐍|💻|📡|🛠|✏️|🔨|Installed|Finished|Compiling)' || true
python -c "import fgf._core" || { echo "setup: building the native module failed" >&2; exit 1; }
