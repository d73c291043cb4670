#!/usr/bin/env bash
# No command destroys data: an output path that is an input, a device, a FIFO,
# a directory, or a file of another kind is refused before any work, and every
# file is left as it was.
set -u
prt="$(realpath "$1")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
failures=0
pass=0
cd "$work"

cat >scene.toml <<EOT
[mesh]
generate = "sphere"
detail = 1
[lighting]
constant = [1, 1, 1]
[basis]
plugin = "sh"
order = 3
[transport]
rays = 64
[output]
bake = "scene.h5"
image = "scene.png"
EOT
"$prt" -q bake scene.toml >/dev/null || { echo "FAIL: the scene does not bake"; exit 1; }
"$prt" -q render scene.toml >/dev/null || { echo "FAIL: the scene does not render"; exit 1; }
mkfifo fifo
mkdir folder
mknod device c 1 3 2>/dev/null || cp -a /dev/null device  # /dev/null's numbers: harmless
echo "notes: keep me" >notes.txt
cp scene.h5 other.h5
cp scene.toml other.toml
snapshot() { for f in scene.toml other.toml scene.h5 other.h5 scene.png notes.txt; do md5sum "$f"; done; stat -c '%n %F' fifo folder device; }
before="$(snapshot)"

# refuse NAME PATTERN -- ARGS: non-zero exit, the pattern on stderr, nothing changed or left.
refuse() {
  local name="$1" pattern="$2"
  shift 3
  "$prt" -q "$@" >stdout 2>stderr
  local code=$? problems=""
  [ "$code" -ne 0 ] || problems+=" exit code 0;"
  grep -q -- "$pattern" stderr || problems+=" message lacks '$pattern';"
  [ "$(snapshot)" = "$before" ] || problems+=" a file changed;"
  ls -a . folder | grep -q '\.tmp-' && problems+=" a temporary was left;"
  [ -z "$(ls folder)" ] || problems+=" something was written into folder/;"
  if [ -n "$problems" ]; then
    echo "FAIL $name:$problems"
    sed 's/^/    stderr: /' stderr
    failures=$((failures + 1))
  else
    echo "ok   $name: $(head -n 1 stderr)"
    pass=$((pass + 1))
  fi
}

refuse "bake over its own scene" "same file as the input" -- bake scene.toml -o scene.toml
refuse "bake over the scene, forced" "same file as the input" -- bake scene.toml -o ./scene.toml --force
refuse "render over its input bake" "same file as the input" -- render scene.toml --bake scene.h5 -o scene.h5
refuse "bake into a FIFO" "FIFO" -- bake scene.toml -o fifo
refuse "bake into a device" "device" -- bake scene.toml -o device
refuse "render into a device" "device" -- render scene.toml -o device
refuse "bake into a directory" "directory" -- bake scene.toml -o folder
refuse "bake over a PNG" "refusing to replace a PNG image" -- bake scene.toml -o scene.png
refuse "bake over notes" "refusing to replace a text file" -- bake scene.toml -o notes.txt
refuse "render over a bake" "refusing to replace a bake file" -- render scene.toml -o other.h5
refuse "bake into a missing folder" "does not exist" -- bake scene.toml -o no/such/out.h5
refuse "compress onto its input" "same file as the input" -- compress scene.h5 -c pca -o scene.h5
refuse "table over another scene" "refusing to replace a scene file" -- compare-bases scene.toml --bases sh:order=2 --json other.toml
refuse "compare-bases table over the scene" "same file as the input" -- compare-bases scene.toml --bases sh:order=2 --csv scene.toml
sed 's|bake = "scene.h5"|bake = "folder"|' scene.toml >dir_output.toml
before="$(snapshot)"
refuse "[output] bake names a directory" "directory" -- bake dir_output.toml

# --force replaces an output of another kind, never an input.
"$prt" -q bake scene.toml -o notes.txt --force >/dev/null 2>stderr
if [ $? -eq 0 ] && head -c 9 notes.txt | grep -q PRT-BAKE; then
  echo "ok   --force replaces a file of another kind"
  pass=$((pass + 1))
else
  echo "FAIL --force did not replace notes.txt"
  failures=$((failures + 1))
fi

# Killed by SIGINT or SIGTERM at random moments: no temporary is left, and a
# bake file that exists is complete.
sed -e 's/^detail = 1$/detail = 4/' -e 's/^rays = 64$/rays = 2048/' scene.toml >slow.toml
killed_ok=1
for attempt in $(seq 1 12); do
  rm -f slow.h5
  "$prt" -q bake slow.toml -o slow.h5 >/dev/null 2>&1 &
  pid=$!
  sleep "0.$((RANDOM % 9))$((RANDOM % 10))"
  kill -s "$([ $((attempt % 2)) -eq 0 ] && echo INT || echo TERM)" "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  if ls -a | grep -q '\.tmp-'; then
    echo "FAIL kill $attempt left a temporary: $(ls -a | grep '\.tmp-')"
    killed_ok=0
  elif [ -e slow.h5 ] && ! "$prt" -q info slow.h5 >/dev/null 2>&1; then
    echo "FAIL kill $attempt left an unreadable slow.h5"
    killed_ok=0
  fi
done
if [ "$killed_ok" -eq 1 ]; then
  echo "ok   12 bakes killed by SIGINT/SIGTERM left no temporary and no damaged file"
  pass=$((pass + 1))
else
  failures=$((failures + 1))
fi

echo "$pass passed, $failures failed"
[ "$failures" -eq 0 ]
