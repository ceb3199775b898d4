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
    # System packages the tests need, from Debian (we run as root on CI):
    # - libllvm19: Mitsuba's llvm_ad_rgb variant (tests/test_mitsuba_plugin.py);
    #   Dr.Jit aborts with Debian 12's default LLVM 15;
    # - python3-openvdb: the reference OpenVDB implementation for Debian's
    #   /usr/bin/python3, the independent reader of tests/test_vdb.py.
    apt_pkgs=""
    [ -e /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 ] || apt_pkgs="$apt_pkgs libllvm19"
    /usr/bin/python3 -c "import pyopenvdb" 2>/dev/null || apt_pkgs="$apt_pkgs python3-openvdb"
    if [ -n "$apt_pkgs" ]; then
        if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
            export DEBIAN_FRONTEND=noninteractive
            apt-get -o DPkg::Lock::Timeout=600 update -qq >/dev/null
            # shellcheck disable=SC2086
            apt-get -o DPkg::Lock::Timeout=600 install -y -qq $apt_pkgs >/dev/null
        else
            echo "setup: error: the tests need Debian's$apt_pkgs (run as root, or install them)" >&2
            exit 1
        fi
    fi
else
    python -m pip install --quiet --disable-pip-version-check "maturin>=1.5,<2" "numpy>=1.24" "scipy>=1.10" "matplotlib>=3.7" "tqdm>=4.60"
fi
# Release build of the native module, installed in editable mode with the `fgf` command.
maturin develop --release --quiet 2>&1 | grep -v -E '^(📦|🔗|🐍|💻|📡|🛠|✏️|🔨|Installed|Finished|Compiling)' || true
python -c "import fgf._core" || { echo "setup: building the native module failed" >&2; exit 1; }
