#!/usr/bin/env bash
# Glossy images against the glossy ground truth over several light rotations
# and cameras (the scene's, and one turned 30 degrees about the vertical; the
# order-5 seam of docs/glossy.md): scenes/bunny_glossy.toml
# with exact transfer, relative RMS per vertex below a bound at every
# setting, and no under-resolved-light warning. The same scene at order 5
# must warn and exceed the bound somewhere, so the test can fail.
#   glossy_accuracy.sh <prt> <source dir>
set -euo pipefail
prt="$1"
src="$(realpath "$2")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
bound=0.15
make_scene() {  # order, rotation, camera position
  sed -e "s|\.\./data/|$src/data/|" -e "s|\.\./out/|$work/|" \
      -e 's/^plugin = "cpca"$/plugin = "none"/' -e '/^method = /d; /^clusters = /d; /^components = /d; /^iterations_per_component = /d' \
      -e "s/^order = 10$/order = $1/" -e "s/^rotation = 90.0$/rotation = $2/" \
      -e 's/^samples = 2048$/samples = 512/' -e 's/^width = 800$/width = 200/' -e 's/^height = 600$/height = 150/' \
      "$src/scenes/bunny_glossy.toml" >"$work/scene.toml"
  [ -z "$3" ] || sed -i "s/^\[camera\]$/[camera]\nposition = $3/" "$work/scene.toml"
  return 0
}
worst() {  # order, settings...: prints the worst relative RMS; warnings to warnings.txt
  local order="$1" worst=0
  shift
  make_scene "$order" 90 ""
  "$prt" -q bake "$work/scene.toml" >/dev/null
  for setting in "$@"; do
    IFS='|' read -r rotation camera <<<"$setting"
    make_scene "$order" "$rotation" "$camera"
    out=$("$prt" -q render "$work/scene.toml" --compare --no-budget 2>"$work/stderr.txt")
    cat "$work/stderr.txt" >>"$work/warnings.txt"
    rel=$(sed -n 's/.*(relative \([0-9.]*\)).*/\1/p' <<<"$out")
    echo "order $order, rotation $rotation, camera ${camera:-scene}: relative RMS $rel" >&2
    worst=$(awk -v a="$worst" -v b="$rel" 'BEGIN { print (b > a) ? b : a }')
  done
  echo "$worst"
}
: >"$work/warnings.txt"
good=$(worst 10 "18|" "90|" "200|" "18|[1.38, 0.42, 2.40]")
if grep -q "warning" "$work/warnings.txt"; then cat "$work/warnings.txt"; echo "FAIL: order 10 warns"; exit 1; fi
: >"$work/warnings.txt"
bad=$(worst 5 "18|")
grep -q "raise \[basis\] order" "$work/warnings.txt" || { echo "FAIL: order 5 does not warn"; exit 1; }
echo "worst relative RMS: order 10 $good, order 5 $bad (bound $bound)"
awk -v g="$good" -v b="$bad" -v bound="$bound" 'BEGIN { exit !(g < bound && b > bound) }' ||
  { echo "FAIL: expected order 10 below and order 5 above the bound"; exit 1; }
