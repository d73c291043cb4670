#!/usr/bin/env bash
# The papers' results from the command line, as a user runs them:
#  - glossy inter-reflection: scenes/box_glossy_bounces.toml (2 bounces)
#    rendered with --compare prints its error against the 2-bounce ground
#    truth, and the same transfer without its bounces has a larger error;
#  - point lights with eigentransport: scenes/bunny_eigen_point.toml renders,
#    prints its error against the ground truth and against brute-force
#    re-projection, both small (docs/bases.md has the light alone too);
#  - the subsurface bunny (scenes/bunny_subsurface.toml) matches a ground
#    truth that sums the same dipole over every vertex pair;
#  - prt-view moves the point light (--point-step): the printed position
#    changes and so does the screenshot.
#   papers.sh <prt> <prt-view> <source dir>
set -euo pipefail
prt="$(realpath "$1")"
viewer="$(realpath "$2")"
src="$(realpath "$3")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
[ -f "$src/data/meshes/bunny00.off" ] || { echo "FAIL: run scripts/setup.sh" >&2; exit 1; }
relative() { sed -n "s/^$1.*(relative \([0-9.]*\)).*/\1/p" <<<"$2" | head -1; }
below() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a < b) }'; }
local_scene() {  # scene file, output name: paths into the work folder, fewer samples
  sed -e "s|\"\.\./data/|\"$src/data/|" -e "s|\"\.\./out/[a-z_]*|\"$work/$2|" \
      -e 's/^samples = [0-9]*$/samples = 256/' -e 's/^width = .*/width = 320/' \
      -e 's/^height = .*/height = 240/' "$src/scenes/$1" >"$work/$2.toml"
  grep -q '^\[ground_truth\]' "$work/$2.toml" || printf '\n[ground_truth]\nsamples = 256\n' >>"$work/$2.toml"
}

# 1. Glossy inter-reflection.
local_scene box_glossy_bounces.toml box
"$prt" -q bake "$work/box.toml" >/dev/null
out=$("$prt" -q render "$work/box.toml" --compare --no-budget)
with=$(relative "error against ground truth" "$out")
without=$(relative "error of the same transfer without its 2 bounces" "$out")
echo "glossy box, 2 bounces: relative RMS $with; without the bounces $without"
[ -n "$with" ] && [ -n "$without" ] || { echo "FAIL: errors not printed"; echo "$out"; exit 1; }
below "$with" "$without" || { echo "FAIL: bounces do not lower the error"; exit 1; }
below "$with" 0.2 || { echo "FAIL: glossy bounces too far from the ground truth"; exit 1; }

# 2. Point lights and eigentransport.
local_scene bunny_eigen_point.toml point
"$prt" -q bake "$work/point.toml" >/dev/null
out=$("$prt" -q render "$work/point.toml" --compare --no-budget)
rule=$(relative "error against ground truth" "$out")
brute=$(relative "error of brute-force re-projection" "$out")
echo "eigentransport, point light + environment: nearest rule $rule, brute force $brute"
[ -n "$rule" ] && [ -n "$brute" ] || { echo "FAIL: errors not printed"; echo "$out"; exit 1; }
below "$rule" 0.15 && below "$brute" 0.15 || { echo "FAIL: point-light error too large"; exit 1; }

# 3. Subsurface against a ground truth that sums the dipole over all vertex pairs.
local_scene bunny_subsurface.toml subsurface
"$prt" -q bake "$work/subsurface.toml" >/dev/null
out=$("$prt" -q render "$work/subsurface.toml" --compare --no-budget)
error=$(relative "error against ground truth" "$out")
echo "subsurface bunny against the pair-sum ground truth: relative RMS $error"
below "$error" 0.08 || { echo "FAIL: subsurface error too large"; echo "$out"; exit 1; }

# 4. The viewer moves the light.
command -v xvfb-run >/dev/null || { echo "FAIL: xvfb-run missing; run scripts/setup.sh" >&2; exit 1; }
x() { xvfb-run -a -s "-screen 0 1024x768x24" "$@"; }
cd "$work"
x "$viewer" "$work/point.toml" --frames 3 --light-step 0 --screenshot still.png >still.log
x "$viewer" "$work/point.toml" --frames 3 --light-step 0 --point-step -3 2 0 --screenshot moved.png \
  >moved.log
positions=$(grep -o 'point light 1 at ([^)]*)' moved.log | sort -u | wc -l)
[ "$positions" -eq 3 ] || { echo "FAIL: the light did not move"; cat moved.log; exit 1; }
/usr/bin/python3 - still.png moved.png <<'PY'
import sys
from PIL import Image, ImageChops
a, b = (Image.open(f).convert("RGB") for f in sys.argv[1:3])
difference = sum(ImageChops.difference(a, b).convert("L").getdata()) / (a.width * a.height)
print(f"viewer: moving the light changes the image by {difference:.2f} levels on average")
sys.exit(0 if difference > 0.5 else 1)
PY
echo "PASS"
