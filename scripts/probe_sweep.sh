#!/usr/bin/env bash
# Probe spacing and bases against the moving object's error (docs/receivers.md):
# bakes scenes/room_probes.toml at each spacing and basis pair, then measures
# the elephant at three positions (the room's middle, by the window, against
# the +x wall) with `prt probes`. Prints one Markdown table; ~30 s on 2 cores.
# usage: scripts/probe_sweep.sh [build dir] [output folder]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
out=${2:-$root/out/probe_sweep}
prt="$build/bin/prt"
mkdir -p "$out"
positions=(--at 0.2,0,0.6 --at 0.3,0,1.5 --at 1.7,0,0.3)
echo "| spacing | light basis | incident basis | probes | stored | bake | relight | middle: leak control / trilinear | window | wall | wall: trilinear / leak control |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for spacing in 1.0 0.5 0.25; do
  for bases in "4 4" "10 3"; do
    read -r light incident <<<"$bases"
    scene="$out/room_${spacing}_${light}_${incident}.toml"
    # The scene with its paths made absolute, its spacing and orders replaced.
    sed -e "s|\"\.\./|\"$root/|g" -e "s|^spacing = .*|spacing = $spacing|" \
        -e "/^\[basis\]/,/^order/ s|^order = .*|order = $light|" \
        -e "/^\[exit\]/,/^order/ s|^order = .*|order = $incident|" \
        -e "s|^bake = .*|bake = \"$out/room_${spacing}_${light}_${incident}.h5\"|" \
        -e "s|^image = .*|image = \"$out/room_${spacing}_${light}_${incident}.png\"|" \
        "$root/scenes/room_probes.toml" >"$scene"
    bake_log=$("$prt" bake "$scene" --force 2>/dev/null)
    probes=$(grep -o '^[0-9]* probes' <<<"$bake_log" | cut -d' ' -f1)
    stored=$(grep -o '= [0-9.]* MB' <<<"$bake_log" | head -1 | tr -d '= ')
    bake=$(grep 'trace probes' <<<"$bake_log" | awk '{print $3}')
    log=$("$prt" -q probes "$scene" "${positions[@]}")
    relight=$(grep -o 'relight probes: [0-9.]* ms' <<<"$log" | awk '{print $3}')
    rows=$(grep '^| [0-9-]' <<<"$log")
    cell() { sed -n "${1}p" <<<"$rows" | awk -F'|' '{gsub(/ /,"",$3); gsub(/ /,"",$4); print $3 " / " $4}'; }
    factor=$(sed -n 3p <<<"$rows" | awk -F'|' '{gsub(/ /,"",$5); print $5}')
    echo "| $spacing | sh order $light | sh order $incident | $probes | $stored | ${bake} s | ${relight} ms | $(cell 1) | $(cell 2) | $(cell 3) | $factor |"
  done
done
