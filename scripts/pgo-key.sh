#!/usr/bin/env bash
# Print the key of the profile that scripts/setup.sh trains (target/pgo/key):
# a hash of what the profile was trained from, i.e. the toolchain, RUSTFLAGS,
# and the tracked and modified files of the sources, the Python package, the
# scenes and the training. setup.sh keeps a profile while its key is
# unchanged; scripts/build_wheel.sh uses it only then. Prints nothing
# outside a git checkout (no key: every set-up trains afresh).
set -euo pipefail
cd "$(dirname "$0")/.."
git rev-parse --is-inside-work-tree >/dev/null 2>&1 || exit 0
inputs="crates Cargo.toml Cargo.lock .cargo python scenes scripts/setup.sh scripts/pgo-key.sh scripts/pgo-train.sh benchmarks/make_mesh_envmap.py"
# shellcheck disable=SC2086
{ rustc -vV; echo "RUSTFLAGS=${RUSTFLAGS-(unset)}"; git ls-files -s -- $inputs
    git diff HEAD -- $inputs; git ls-files -o --exclude-standard -- $inputs; } | sha256sum | cut -d' ' -f1
