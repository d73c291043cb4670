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

# report NAME PROBLEMS OK_TEXT: one check's verdict, counted (stderr shown on failure).
report() {
  if [ -n "$2" ]; then
    echo "FAIL $1:$2"
    sed 's/^/    stderr: /' "$work/stderr"
    failures=$((failures + 1))
  else
    echo "ok   $1: $3"
    pass=$((pass + 1))
  fi
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
  report "$name" "$problems" "$(cat "$work/stderr")"
}

# expect_warning NAME PATTERN... -- ARGS...: runs prt, which must succeed
# with every pattern (grep) on its stderr.
expect_warning() {
  local name="$1" patterns=()
  shift
  while [ "$1" != "--" ]; do patterns+=("$1") && shift; done
  shift
  (cd "$work" && "$prt" -q "$@" >"$work/stdout" 2>"$work/stderr")
  local code=$? problems=""
  [ "$code" -eq 0 ] || problems+=" exit code $code;"
  for pattern in "${patterns[@]}"; do
    grep -q -- "$pattern" "$work/stderr" || problems+=" stderr lacks '$pattern';"
  done
  report "$name" "$problems" "$(tr '\n' ' ' <"$work/stderr")"
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
expect_error "sweep of a parameter the plug-in lacks" \
  'good.toml: error: --sweep configuration "clusters=64": compressor "none": unknown parameter "clusters"; it takes no parameters' \
  -- bench good.toml --sweep compressor.clusters=64,256 --out sweep_out
report "a refused sweep writes no folder" "$([ -e "$work/sweep_out" ] && echo ' sweep_out was created;')" "none"

good_scene | sed 's/^rays = 64/rays = 0/' >"$work/range.toml"
{ good_scene; printf '[compressor]\nplugin = "pca"\n%s = 1\n' "$(head -c 1000000 /dev/zero | tr '\0' k)"; } >"$work/long_key.toml"
expect_error "out of range" 'range.toml:10:1: error: section \[transport\]: parameter "rays" = 0 is out of range \[1, 4194304\]' -- bake range.toml

# Issue 45: inputs that used to be accepted silently, or hang, or abort.
mesh="$src/data/meshes/bunny00.off"
start=$(date +%s%N)
expect_error "subdivide to 10^12 vertices" 'error: --vertices 1000000000000: meshes are limited to' -- subdivide "$mesh" -o big.ply -n 1000000000000
expect_error "subdivide beyond memory" 'error: --vertices 100000000: the subdivided mesh needs about 40.0 GB of memory' -- subdivide "$mesh" -o big.ply -n 100000000
elapsed_ms=$((($(date +%s%N) - start) / 1000000))
if [ "$elapsed_ms" -lt 4000 ]; then
  echo "ok   both subdivide refusals came up front ($elapsed_ms ms)"
  pass=$((pass + 1))
else
  echo "FAIL subdivide refusals took $elapsed_ms ms"
  failures=$((failures + 1))
fi
# Under a 2 GB address-space limit (where 10^12 used to abort with "pure
# virtual method called") the limit is part of the memory available.
(cd "$work" && ulimit -v 2000000 && "$prt" -q subdivide "$mesh" -o lim.ply -n 10000000 >/dev/null 2>"$work/stderr")
code=$?
if [ "$code" -ne 0 ] && [ "$code" -lt 128 ] && [ "$(wc -l <"$work/stderr")" -eq 1 ] &&
  grep -q "memory" "$work/stderr" && [ ! -e "$work/lim.ply" ]; then
  echo "ok   subdivide under ulimit -v 2 GB: $(cat "$work/stderr")"
  pass=$((pass + 1))
else
  echo "FAIL subdivide under ulimit -v 2 GB: exit $code"
  sed 's/^/    stderr: /' "$work/stderr"
  failures=$((failures + 1))
fi
# A command-line value is refused by the argument parser (its own two-line form).
(cd "$work" && "$prt" -q render good.toml --exposure nan >/dev/null 2>"$work/stderr")
if [ $? -ne 0 ] && grep -q 'exposure "nan" is not a finite positive number' "$work/stderr" &&
  [ ! -e "$work/out.png" ]; then
  echo "ok   exposure NaN: $(head -n 1 "$work/stderr")"
  pass=$((pass + 1))
else
  echo "FAIL exposure NaN accepted"
  failures=$((failures + 1))
fi
echo "my notes" >"$work/notes.txt"
expect_error "stability report over a note" 'notes.txt: error: refusing to replace a text file with a JSON file' -- stability --json notes.txt
grep -q "my notes" "$work/notes.txt" || { echo "FAIL the note was changed"; failures=$((failures + 1)); }
expect_error "a 10^6-character key is elided" 'characters elided' -- bake long_key.toml
[ "$(wc -c <"$work/stderr")" -lt 2500 ] || { echo "FAIL the long key's message has $(wc -c <"$work/stderr") bytes"; failures=$((failures + 1)); }

# A budget beyond what the data supports is used as far as it goes, with a
# warning at the key's line that says what was used.
{ good_scene | sed 's/^bake = .*/bake = "budget.h5"/; s/^image = .*/image = "budget.png"/'
  printf '[compressor]\nplugin = "cpca"\nclusters = 1000000\ncomponents = 8\n'; } >"$work/budget.toml"
expect_warning "budgets beyond the data warn with the value used" \
  'budget.toml:16:1: compressor "cpca": clusters = 1000000 is more than .*; [0-9]* used' -- bake budget.toml
# More components than coefficients would store more than the transfer: refused at the key.
{ good_scene | sed 's/^bake = .*/bake = "out.h5"/; s/^image = .*/image = "out.png"/'
  printf '[compressor]\nplugin = "pca"\ncomponents = 100000\n'; } >"$work/components.toml"
expect_error "components beyond the coefficients are refused" \
  "components.toml:16:1: error: parameter \"components\": compressor \"pca\": 100000 is more than the transfer's 9 coefficients per vertex" -- bake components.toml
{ good_scene | sed 's/^bake = .*/bake = "haar.h5"/; s/^image = .*/image = "haar.png"/; s/^plugin = "sh"/plugin = "haar"\nresolution = 4\nk = 1000000000/; /^order = 3/d'; } >"$work/haar.toml"
expect_warning "haar k beyond its coefficients warns" \
  'basis "haar": k = 1000000000 is more than its 96 coefficients (resolution 4); 96 used' -- bake haar.toml

# Under-sampling is said, not silent: a cube map rounds rays to 6 R^2, and
# fewer directions than twice the basis's functions alias.
{ good_scene | sed 's/^bake = .*/bake = "sampled.h5"/; s/^image = .*/image = "sampled.png"/; s/^rays = 64/directions = "cubemap"\nrays = 256/; s/^order = 3/order = 13/'; } >"$work/sampled.toml"
expect_warning "under-sampling is said" 'sampled.toml:11:1: rays = 256 makes a 6 x 7 x 7 cube map: 294 directions' \
  "sampled.toml:11:1: 294 directions for basis .sh.'s 169 functions: fewer than twice as many" -- bake sampled.toml

# A basis that claims an orthonormality it lacks is refused before any ray
# (its relight would silently be wrong); the honest one bakes.
variants="$(dirname "$(dirname "$(realpath "$prt")")")/test_plugins/variants"
if [ -d "$variants/claims_orthonormal" ]; then
  good_scene | sed 's/^plugin = "sh"/plugin = "variant"/; /^order = 3/d' >"$work/claims.toml"
  export PRT_PLUGIN_PATH="$variants/claims_orthonormal"
  expect_error "a false orthonormality claim" 'claims.toml:7:10: error: basis "variant" says it is orthonormal, but its Gram matrix differs from the identity by 0.5' -- bake claims.toml
  unset PRT_PLUGIN_PATH
  export PRT_PLUGIN_PATH="$variants/good"
  expect_warning "the orthonormal variant bakes" -- bake claims.toml
  unset PRT_PLUGIN_PATH
fi

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
