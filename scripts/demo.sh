#!/usr/bin/env bash
# One command from a fresh Debian 12 machine to an image: installs the
# dependencies and data, builds, bakes the default scene (bunny00.off under a
# Blender HDRI, shadowed order-10 SH) and renders it to out/bunny.png.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
bash "$root/scripts/build.sh"
"$root/build/bin/prt" demo "${1:-$root/scenes/bunny.toml}"
