#!/usr/bin/env bash
# The SDK as documented: runs the shell blocks of docs/writing-a-plugin.md
# marked "tested:" verbatim, in a scratch checkout that shares this build
# (build -> the build tree; examples, scenes, data as in the source tree), with
# HOME pointing at a scratch folder. No flag is added: what the docs say is
# what works. Then checks what the commands should have produced, that a
# Debug build of a plug-in loads into this (Release) host, and that the
# installed binaries load code only from where they belong.
set -euo pipefail
build="$(realpath "$1")"
src="$(realpath "$2")"
source "$(dirname "${BASH_SOURCE[0]}")/documented_blocks.sh"
scratch_checkout "$build" "$src"

# The marked blocks, in order.
script="$work/documented.sh"
tested_blocks "$src/docs/writing-a-plugin.md" >"$script"
[ "$(grep -c 'cmake' "$script")" -ge 5 ] || { echo "FAIL: no documented commands found"; exit 1; }
echo "--- documented commands:"
cat "$script"
echo "---"
(cd "$work/checkout" && HOME="$work/home" bash -euo pipefail "$script") >"$work/out.txt" 2>&1 || {
  cat "$work/out.txt"
  echo "FAIL: the documented commands failed"
  exit 1
}
grep -E "tests passed|Passed" "$work/out.txt"
grep -q "^basis zonal " "$work/out.txt" || { echo "FAIL: prt plugins does not list zonal"; exit 1; }
for image in bunny_zonal_diffuse bunny_zonal_glossy bunny_gautron bunny_lobes; do
  [ -s "$work/checkout/out/$image.png" ] || { echo "FAIL: no image $image.png"; exit 1; }
done
if grep -q "warning" "$work/out.txt"; then grep warning "$work/out.txt"; echo "FAIL: warnings"; exit 1; fi

# Debug and RelWithDebInfo plug-ins load into the Release host.
for type in Debug RelWithDebInfo; do
  cmake -S "$src/examples/zonal_basis" -B "$work/zonal-$type" -DCMAKE_BUILD_TYPE=$type \
    -DCMAKE_PREFIX_PATH="$work/home/prt" >/dev/null
  cmake --build "$work/zonal-$type" >/dev/null
  ctest --test-dir "$work/zonal-$type" >/dev/null || { echo "FAIL: $type plug-in refused"; exit 1; }
  echo "$type plug-in: conformance passed"
done

# The installed binaries and libraries load code only from where they belong.
bash "$src/tests/integration/load_paths.sh" "$work/home/prt"
