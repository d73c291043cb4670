#!/usr/bin/env bash
# The renderer conformance kit fails a broken renderer, naming the check and
# the measured value: one that fills the frame with the mean radiance (no
# coverage, background or depth order), and one that also draws the wrong size.
#   kit_catches_renderers.sh <prt_renderer_conformance> <broken plug-ins folder>
set -uo pipefail
kit="$1"
root="$2"
failures=0
check() {  # folder, failing check, text its message must contain
  local out
  out=$(PRT_PLUGIN_PATH="$root/$1" "$kit" --plugin flat 2>&1)
  if [ $? -eq 0 ]; then echo "FAIL $1: the kit passed"; failures=$((failures + 1)); return; fi
  if ! grep -qF "$2" <<<"$out" || ! grep -qF "$3" <<<"$out"; then
    echo "FAIL $1: expected a failure of \"$2\" mentioning \"$3\"; got:"
    grep -A12 "FAILED" <<<"$out" | head -30
    failures=$((failures + 1)); return
  fi
  echo "ok   $1 fails \"$2\" ($3)"
}
check renderer_flat "a surface of constant radiance shows it; uncovered pixels show the background" "off_by"
check renderer_flat "the nearer of two surfaces is drawn, whatever the triangle order" "the nearer sphere"
check renderer_small "draws an image of the camera's size, finite and non-negative" "image.width"
echo "$failures failure(s)"
[ "$failures" -eq 0 ]
