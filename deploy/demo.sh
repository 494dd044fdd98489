#!/usr/bin/env bash
# Renders the built-in Cornell box into an EXR and a PNG preview.
set -euo pipefail
build=${1:-build}
out=${2:-out}
mkdir -p "$out"
"$build/server/photond" render builtin:cornell-box --integrator path --spp 64 --width 512 --height 512 \
    -o "$out/cornell-box.exr" --preview "$out/cornell-box.png" --stats-json "$out/cornell-box.stats.json"
echo "wrote $out/cornell-box.exr and $out/cornell-box.png"
