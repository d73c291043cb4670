#!/usr/bin/env bash
# Every stage benchmark of the performance issue (12) in one run, as one table:
#   stage | time | bound (measured in the same run) | ratio | limit | PASS/FAIL
# Benchmarks, not tests: the suite never runs this (only the `long` ctest
# entry of docs/performance.md's block does). Needs the build (it runs
# scripts/build.sh when a benchmark is missing) and, for the OpenGL rows, a
# display (it wraps itself in xvfb-run when DISPLAY is unset).
#
#   scripts/perf.sh            # ~5 minutes on 2 cores; logs in out/perf/
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="$root/build/bin"
out="$root/out/perf"
mkdir -p "$out"
[ -x "$bin/bench_rotation" ] || bash "$root/scripts/build.sh" >/dev/null
gl=()
[ -n "${DISPLAY:-}" ] || gl=(xvfb-run -a)

# Scenes: the bunny's diffuse CPCA 256x8 (scenes/bunny_cpca.toml), its order-10
# exact transfer (scenes/bunny.toml) and the paper's glossy 24x25 (order-5
# light, reduced order-5 hemispherical exit basis, CPCA 256x8).
scene() {  # source scene, name, sed program
  sed "$3; s|\"\\.\\./|\"../../|g; s|out/[a-z_0-9]*\\.h5|out/perf/$2.h5|; s|out/[a-z_0-9]*\\.png|out/perf/$2.png|" \
    "$root/scenes/$1" >"$out/$2.toml"
}
scene bunny.toml bunny ''
scene bunny_cpca.toml bunny_cpca ''
scene bunny_glossy.toml bunny_glossy_24x25 's/^order = 10$/order = 5/; s/^method = "iterative"$/method = "static"/; s/^clusters = 512$/clusters = 256/; s/^components = 12$/components = 8/; /^iterations_per_component = /d'
for s in bunny bunny_cpca bunny_glossy_24x25; do
  [ -f "$out/$s.h5" ] || "$bin/prt" -q bake "$out/$s.toml" >"$out/bake_$s.log"
done

run() {  # log name, command...
  local log="$out/$1.log"
  shift
  echo "running: ${*#"$root/"}" >&2
  "$@" >"$log" 2>&1 || true  # a FAIL row says what failed; keep going
}
run rotation "$bin/bench_rotation" 10
run light "$bin/bench_light" 10
run bake_1024 "$bin/bench_bake" "$root/data/meshes/bunny00.off" 1024 10 5
run bake_4096 "$bin/bench_bake" "$root/data/meshes/bunny00.off" 4096 10 5
run truth "$bin/bench_truth" "$root/data/meshes/bunny00.off" "$root/data/hdri/courtyard.exr" 1024 3
run compress_diffuse "$bin/bench_compress" "$out/bunny.h5" 256 8 iterative
run compress_glossy "$bin/bench_compress" "$out/bunny_glossy_24x25.h5" 256 8 iterative 40
run eigen "$bin/bench_eigen"
run view_diffuse "${gl[@]}" "$bin/bench_view" "$out/bunny_cpca.toml" 20
run view_glossy "${gl[@]}" "$bin/bench_view" "$out/bunny_glossy_24x25.toml" 20

table="$out/table.md"
{
  echo "| stage | time | bound (same run) | ratio | limit | result |"
  echo "|---|---|---|---|---|---|"
  for log in rotation light bake_1024 bake_4096 truth compress_diffuse compress_glossy eigen \
    view_diffuse view_glossy; do
    if grep -q '^PERF|' "$out/$log.log"; then
      grep '^PERF|' "$out/$log.log" | awk -F'|' '{ printf "|"; for (i = 2; i <= NF; ++i) printf " %s |", $i; print "" }'
    else
      echo "| $log | - | - | - | - | FAIL (no result: see out/perf/$log.log) |"
    fi
  done
} >"$table"
cat "$table"
! grep -q 'FAIL' "$table"
