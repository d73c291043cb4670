#!/usr/bin/env bash
# `cmake --install` from a build tree the installing user cannot write (run
# as root, the install runs as user nobody; the build tree is root's), into
# a fresh prefix: prt and prt-view are installed, the manifest lands in the
# prefix, the build tree is unchanged, and the installed prt finds the
# installed plug-ins with no environment variable.
#   install_readonly.sh <build folder>
set -euo pipefail
build="$(realpath "$1")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"
as_user=()
nobody=(setpriv --reuid=65534 --regid=65534 --clear-groups)
if [ "$(id -u)" -eq 0 ] && "${nobody[@]}" test -r "$build/cmake_install.cmake"; then
  chown 65534:65534 "$work"
  as_user=("${nobody[@]}")
  # nobody must not be able to write the build tree, or the test proves nothing
  if "${as_user[@]}" test -w "$build"; then echo "FAIL: nobody can write $build"; exit 1; fi
else
  # Not root, or the build tree lies where nobody cannot read it (a private
  # home): the install runs as this user, and the build tree is checked unchanged.
  echo "note: the install runs as $(id -un); the build tree is checked unchanged"
fi
listing() { find "$build" -maxdepth 1 -printf '%f %y %s %T@\n' | sort; }
before="$(listing)"
"${as_user[@]}" env -i PATH="$PATH" HOME="$work" cmake --install "$build" --prefix "$prefix" \
  >"$work/install.log" 2>&1 || { tail -20 "$work/install.log"; echo "FAIL: cmake --install failed"; exit 1; }
[ "$(listing)" = "$before" ] || { echo "FAIL: the install changed the build tree"; diff <(echo "$before") <(listing) || true; exit 1; }
for f in bin/prt bin/prt-view share/prt/install_manifest.txt; do
  [ -s "$prefix/$f" ] || { echo "FAIL: $f not installed"; exit 1; }
done
grep -qx "$prefix/bin/prt" "$prefix/share/prt/install_manifest.txt" ||
  { echo "FAIL: the manifest does not list bin/prt"; exit 1; }
out=$("${as_user[@]}" env -i PATH="$PATH" HOME="$work" "$prefix/bin/prt" plugins)
grep -q "$prefix/lib/prt/plugins/libprt-basis-sh.so" <<<"$out" ||
  { echo "$out" | head; echo "FAIL: the installed prt does not find the installed plug-ins"; exit 1; }
if grep -q "$build" <<<"$out"; then echo "FAIL: the installed prt loads plug-ins from the build tree"; exit 1; fi
echo "install from a read-only build tree: ok ($(wc -l <"$prefix/share/prt/install_manifest.txt") files)"
