#!/usr/bin/env bash
# Bad input gets one clear line on stderr naming the problem and the place, a
# non-zero exit, and no output file.
set -u
prt="$1"
src="$2"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
failures=0
pass=0

good_scene() {
  cat <<EOT
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
bake = "out.h5"
image = "out.png"
EOT
}

# expect_error NAME PATTERN -- ARGS...: runs prt, checks exit, message and leftovers.
expect_error() {
  local name="$1" pattern="$2"
  shift 3
  rm -f "$work"/out.h5 "$work"/out.png
  (cd "$work" && "$prt" -q "$@" >"$work/stdout" 2>"$work/stderr")
  local code=$?
  local lines
  lines=$(wc -l <"$work/stderr")
  local problems=""
  [ "$code" -ne 0 ] || problems+=" exit code 0;"
  [ "$lines" -eq 1 ] || problems+=" $lines lines on stderr;"
  grep -q -- "$pattern" "$work/stderr" || problems+=" message lacks '$pattern';"
  [ ! -e "$work/out.h5" ] || problems+=" out.h5 was written;"
  [ ! -e "$work/out.png" ] || problems+=" out.png was written;"
  ls -a "$work" | grep -q '\.tmp-' && problems+=" a temporary was left;"
  if [ -n "$problems" ]; then
    echo "FAIL $name:$problems"
    sed 's/^/    stderr: /' "$work/stderr"
    failures=$((failures + 1))
  else
    echo "ok   $name: $(cat "$work/stderr")"
    pass=$((pass + 1))
  fi
}

good_scene | sed 's/^order = 3/ordr = 3/' >"$work/misspelt.toml"
expect_error "misspelt key" 'misspelt.toml:8:1: error: basis "sh": unknown parameter "ordr".*did you mean "order"' -- bake misspelt.toml

good_scene | sed 's/^generate = "sphere"/file = "meshes\/missing.off"/' >"$work/missing_mesh.toml"
expect_error "missing mesh" 'missing_mesh.toml:2:1: error: .*missing.off" not found' -- bake missing_mesh.toml

good_scene | sed 's/^plugin = "sh"/plugin = "spherical"/' >"$work/bad_plugin.toml"
expect_error "unknown plug-in" 'bad_plugin.toml:7:10: error: no basis plug-in named "spherical"; available: .*\bsh\b' -- bake bad_plugin.toml

good_scene >"$work/good.toml"
head -c 5000 /dev/urandom >"$work/corrupt.h5"
expect_error "corrupt bake" 'corrupt.h5: error: not a PRT bake file' -- render good.toml --bake corrupt.h5

expect_error "missing bake" 'out.h5: error: bake file not found' -- render good.toml

good_scene | sed 's/^rays = 64/rays = 0/' >"$work/range.toml"
expect_error "out of range" 'range.toml:10:1: error: section \[transport\]: parameter "rays" = 0 is out of range \[1, 4194304\]' -- bake range.toml

# A good scene still works end to end in the same folder.
if (cd "$work" && "$prt" -q bake good.toml >/dev/null && "$prt" -q render good.toml >/dev/null) &&
  [ -s "$work/out.h5" ] && [ -s "$work/out.png" ]; then
  echo "ok   good scene bakes and renders"
  pass=$((pass + 1))
else
  echo "FAIL good scene"
  failures=$((failures + 1))
fi
# A misspelt compressor parameter changes nothing in the bake file.
if [ -s "$work/out.h5" ]; then
  before=$(md5sum <"$work/out.h5")
  if (cd "$work" && ! "$prt" -q compress out.h5 -c cpca -p clustrs=4 2>"$work/stderr") &&
    grep -q 'command line parameter 1: error: compressor "cpca": unknown parameter "clustrs".*did you mean "clusters"' "$work/stderr" &&
    [ "$(wc -l <"$work/stderr")" -eq 1 ] && [ "$(md5sum <"$work/out.h5")" = "$before" ]; then
    echo "ok   misspelt compressor parameter: $(cat "$work/stderr")"
    pass=$((pass + 1))
  else
    echo "FAIL misspelt compressor parameter"
    sed 's/^/    stderr: /' "$work/stderr"
    failures=$((failures + 1))
  fi
fi
echo "$pass passed, $failures failed"
[ "$failures" -eq 0 ]
