#!/usr/bin/env bash
# Prints a Markdown table: compressor x (clusters, n') -> SE, storage, encode
# time, overdraw, for the order-10 SH shadowed transfer of a mesh.
#   scripts/compression_table.sh data/meshes/bunny00.off [more meshes...]
# Bakes each mesh once (1024 rays, courtyard HDRI) into out/, then runs
# `prt compress` on copies. Needs a built tree (scripts/build.sh).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
prt="$root/build/bin/prt"
mkdir -p "$root/out"
fixed_configs=(
  "cpca method=static clusters=256 components=4"
  "cpca method=static clusters=256 components=8"
  "cpca method=iterative clusters=256 components=8"
  "cpca method=adaptive clusters=256 components=8"
  "cpca method=static clusters=256 components=8 reclassify=true"
  "cpca method=static clusters=256 components=8 reclassify=true supercluster=greedy"
  "cpca method=static clusters=256 components=8 reclassify=true supercluster=chen"
  "cpca method=static clusters=256 components=8 alpha=10"
)
for mesh in "$@"; do
  name="$(basename "${mesh%.*}")"
  scene="$root/out/table_$name.toml"
  cat >"$scene" <<EOT
[mesh]
file = "$(realpath "$mesh")"
[lighting]
environment = "$root/data/hdri/courtyard.exr"
[transport]
rays = 1024
[basis]
plugin = "sh"
order = 10
[output]
bake = "$root/out/table_$name.h5"
EOT
  [ -f "$root/out/table_$name.h5" ] || "$prt" -q bake "$scene" >/dev/null
  vertices=$("$prt" info "$root/out/table_$name.h5" | sed -n 's/^mesh: *\([0-9]*\) vertices.*/\1/p')
  # VQ and PCA at the storage of CPCA with 256 clusters and n' = 8 (Fig. 10's comparison):
  # S = v n' + m_c (n' + 1) n, VQ: m_c n = S, PCA: v n' + (n' + 1) n <= S.
  storage=$((vertices * 8 + 256 * 9 * 100))
  configs=("vq clusters=256" "vq clusters=$((storage / 100))" "pca components=8"
    "pca components=$(((storage - 100) / (vertices + 100)))" "${fixed_configs[@]}")
  echo
  echo "### $name ($vertices vertices, order-10 SH: n = 100)"
  echo
  echo "| compressor | parameters | SE | floats stored | MB | encode s | overdraw | supercluster overdraw |"
  echo "|---|---|---|---|---|---|---|---|"
  for config in "${configs[@]}"; do
    set -- $config
    plugin="$1"
    shift
    args=()
    for p in "$@"; do args+=(-p "$p"); done
    json=$("$prt" -q compress "$root/out/table_$name.h5" -o "$root/out/table_tmp.h5" -c "$plugin" \
      "${args[@]}" --json)
    python3 - "$plugin" "$*" "$json" <<'PY'
import json, sys
plugin, params, r = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
print(f"| {plugin} | {params} | {r['squared_error']:.4g} | {r['stored_floats']:.0f} | "
      f"{r['stored_bytes'] / 1e6:.2f} | {r['encode_seconds']:.2f} | {r['overdraw']:.3f} | "
      f"{r['supercluster_overdraw']:.3f} |")
PY
  done
done
rm -f "$root/out/table_tmp.h5"
