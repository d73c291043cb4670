#!/usr/bin/env bash
# Installs every Debian package PRT needs and fetches the real data (CGAL meshes,
# Blender HDR environment maps) into data/. Idempotent and non-interactive.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export DEBIAN_FRONTEND=noninteractive

packages=(
  build-essential cmake pkg-config ninja-build clang-format clang
  libeigen3-dev libembree-dev libopenmesh-dev libglfw3-dev libglm-dev
  libboost-dev libboost-filesystem-dev catch2 libtbb-dev libtomlplusplus-dev
  libcli11-dev nlohmann-json3-dev libopenexr-dev libhdf5-dev hdf5-tools libstb-dev libepoxy-dev libimgui-dev
  liblapack-dev xvfb xauth libgl1-mesa-dri openmpi-bin libopenmpi-dev
  python3-h5py python3-matplotlib python3-sklearn python3-numpy python3-pil
  pybind11-dev python3-dev python3-pytest python3-tqdm python3-nbclient python3-nbformat python3-ipykernel
)

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
