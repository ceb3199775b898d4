#!/usr/bin/env bash
# Nanoseconds per transmittance evaluation and per free-flight sample, for
# each model (Rust, divan; crates/fgf-core/benches/transmittance.rs).
# Usage: bash benchmarks/transmittance.sh
# Each divan iteration processes a batch of 1024 calls; this script divides
# divan's median by 1024 and prints one table (ns per call, one core).
set -euo pipefail
cd "$(dirname "$0")/.."
BATCH=1024
out=$(cargo bench -q -p fgf-core --bench transmittance 2>/dev/null)
python3 - "$BATCH" <<PY
import re, sys
batch = int(sys.argv[1])
text = """$out"""
unit = {"ns": 1.0, "µs": 1e3, "us": 1e3, "ms": 1e6, "s": 1e9}
group, rows = None, {}
for line in text.splitlines():
    m = re.match(r"^[├╰]─ (\w+)\s", line)
    if m:
        group = m.group(1)
        continue
    m = re.match(r"^[│ ]\s+[├╰]─ (\w+)\s+(\S+) (\S+)\s+│\s+(\S+) (\S+)\s+│\s+(\S+) (\S+)", line)
    if m and group:
        name, med, med_u = m.group(1), m.group(6), m.group(7)
        rows.setdefault(name, {})[group] = float(med) * unit[med_u] / batch
cols = ["tr", "pdf", "sample_surface", "sample_medium"]
print(f"{'model':<18}" + "".join(f"{c:>16}" for c in cols) + "   (ns per call, median)")
for name, r in rows.items():
    print(f"{name:<18}" + "".join(f"{r.get(c, float('nan')):>16.1f}" for c in cols))
PY
