#!/usr/bin/env bash
# Deterministic cost of a render: instructions counted by valgrind's callgrind.
#
#   bash benchmarks/callgrind.sh [SCENE] [SPP] [THREADS] [name=value]...
#
# Defaults: scenes/reference/cube-homogeneous.xml, 16 spp, 1 thread. For the
# mesh scene, write its generated assets first:
#
#   python benchmarks/make_mesh_envmap.py
#   bash benchmarks/callgrind.sh scenes/reference/mesh-envmap.xml 4 1 res=128
#
# Builds the
# `render_scene` example (fgf-render, no Python) in target/callgrind (or
# $CALLGRIND_TARGET_DIR) with
# `-C target-cpu=x86-64-v3` (AVX2: valgrind 3.19 does not run the AVX-512 code
# that this machine's native flags allow, and a fixed CPU level makes counts
# comparable between machines), renders under callgrind with seed 0 and prints
#
#   instructions <total> render <Prepared::render_range, inclusive> per-sample <render / samples> hash <image hash>
#
# `render` and `per-sample` count the thread that called render_range: use them
# with 1 thread (with more, compare the totals). Instruction counts do not
# depend on the machine's load, so two builds can be
# compared while other jobs run; they repeat to about 1e-5 (the thread pool's
# start-up varies a little). The hash is the FNV-1a hash of the image's bits
# (the same for any thread count). Needs valgrind (Debian: apt-get install valgrind).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
scene="${1:-$root/scenes/reference/cube-homogeneous.xml}"
spp="${2:-16}"
threads="${3:-1}"
shift $(( $# < 3 ? $# : 3 ))
command -v valgrind >/dev/null || { echo "callgrind.sh: valgrind is required" >&2; exit 2; }
[ -f "$scene" ] || { echo "callgrind.sh: no scene file $scene" >&2; exit 2; }
export CARGO_TARGET_DIR="${CALLGRIND_TARGET_DIR:-$root/target/callgrind}"
RUSTFLAGS="-C target-cpu=x86-64-v3" cargo build -q --release -p fgf-render --example render_scene \
    --manifest-path "$root/Cargo.toml"
bin="$CARGO_TARGET_DIR/release/examples/render_scene"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" "$bin" "$scene" "$spp" "$threads" "$@" \
    >"$tmp/stdout" 2>"$tmp/stderr" || { cat "$tmp/stderr" >&2; exit 1; }
total=$(grep -o 'Collected : [0-9]*' "$tmp/stderr" | grep -o '[0-9]*$')
# awk reads the whole listing: stopping at the first match (grep -m1) made
# callgrind_annotate die of SIGPIPE on long listings, which pipefail turned
# into a silent exit.
render=$(callgrind_annotate --inclusive=yes "$tmp/cg.out" 2>/dev/null \
    | awk '!done && /fgf_render::render::Prepared::render_range/ {gsub(",", "", $1); print $1; done = 1}')
hash=$(grep -o 'hash [0-9a-f]*' "$tmp/stdout" | cut -d' ' -f2)
samples=$(grep -o 'samples [0-9]*$' "$tmp/stdout" | cut -d' ' -f2)
echo "instructions $total render ${render:-?} per-sample $(awk -v r="${render:-0}" -v n="$samples" 'BEGIN{printf "%.1f", r / n}') hash $hash"
