#!/usr/bin/env bash
# Install everything and run every test: the lint gates (rustfmt, clippy,
# rustdoc, mypy), Rust unit/property tests, the Python suite, then the slow
# statistical tests in their own release-mode step.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --test
. .venv/bin/activate
echo "== lint: cargo fmt --check, cargo clippy -D warnings, cargo doc -D warnings, mypy, stubtest"
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --release -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps -q
python -m mypy python/fgf benchmarks
# The native module's stub against the module itself.
python -m mypy.stubtest fgf._core
echo "== cargo test (workspace)"
cargo test --workspace --exclude fgf-py --release
echo "== pytest (fast)"
python -m pytest -q -m "not slow"
echo "== wheel: its portable and x86-64-v3 builds, fresh venv, smoke tests"
bash scripts/wheel_smoke.sh
echo "== slow statistical tests"
cargo test --workspace --exclude fgf-py --release -- --ignored
python -m pytest -q -m slow
echo "== fuzz: coverage-guided parsers (XML + includes/defaults, .vol, OBJ, PLY), 60 s each"
bash scripts/fuzz.sh 60
