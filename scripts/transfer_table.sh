#!/usr/bin/env bash
# Prints a Markdown table: transfer kind x matrix size x compression -> bake
# time, encode time, file size, relight time per frame and RMS error against
# the Monte Carlo ground truth (same BRDF, bounces and camera).
#   scripts/transfer_table.sh [mesh.off] [hdri.exr]
# Defaults: the CGAL bunny under Blender's courtyard. Needs a built tree.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
prt="$root/build/bin/prt"
mesh="$(realpath "${1:-$root/data/meshes/bunny00.off}")"
hdri="$(realpath "${2:-$root/data/hdri/courtyard.exr}")"
work="$root/out/transfer_table"
mkdir -p "$work"

glossy='diffuse = 0.4\nspecular = 0.6\nexponent = 12'
# name | material lines | bounces | compressor lines | exit basis lines
configs=(
  "diffuse 25|brdf = \"lambert\"|0|plugin = \"none\""
  "diffuse 25|brdf = \"lambert\"|0|plugin = \"cpca\"\nclusters = 256\ncomponents = 8"
  "diffuse 25, 2 bounces|brdf = \"lambert\"|2|plugin = \"none\""
  "diffuse 25, 2 bounces|brdf = \"lambert\"|2|plugin = \"cpca\"\nclusters = 256\ncomponents = 8"
  "phong 16x25 LS|brdf = \"phong\"\\n$glossy|0|plugin = \"cpca\"\nclusters = 256\ncomponents = 8|order = 4"
  "phong 24x25 LS|brdf = \"phong\"\\n$glossy|0|plugin = \"none\"|reduced = true"
  "phong 24x25 LS|brdf = \"phong\"\\n$glossy|0|plugin = \"cpca\"\nclusters = 256\ncomponents = 8|reduced = true"
  "phong 25x25 zero|brdf = \"phong\"\\n$glossy\nprojection = \"zero\"|0|plugin = \"cpca\"\nclusters = 256\ncomponents = 8|projection = \"zero\""
  "phong 25x25 LS|brdf = \"phong\"\\n$glossy|0|plugin = \"cpca\"\nclusters = 256\ncomponents = 8|"
  "cook-torrance 24x25 LS|brdf = \"cook-torrance\"\\n$glossy\nroughness = 0.35\nfresnel = 0.5|0|plugin = \"cpca\"\nclusters = 256\ncomponents = 8|reduced = true"
  "ward 24x25 LS|brdf = \"ward\"\\n$glossy\nanisotropic_roughness = [0.15, 0.45]|0|plugin = \"cpca\"\nclusters = 256\ncomponents = 8|reduced = true"
)
echo "| transfer | compression | bake s | encode s | file MB | relight ms/frame | RMS vs ground truth | relative |"
echo "|---|---|---|---|---|---|---|---|"
i=0
for config in "${configs[@]}"; do
  IFS='|' read -r name material bounces compressor exit <<<"$config"
  i=$((i + 1))
  scene="$work/config$i.toml"
  printf '%b\n' "[mesh]
file = \"$mesh\"
[material]
albedo = [0.9, 0.75, 0.6]
$material
[transport]
rays = 1024
bounces = $bounces
[basis]
plugin = \"sh\"
order = 5
[exit]
plugin = \"hsh\"
$exit
[compressor]
$compressor
[lighting]
environment = \"$hdri\"
rotation = 90
[camera]
width = 400
height = 300
[ground_truth]
samples = 1024
[output]
bake = \"config$i.h5\"
image = \"config$i.png\"" >"$scene"
  bake_out=$("$prt" -q bake "$scene")
  bake_s=$(sed -n 's/^  total *\([0-9.]*\) s/\1/p' <<<"$bake_out" | tail -1)
  encode_s=$(sed -n 's/^  compress ([a-z]*) *\([0-9.]*\) s/\1/p' <<<"$bake_out")
  size=$(stat -c %s "$work/config$i.h5")
  render_out=$("$prt" -q render "$scene" --compare)
  relight=$(sed -n 's/^  relight vertices *\([0-9.]*\) s/\1/p' <<<"$render_out")
  project=$(sed -n 's/^  project light *\([0-9.]*\) s/\1/p' <<<"$render_out")
  rms=$(sed -n 's/.*RMS per vertex \([0-9.eE+-]*\) (relative \([0-9.]*\)).*/\1 | \2/p' <<<"$render_out")
  compression=$(printf '%b' "$compressor" | tr '\n' ' ' | sed 's/plugin = //; s/"//g; s/clusters = \([0-9]*\) components = \([0-9]*\)/\1 x \2/')
  awk -v n="$name" -v c="$compression" -v b="$bake_s" -v e="$encode_s" -v s="$size" \
    -v r="$relight" -v p="$project" -v rms="$rms" \
    'BEGIN { printf "| %s | %s | %.2f | %.2f | %.1f | %.1f | %s |\n", n, c, b, e, s / 1e6, 1000 * (r + p), rms }'
done
