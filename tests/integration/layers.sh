#!/usr/bin/env bash
# docs/architecture.md's include layers hold in the tree
# (scripts/check_layers.py), and the check is not a rubber stamp: in a copy
# of the tree, a numerics file that includes the composition layer, a
# plug-in library that includes the checkpoint folder, the bake file
# including the plug-ins' clustering and a file in no layer are
# each reported with their file and line, and the script fails.
set -uo pipefail
root="$1"
python="$(command -v python3 || echo /usr/bin/python3)"
failures=0
fail() { echo "FAIL: $1"; failures=$((failures + 1)); }

out=$("$python" "$root/scripts/check_layers.py" --root "$root" 2>&1) || fail "the tree breaks its layers:"$'\n'"$out"
echo "$out" | tail -n 1

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cp -r "$root/docs" "$root/framework" "$root/plugins" "$work/"
mkdir -p "$work/scripts" && cp "$root/scripts/check_layers.py" "$work/scripts/"
sed -i '1i #include "prt/pipeline.hpp"' "$work/framework/src/interreflection.cpp"
sed -i '1i #include "prt/checkpoint.hpp"' "$work/plugins/compressor/clustering/lbg.cpp"
echo '#include "prt/error.hpp"' > "$work/framework/src/unlisted_stage.cpp"
sed -i '1i #include "prt/clustering.hpp"' "$work/framework/src/bake_file.cpp"
out=$("$python" "$work/scripts/check_layers.py" --root "$work" 2>&1) && fail "planted back-up includes pass"
echo "$out"
grep -q '^framework/src/interreflection.cpp:1: back-up include: layer numerics includes prt/pipeline.hpp (layer composition)$' <<<"$out" ||
  fail "numerics including composition is not reported with its file and line"
grep -q '^plugins/compressor/clustering/lbg.cpp:1: back-up include: layer shared includes prt/checkpoint.hpp (layer runs)$' <<<"$out" ||
  fail "a plug-in library including the checkpoint folder is not reported"
grep -q '^framework/src/unlisted_stage.cpp: in no layer' <<<"$out" || fail "a file in no layer is not reported"
grep -q '^framework/src/bake_file.cpp:1: skipped-layer include: layer files includes prt/clustering.hpp (layer shared), not one it may use$' <<<"$out" ||
  fail "the files layer including the plug-ins' shared code (below it, not one it may use) is not reported"
grep -q '2 back-up includes, 1 skipped-layer includes, 1 files in no layer' <<<"$out" || fail "the summary does not count them"
[ $failures -eq 0 ] && echo "layers: ok"
exit $failures
