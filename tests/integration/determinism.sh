#!/usr/bin/env bash
# A bake is bit-identical whatever the number of cores: each compressor
# family (iterative CPCA with coherence passes, adaptive CPCA, VQ with
# geometry-coherent classification) and a fitted basis (eigentransport) is
# baked with every core and pinned to one (taskset -c 0), and the two files
# must be equal byte for byte.
#   determinism.sh <prt> <source dir>
set -euo pipefail
prt="$(realpath "$1")"
src="$(realpath "$2")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
[ -f "$src/data/meshes/bunny00.off" ] || { echo "FAIL: run scripts/setup.sh" >&2; exit 1; }
command -v taskset >/dev/null || { echo "FAIL: taskset (util-linux) missing" >&2; exit 1; }
[ "$(nproc)" -ge 2 ] || echo "note: one core here; the comparison still runs"

scene() {  # name, [basis] lines, [compressor] lines
  cat >"$work/$1.toml" <<SCENE
[mesh]
file = "$src/data/meshes/bunny00.off"
[transport]
${4:-rays = 256}
[basis]
$2
[compressor]
$3
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE
}
scene iterative 'plugin = "sh"
order = 10' 'plugin = "cpca"
method = "iterative"
clusters = 256
components = 4
reclassify = true
supercluster = "greedy"'
scene adaptive 'plugin = "sh"
order = 6' 'plugin = "cpca"
method = "adaptive"
clusters = 32
components = 4
init = "kmeans++"'
scene vq_coherent 'plugin = "sh"
order = 6' 'plugin = "vq"
clusters = 64
alpha = 0.5'
scene eigen 'plugin = "eigen"
d = 16' 'plugin = "cpca"
clusters = 16
components = 4' 'directions = "cubemap"
rays = 384'

for name in iterative adaptive vq_coherent eigen; do
  "$prt" -q bake "$work/$name.toml" -o "$work/$name.all.h5" >/dev/null
  taskset -c 0 "$prt" -q bake "$work/$name.toml" -o "$work/$name.one.h5" >/dev/null
  if cmp -s "$work/$name.all.h5" "$work/$name.one.h5"; then
    echo "$name: identical on $(nproc) cores and on one"
  else
    echo "FAIL: $name differs between $(nproc) cores and one core"
    h5diff "$work/$name.all.h5" "$work/$name.one.h5" | head -20 || true
    exit 1
  fi
done
