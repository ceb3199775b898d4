#!/usr/bin/env bash
# Coverage-guided fuzzing of the parsers (fuzz/: XML with includes and
# defaults, .vol, OBJ, PLY) for a bounded time each: libFuzzer through
# libfuzzer-sys, built with a nightly toolchain and SanitizerCoverage
# instrumentation (the flags cargo-fuzz passes; cargo-fuzz itself is not
# needed). Usage: bash scripts/fuzz.sh [SECONDS_PER_TARGET]  (default 60).
# A crash leaves its input in fuzz/artifacts/ and fails the script.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-60}
if ! rustup toolchain list | grep -q '^nightly'; then
    echo "fuzz: error: needs a nightly toolchain (rustup toolchain install nightly)" >&2
    exit 1
fi
export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -Cdebug-assertions -Coverflow-checks"
# An explicit --target keeps the instrumentation off build scripts and proc macros.
triple=$(rustc +nightly -vV | sed -n 's/^host: //p')
CARGO_TARGET_DIR=target/fuzz cargo +nightly build --quiet --release --manifest-path fuzz/Cargo.toml --bins --target "$triple"
mkdir -p fuzz/artifacts
for t in xml vol obj ply; do
    work=$(mktemp -d)
    cp fuzz/corpus/$t/* "$work"/
    echo "== fuzz $t for ${secs}s"
    # -rss_limit_mb: an input that makes a parser allocate past 2 GB is a bug too.
    set +e
    target/fuzz/"$triple"/release/$t "$work" -max_total_time="$secs" -rss_limit_mb=2048 -max_len=65536 \
        -artifact_prefix=fuzz/artifacts/$t- -print_final_stats=1 > "$work/log" 2>&1
    status=$?
    set -e
    grep -E "^(#[0-9]+ *DONE|stat::number_of_executed_units|stat::peak_rss_mb|==[0-9]+==|SUMMARY|thread .* panicked)" "$work/log" || true
    rm -rf "$work"
    if [ "$status" != 0 ]; then
        echo "fuzz: $t found a crash (exit $status); input in fuzz/artifacts/" >&2
        exit 1
    fi
done
