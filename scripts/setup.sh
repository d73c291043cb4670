#!/usr/bin/env bash
# Installs every Debian package PRT needs and fetches the real data (CGAL meshes,
# Blender HDR environment maps) into data/. Idempotent and non-interactive.
#   scripts/setup.sh [--demo]   (--demo: only the CLI's packages, for scripts/demo.sh)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export DEBIAN_FRONTEND=noninteractive

# What the CLI and the plug-ins build from (scripts/demo.sh installs these
# alone: --demo), then the rest: the OpenGL renderer and prt-view, prt-mpi, the
# Python module, the tests and their tools.
demo_packages=(
  build-essential cmake pkg-config ninja-build
  libeigen3-dev libembree-dev libopenmesh-dev libboost-dev libboost-filesystem-dev
  libtbb-dev libtomlplusplus-dev libcli11-dev nlohmann-json3-dev libopenexr-dev
  libhdf5-dev libstb-dev liblapack-dev libxxhash-dev libcgal-dev
)
packages=(
  "${demo_packages[@]}" clang-format clang libglfw3-dev libglm-dev catch2 hdf5-tools
  libepoxy-dev libimgui-dev xvfb xauth libgl1-mesa-dri openmpi-bin libopenmpi-dev
  python3-h5py python3-matplotlib python3-sklearn python3-skimage python3-numpy python3-pil
  pybind11-dev python3-dev python3-pytest python3-tqdm python3-nbclient python3-nbformat python3-ipykernel
)
if [ "${1:-}" = "--demo" ]; then
  packages=("${demo_packages[@]}")
elif [ $# -gt 0 ]; then
  echo "usage: scripts/setup.sh [--demo]" >&2
  exit 2
fi

sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${#missing[@]} packages: ${missing[*]}"
  "${sudo_cmd[@]}" apt-get update -q
  "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
else
  echo "setup: all packages present"
fi

data="$root/data"
mkdir -p "$data"
work="$(mktemp -d)"; chmod 755 "$work"
trap 'rm -rf "$work"' EXIT

if [ ! -f "$data/meshes/bunny00.off" ]; then
  echo "setup: fetching CGAL meshes (libcgal-demo)"
  (cd "$work" && apt-get download -q libcgal-demo)
  dpkg-deb -x "$work"/libcgal-demo_*.deb "$work/cgal"
  tar -xzf "$work/cgal/usr/share/doc/libcgal-dev/data.tar.gz" -C "$work" data/meshes
  rm -rf "$data/meshes.tmp" && mv "$work/data/meshes" "$data/meshes.tmp"
  mv "$data/meshes.tmp" "$data/meshes"
fi

if [ ! -f "$data/hdri/studio.exr" ]; then
  echo "setup: fetching Blender HDR environment maps (blender-data)"
  (cd "$work" && apt-get download -q blender-data)
  dpkg-deb -x "$work"/blender-data_*.deb "$work/blender"
  rm -rf "$data/hdri.tmp" && mkdir -p "$data/hdri.tmp"
  cp "$work"/blender/usr/share/blender/datafiles/studiolights/world/*.exr "$data/hdri.tmp/"
  rm -rf "$data/hdri" && mv "$data/hdri.tmp" "$data/hdri"
fi
echo "setup: data ready in $data ($(ls "$data/meshes" | wc -l) meshes, $(ls "$data/hdri" | wc -l) HDR maps)"
