#!/usr/bin/env bash
# The Python module as documented: runs the shell blocks of docs/python.md
# marked "tested:" verbatim, in a scratch checkout that shares this build,
# with HOME in a scratch folder. Then checks what they should have produced:
# the example's plot, and an installed module that loads the installed
# plug-ins (not the build tree's).
#   python_install.sh <build folder> <source folder>
set -euo pipefail
build="$(realpath "$1")"
src="$(realpath "$2")"
source "$(dirname "${BASH_SOURCE[0]}")/documented_blocks.sh"
scratch_checkout "$build" "$src"

# The marked blocks, in order.
script="$work/documented.sh"
tested_blocks "$src/docs/python.md" >"$script"
[ "$(grep -c 'python3' "$script")" -ge 3 ] || { echo "FAIL: no documented commands found"; exit 1; }
echo "--- documented commands:"
cat "$script"
echo "---"
(cd "$work/checkout" && env -u PYTHONPATH HOME="$work/home" MPLBACKEND=Agg \
  bash -euo pipefail "$script") >"$work/out.txt" 2>&1 || {
  cat "$work/out.txt"
  echo "FAIL: the documented commands failed"
  exit 1
}
cat "$work/out.txt" | grep -v "^\s*$" | tail -20
for plot in error_vs_bytes images; do
  [ -s "$work/checkout/out/python/$plot.png" ] || { echo "FAIL: no $plot.png"; exit 1; }
done
# The installed module is the installed copy, and it finds the installed plug-ins.
installed="$work/home/prt"
site=$(find "$installed" -type d -name dist-packages | head -1)
[ -n "$site" ] || { echo "FAIL: nothing installed under dist-packages"; exit 1; }
out=$(cd "$work" && env -u PRT_PLUGIN_PATH PYTHONPATH="$site" /usr/bin/python3 -c "
import prt
print(prt.__file__)
for p in prt.plugins(): print(p['file'])")
echo "$out" | head -3
if grep -v "^$installed/" <<<"$out" | grep -q .; then
  echo "FAIL: the installed module uses files outside $installed:"; grep -v "^$installed/" <<<"$out"
  exit 1
fi
[ "$(grep -c "^$installed/lib/prt/plugins/" <<<"$out")" -ge 8 ] || {
  echo "FAIL: the installed module did not find the installed plug-ins"; exit 1; }
echo "ok: documented commands ran; the installed module loads only installed files"
