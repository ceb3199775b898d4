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
# Release build of the native module, installed in editable mode with the
# `fgf` command; in cargo's target folder $1 if given.
build() {
    if [ -n "${1:-}" ]; then
        local CARGO_TARGET_DIR="$1"
        export CARGO_TARGET_DIR
    fi
    maturin develop --release --quiet 2>&1 \
        | grep -v -E '^(📦|🔗|🐍|🍹|💻|📡|🛠|✏️|🔨|Installed|Finished|Compiling|Requirement already satisfied|Ignoring |Looking in links)' || true
    python -c "import fgf._core" || { echo "setup: building the native module failed" >&2; exit 1; }
}
# Profile-guided: built once instrumented, trained on small versions of the
# jobs users run (scripts/pgo-train.sh, ~10 s), then built again with the
# profile (renders 4-12 % faster, images bit-identical; docs/benchmarks.md,
# "Profile-guided build").
# Needs LLVM's llvm-profdata, version 19 or later, which reads the profiles
# of rustc's LLVM (Debian: llvm-19). FGF_PGO=0 skips it.
profdata=""
for v in 25 24 23 22 21 20 19; do
    command -v "llvm-profdata-$v" >/dev/null && { profdata="llvm-profdata-$v"; break; }
done
if [ -z "$profdata" ] && [ "${FGF_PGO:-1}" != 0 ] && command -v apt-get >/dev/null \
    && [ "$(id -u)" = 0 ]; then
    apt-cache show llvm-19 >/dev/null 2>&1 || apt-get -o DPkg::Lock::Timeout=600 update -qq >/dev/null || true
    if DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=600 install -y -qq llvm-19 >/dev/null; then
        profdata=llvm-profdata-19
    fi
fi
if [ "${FGF_PGO:-1}" = 0 ]; then
    build
elif [ -z "$profdata" ]; then
    echo "setup: note: no llvm-profdata >= 19 (Debian: apt-get install llvm-19); building without profile-guided optimisation" >&2
    build
else
    pgo="$PWD/target/pgo"
    # The flag is added to the target's rustflags of .cargo/config.toml
    # (cargo joins them), or to RUSTFLAGS if the caller set those.
    triple_var="CARGO_TARGET_$(rustc -vV | sed -n 's/^host: //p' | tr 'a-z.-' 'A-Z__')_RUSTFLAGS"
    with_flag() ( # flag, command...
        if [ -n "${RUSTFLAGS+set}" ]; then
            export RUSTFLAGS="$RUSTFLAGS $1"
        else
            export "$triple_var=$1"
        fi
        "${@:2}"
    )
    # rustc tracks the profile file: a new one rebuilds every crate. So a
    # profile is kept while what it was trained from is unchanged
    # (scripts/pgo-key.sh), and set-up run again (as scripts/test.sh runs it)
    # then rebuilds nothing. Outside a git checkout there is no key, and
    # every run trains afresh.
    key=$(bash scripts/pgo-key.sh)
    if [ -n "$key" ] && [ -f "$pgo/fgf.profdata" ] && [ "$(cat "$pgo/key" 2>/dev/null)" = "$key" ]; then
        echo "setup: sources unchanged since the last training; building with its profile"
        with_flag "-Cprofile-use=$pgo/fgf.profdata" build
    else
        rm -rf "$pgo"
        mkdir -p "$pgo"
        # The instrumented build has its own target folder, so that the final
        # one reuses the usual target/ (and a later plain build is
        # incremental). Its build scripts' profiles are dropped: only the
        # training's count. If it fails (a toolchain without the profiler
        # runtime, say), or the training does, the plain build is made.
        start=$(date +%s)
        if with_flag "-Cprofile-generate=$pgo/raw" build "$PWD/target/pgo-gen" \
            && rm -rf "$pgo/raw" \
            && bash scripts/pgo-train.sh "$pgo/out" \
            && "$profdata" merge -o "$pgo/fgf.profdata" "$pgo"/raw/*.profraw; then
            echo "setup: instrumented build and training took $(($(date +%s) - start)) s; building with the profile"
            with_flag "-Cprofile-use=$pgo/fgf.profdata" build
            [ -z "$key" ] || echo "$key" >"$pgo/key"
        else
            echo "setup: note: the instrumented build or its training failed; building without profile guidance" >&2
            build
        fi
    fi
fi
