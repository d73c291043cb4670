#!/usr/bin/env bash
# Refactors keep behaviour: bakes every example scene with two builds of prt
# and compares the files byte for byte (a bake holds no timings, so equal
# inputs give equal bytes). Prints one line per scene and the differing
# datasets (h5diff) where the files differ.
#   scripts/compare_bakes.sh OLD_PRT NEW_PRT [SCENE.toml ...]
# Scenes default to scenes/*.toml without those naming out-of-tree plug-ins
# (zonal, gautron, lobes). Example: build the commit before a change in a worktree
#   git worktree add /tmp/before HEAD~1 && ln -s "$PWD/data" /tmp/before/data
#   (cd /tmp/before && bash scripts/build.sh)
#   scripts/compare_bakes.sh /tmp/before/build/bin/prt build/bin/prt
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
old="$(realpath "$1")"
new="$(realpath "$2")"
shift 2
scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
  for s in "$root"/scenes/*.toml; do
    grep -q 'plugin = "\(zonal\|gautron\|lobes\)"' "$s" || scenes+=("$s")
  done
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
differ=0
for scene in "${scenes[@]}"; do
  name="$(basename "$scene" .toml)"
  if ! "$old" -q bake "$scene" -o "$work/$name.old.h5" >/dev/null 2>"$work/err"; then
    echo "$name: the old build cannot bake it: $(tail -n 1 "$work/err")"
    continue
  fi
  "$new" -q bake "$scene" -o "$work/$name.new.h5" >/dev/null 2>"$work/err" ||
    { echo "$name: the new build cannot bake it: $(tail -n 1 "$work/err")"; differ=$((differ + 1)); continue; }
  if cmp -s "$work/$name.old.h5" "$work/$name.new.h5"; then
    echo "$name: identical ($(stat -c %s "$work/$name.new.h5") bytes)"
  else
    echo "$name: DIFFERENT"
    h5diff "$work/$name.old.h5" "$work/$name.new.h5" 2>&1 | head -10 | sed 's/^/    /'
    differ=$((differ + 1))
  fi
done
echo "$differ scene(s) differ"
[ "$differ" -eq 0 ]
