#!/usr/bin/env bash
# Install everything and run the main job: write out/ images.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
. .venv/bin/activate
mkdir -p out
fgf transmittance --sigma-t 4 --hurst -0.1 --sw 4 -o out/transmittance.png
echo "demo: wrote out/transmittance.png"
fgf render scenes/default.xml -o out/default.exr --png out/default.png
echo "demo: wrote out/default.exr and out/default.png"
