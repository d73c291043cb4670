#!/usr/bin/env bash
# A full disk loses nothing: bake, in-place compress and render, each run with
# its output on a file system that fills up at 10 levels, must exit non-zero
# with one located message ("no space left on device while writing"), by no
# signal, leave no temporary, and leave the old file byte for byte. The file
# system is a small tmpfs where this process may mount one (root in CI), and
# otherwise the ENOSPC shim (tests/faults/enospc_shim.c: writes fail after a
# byte budget). Both are run where both are possible.
set -u
prt="$(realpath "$1")"
shim="$(realpath "$2")"
work="$(mktemp -d)"
mounted=""
cleanup() {
  [ -n "$mounted" ] && umount "$mounted" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
failures=0
checks=0
cd "$work"

cat >scene.toml <<EOT
[mesh]
generate = "sphere"
detail = 2
[lighting]
constant = [1, 1, 1]
[basis]
plugin = "sh"
order = 4
[transport]
rays = 64
[output]
bake = "good.h5"
image = "good.png"
EOT
"$prt" -q bake scene.toml >/dev/null || { echo "FAIL: the scene does not bake"; exit 1; }
"$prt" -q render scene.toml >/dev/null || { echo "FAIL: the scene does not render"; exit 1; }
bake_bytes=$(stat -c %s good.h5)
png_bytes=$(stat -c %s good.png)

# check NAME DIR OLD -- COMMAND...: runs the command; OLD (in DIR) must be unchanged.
check() {
  local name="$1" dir="$2" old="$3"
  shift 4
  local before
  before="$(md5sum "$dir/$old" | cut -d' ' -f1)"
  "$@" >stdout 2>stderr
  local code=$? problems=""
  checks=$((checks + 1))
  [ "$code" -ne 0 ] || problems+=" exit code 0 on a full disk;"
  [ "$code" -lt 128 ] || problems+=" killed by signal $((code - 128));"
  grep -q "no space left on device while writing\|No room\|no room for" stderr ||
    problems+=" no 'no space left on device' message;"
  [ "$(grep -c 'error' stderr)" -le 1 ] || problems+=" more than one error line;"
  [ "$(md5sum "$dir/$old" | cut -d' ' -f1)" = "$before" ] || problems+=" $old changed;"
  [ -z "$(find "$dir" -name '*.tmp-*')" ] || problems+=" a temporary was left;"
  for f in "$dir"/*; do
    case "$f" in
      *.h5) "$prt" -q info "$f" >/dev/null 2>&1 || problems+=" a damaged bake $f under a final name;" ;;
      *.png) /usr/bin/python3 -c "import sys,zlib; d=open(sys.argv[1],'rb').read(); assert d.endswith(b'IEND\xaeB\`\x82')" "$f" 2>/dev/null ||
               problems+=" a cut PNG $f under a final name;" ;;
    esac
  done
  if [ -n "$problems" ]; then
    echo "FAIL $name:$problems"
    sed 's/^/    stderr: /' stderr
    failures=$((failures + 1))
  else
    echo "ok   $name: $(grep error stderr | head -n 1)"
  fi
}

# Ten fill levels between an almost full and an almost large enough file system.
levels() {
  local need=$1
  for k in 1 2 3 4 5 6 7 8 9 10; do echo $((need * k / 11)); done
}

run_with_shim() {
  local dir="$work/shim"
  mkdir -p "$dir"
  for room in $(levels "$bake_bytes"); do
    cp good.h5 "$dir/old.h5"
    check "shim bake, $room bytes of room" "$dir" old.h5 -- \
      env LD_PRELOAD="$shim" PRT_FAULT_BYTES="$room" "$prt" -q bake scene.toml -o "$dir/old.h5"
    check "shim in-place compress, $room bytes of room" "$dir" old.h5 -- \
      env LD_PRELOAD="$shim" PRT_FAULT_BYTES="$room" "$prt" -q compress "$dir/old.h5" -c pca
    rm -f "$dir"/*
  done
  for room in $(levels "$png_bytes"); do
    cp good.png "$dir/old.png"
    check "shim render, $room bytes of room" "$dir" old.png -- \
      env LD_PRELOAD="$shim" PRT_FAULT_BYTES="$room" "$prt" -q render scene.toml --bake good.h5 -o "$dir/old.png"
    rm -f "$dir"/*
  done
}

# tmpfs sizes are whole pages: the old file plus a few pages of room.
run_on_tmpfs() {
  local dir="$work/tmpfs"
  mkdir -p "$dir"
  for pages in 1 2 3 4 6 8 10 12 16 20; do
    local size=$(((bake_bytes + 4095) / 4096 * 4096 + pages * 4096))
    mount -t tmpfs -o size=$size tmpfs "$dir" || return 1
    mounted="$dir"
    cp good.h5 "$dir/old.h5"
    check "tmpfs bake, $pages pages free" "$dir" old.h5 -- "$prt" -q bake scene.toml -o "$dir/old.h5"
    check "tmpfs in-place compress, $pages pages free" "$dir" old.h5 -- \
      "$prt" -q compress "$dir/old.h5" -c pca
    umount "$dir"
    mounted=""
  done
  for pages in 0 1; do
    local size=$(((png_bytes + 4095) / 4096 * 4096 + pages * 4096))
    mount -t tmpfs -o size=$size tmpfs "$dir" || return 1
    mounted="$dir"
    cp good.png "$dir/old.png"
    check "tmpfs render, $pages pages free" "$dir" old.png -- \
      "$prt" -q render scene.toml --bake good.h5 -o "$dir/old.png"
    umount "$dir"
    mounted=""
  done
}

# The shim itself lets a write through when there is room: the same
# commands succeed with room to spare (or every failure above would be the
# shim's, not the full disk's).
control() {
  local dir="$work/control" room=$((bake_bytes * 20))
  mkdir -p "$dir"
  checks=$((checks + 1))
  if env LD_PRELOAD="$shim" PRT_FAULT_BYTES="$room" "$prt" -q bake scene.toml -o "$dir/new.h5" >/dev/null 2>&1 &&
    env LD_PRELOAD="$shim" PRT_FAULT_BYTES="$room" "$prt" -q compress "$dir/new.h5" -c pca >/dev/null 2>&1 &&
    env LD_PRELOAD="$shim" PRT_FAULT_BYTES="$room" "$prt" -q render scene.toml --bake "$dir/new.h5" -o "$dir/new.png" >/dev/null 2>&1 &&
    "$prt" -q info "$dir/new.h5" >/dev/null; then
    echo "ok   with room to spare under the shim, bake, compress and render succeed"
  else
    echo "FAIL with room to spare under the shim, a command failed"
    failures=$((failures + 1))
  fi
}

control
run_with_shim
if mkdir -p "$work/probe" && mount -t tmpfs -o size=64k tmpfs "$work/probe" 2>/dev/null; then
  umount "$work/probe"
  run_on_tmpfs || { echo "FAIL: tmpfs mounting stopped working"; failures=$((failures + 1)); }
else
  echo "note: cannot mount a tmpfs here (not root?): the shim's runs stand for it"
fi
echo "full disk: $checks runs, $failures failed"
[ "$failures" -eq 0 ]
