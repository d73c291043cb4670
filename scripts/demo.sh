#!/usr/bin/env bash
# One command from a fresh Debian 12 machine to an image: installs the
# packages the CLI needs (not the viewer's, Python's or the tests') and the
# data, builds the CLI and the plug-ins the scene names (scripts/test.sh
# installs and builds the rest), bakes the default scene
# (bunny00.off under a Blender HDRI, shadowed order-10 SH) and renders it to
# out/bunny.png.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
scene="${1:-$root/scenes/bunny.toml}"
bash "$root/scripts/setup.sh" --demo
# A plug-in's target is prt_<kind>_<name>; its kind is its section's role
# ([basis] and [exit] name bases); a role the scene leaves out takes the
# scene reader's default (framework/src/scene.cpp: sh, none, cpu).
targets=(--target prt_cli)
while read -r target; do
  kind="${target#prt_}"; name="${kind#*_}"; kind="${kind%%_*}"
  if grep -q "prt_add_plugin($name KIND $kind" "$root/plugins/CMakeLists.txt"; then
    targets+=(--target "$target")
  else  # an out-of-tree plug-in: built and installed by its own project
    echo "demo: $kind plug-in \"$name\" is not in this tree; build it as docs/writing-a-plugin.md says and put it on PRT_PLUGIN_PATH"
  fi
done < <(awk '
  /^\[/ { section = $0; gsub(/[\[\]]/, "", section) }
  /^[[:space:]]*plugin[[:space:]]*=/ {
    name = $0; sub(/^[^"]*"/, "", name); sub(/".*$/, "", name)
    kind = (section == "exit") ? "basis" : section
    if (kind == "basis" || kind == "compressor" || kind == "renderer") {
      print "prt_" kind "_" name
      if (section != "exit") named[kind] = 1
    }
  }
  END {
    if (!named["basis"]) print "prt_basis_sh"
    if (!named["compressor"]) print "prt_compressor_none"
    if (!named["renderer"]) print "prt_renderer_cpu"
  }' "$scene")
bash "$root/scripts/build.sh" "${targets[@]}"
"$root/build/bin/prt" demo "$scene"
