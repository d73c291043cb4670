#!/usr/bin/env bash
# A bake whose transfer exceeds its memory budget (--memory) keeps the rows
# in a file and compresses them in passes: the bake file is identical, byte
# for byte, to the in-memory bake's, for every clustering compressor; its
# peak resident memory is lower by most of the transfer; a compressor that
# cannot read a file is given the rows in memory with a warning; a killed
# out-of-core bake leaves no rows file behind and resumes.
#   memory_budget.sh <prt> <source dir>
set -euo pipefail
prt="$(realpath "$1")"
src="$(realpath "$2")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
[ -f "$src/data/meshes/bunny00.off" ] || { echo "FAIL: run scripts/setup.sh" >&2; exit 1; }

# 100,000 vertices x 100 coefficients: a 40 MB transfer.
"$prt" -q subdivide "$src/data/meshes/bunny00.off" -o "$work/bunny.ply" -n 100000 >/dev/null
scene() {  # scene <name> <compressor lines>
  cat >"$work/$1.toml" <<SCENE
[mesh]
file = "$work/bunny.ply"
[transport]
rays = 64
[basis]
plugin = "sh"
order = 10
[compressor]
$2
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE
}
scene cpca $'plugin = "cpca"\nmethod = "iterative"\nclusters = 32\ncomponents = 2'
scene vq $'plugin = "vq"\nclusters = 32'
scene pca $'plugin = "pca"\ncomponents = 6'
scene none $'plugin = "none"'

peak() { sed -n 's/^peak memory: \([0-9.]*\) GB.*/\1/p' <<<"$1"; }
transfer_gb=0.040
for name in cpca vq pca; do
  in_memory=$("$prt" -q bake "$work/$name.toml" -o "$work/$name-memory.h5")
  on_disk=$("$prt" bake "$work/$name.toml" -o "$work/$name-disk.h5" --memory 30M 2>&1)
  grep -q "the transfer's rows are kept in" <<<"$on_disk" ||
    { echo "FAIL ($name): the 30 MB budget did not move the transfer to disk: $on_disk"; exit 1; }
  cmp "$work/$name-memory.h5" "$work/$name-disk.h5" ||
    { echo "FAIL ($name): the out-of-core bake differs from the in-memory one"; exit 1; }
  a=$(peak "$in_memory"); b=$(peak "$on_disk")
  echo "$name: identical files; peak memory $a GB in memory, $b GB out of core"
  # The passes release what they read: most of the transfer never stays resident.
  [ "$(echo "$b + 0.5 * $transfer_gb < $a" | bc)" = 1 ] ||
    { echo "FAIL ($name): out of core peaks at $b GB against $a GB in memory"; exit 1; }
done

# prt compress reads a bake's transfer into a file, block by block, when it
# exceeds the budget: the re-compressed file is the same.
"$prt" -q compress "$work/vq-memory.h5" -c cpca -p clusters=16 -o "$work/re-memory.h5" >/dev/null
out=$("$prt" compress "$work/vq-memory.h5" -c cpca -p clusters=16 -o "$work/re-disk.h5" \
        --memory 30M 2>&1)
grep -q "compressed in passes" <<<"$out" || { echo "FAIL: prt compress kept it in memory: $out"; exit 1; }
cmp "$work/re-memory.h5" "$work/re-disk.h5" || { echo "FAIL: prt compress differs on disk"; exit 1; }
echo "prt compress --memory 30M: identical"

# A compressor without the capability gets the rows in memory, and says so.
out=$("$prt" bake "$work/none.toml" -o "$work/none-disk.h5" --memory 30M 2>&1)
grep -q 'reads the transfer from memory only' <<<"$out" || { echo "FAIL: no warning: $out"; exit 1; }
"$prt" -q bake "$work/none.toml" -o "$work/none-memory.h5" >/dev/null
cmp "$work/none-memory.h5" "$work/none-disk.h5" || { echo "FAIL: none differs on disk"; exit 1; }
echo "none: warned, loaded, identical"

# Killed while tracing out of core: no rows file is left, and the rerun resumes.
"$prt" -q bake "$work/cpca.toml" -o "$work/killed.h5" --memory 30M --slab-vertices 8192 \
  >/dev/null 2>&1 &
pid=$!
sleep 2
kill -9 "$pid" 2>/dev/null || true
wait "$pid" 2>/dev/null || true
if ls -a "$work/.killed.h5.checkpoint" 2>/dev/null | grep -q 'transfer-rows'; then
  echo "FAIL: a killed bake left its rows file"; exit 1
fi
"$prt" -q bake "$work/cpca.toml" -o "$work/killed.h5" --memory 30M --slab-vertices 8192 \
  >/dev/null 2>&1
cmp "$work/cpca-memory.h5" "$work/killed.h5" || { echo "FAIL: resumed out-of-core bake differs"; exit 1; }
echo "killed out-of-core bake: nothing left behind; the rerun is identical"
echo "PASS"
