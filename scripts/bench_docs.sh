#!/usr/bin/env bash
# Regenerates the sweeps of docs/benchmarks.md: two CGAL meshes under two
# Blender HDRIs, 3 bases x 3 compressors x 3 budgets each (27 configurations)
# plus Haar at 3 budgets,
# errors over the scene's light and a copy rotated by 180 degrees. Cube-map
# directions (6 x 16 x 16), which eigentransport needs and SH takes as well.
#   scripts/bench_docs.sh            (needs a built tree and scripts/setup.sh's data)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
prt="$root/build/bin/prt"
bases='basis=sh order=6|sh order=10|eigen d=48'
compressors='compressor=vq clusters=64|vq clusters=256|vq clusters=1024|pca components=4|pca components=8|pca components=16|cpca clusters=64 components=4|cpca clusters=256 components=8|cpca clusters=256 components=16'
for case in "bunny00 courtyard" "armadillo sunset"; do
  set -- $case
  mkdir -p "$root/out"
  scene="$root/out/bench_$1.toml"
  cat >"$scene" <<EOT
[mesh]
file = "$root/data/meshes/$1.off"
[material]
albedo = [0.85, 0.8, 0.75]
[transport]
directions = "cubemap"
rays = 1536
[lighting]
environment = "$root/data/hdri/$2.exr"
rotation = 90
[camera]
width = 320
height = 240
exposure = 0.7
[ground_truth]
samples = 512
EOT
  "$prt" -q bench "$scene" --out "$root/docs/bench/$1_$2" --lights 2 \
    --sweep "$bases" --sweep "$compressors" --no-report
  # Haar keeps its k largest coefficients and takes no compressor: its three
  # budgets join the same results (and plots) as a fourth basis.
  "$prt" -q bench "$scene" --out "$root/docs/bench/$1_$2" --lights 2 \
    --sweep 'basis=haar resolution=16 k=32|haar resolution=16 k=64|haar resolution=16 k=128' \
    --sweep 'compressor=none' 
done
