#!/usr/bin/env bash
# Per-texel against per-vertex transfer at several atlas resolutions, under
# several lights and on two CGAL meshes (docs/receivers.md): variants of
# scenes/nefertiti_texels.toml measured with `prt texels` at 8,192 samples a
# point. Prints one Markdown table per variant; ~1 min on 2 cores.
# usage: scripts/texel_sweep.sh [build dir] [output folder]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
out=${2:-$root/out/texel_sweep}
prt="$build/bin/prt"
mkdir -p "$out"
# name | mesh | HDR map | rotation | SH order | resolutions
variants=(
  "nefertiti, courtyard|nefertiti|courtyard|90|10|16 24 32 48 64 128"
  "nefertiti, sunrise (a low sun), SH order 20|nefertiti|sunrise|0|20|16 24 32 48 64"
  "open box (8 vertices), courtyard|open_cube|courtyard|90|10|4 8 16 32 64"
)
for variant in "${variants[@]}"; do
  IFS='|' read -r name mesh map rotation order resolutions <<<"$variant"
  scene="$out/${mesh}_${map}_${order}.toml"
  sed -e "s|\"\.\./|\"$root/|g" -e "s|nefertiti.off|$mesh.off|" \
      -e "s|courtyard.exr|$map.exr|" -e "s|^rotation = .*|rotation = $rotation.0|" \
      -e "s|^order = .*|order = $order|" "$root/scenes/nefertiti_texels.toml" >"$scene"
  arguments=()
  for r in $resolutions; do arguments+=(--resolution "$r"); done
  echo "### $name"
  "$prt" -q texels "$scene" "${arguments[@]}" --samples 8192 | grep -v '^wrote'
  echo
done
