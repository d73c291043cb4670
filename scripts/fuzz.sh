#!/usr/bin/env bash
# Builds the libFuzzer harnesses (tests/fuzz, clang, ASan + UBSan) into
# build-fuzz/ against the main build's libprt.so and runs them.
#   scripts/fuzz.sh [TARGET|all] [SECONDS] [-- extra libFuzzer flags]
# TARGET: scene, mesh, image, bake, bake_sealed, elf. bake_sealed is the bake
# harness with PRT_FUZZ_SEAL=1: every input gets a valid checksum first, as a
# crafted file would, so it reaches libhdf5 (in the child that parses it). Each run starts from the seed corpus
# (tests/fuzz/corpus/TARGET plus files made from the build and data/), replays
# every kept regression input (tests/fuzz/regressions/TARGET), and stops at
# the first sanitizer report, which is saved under build-fuzz/artifacts/.
# Prints one line per target: executions, corpus size, result.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
targets="${1:-all}"
seconds="${2:-60}"
shift $(($# > 2 ? 2 : $#))
[ "${1:-}" = "--" ] && shift
[ "$targets" = all ] && targets="scene mesh image bake bake_sealed elf"
build="$root/build"
out="$root/build-fuzz"
[ -f "$build/lib/libprt.so" ] || { echo "fuzz: build the project first (scripts/build.sh)"; exit 1; }
command -v clang++ >/dev/null || { echo "fuzz: clang++ is missing (apt-get install clang)"; exit 1; }
if [ ! -f "$out/build.ninja" ]; then
  CC=clang CXX=clang++ cmake -S "$root/tests/fuzz" -B "$out" -G Ninja -DPRT_BUILD="$build" >/dev/null
fi
cmake --build "$out" >/dev/null

# Seeds made from the build: a small bake and the test plug-ins' ELF files.
seeds="$out/seeds"
mkdir -p "$seeds"/{scene,mesh,image,bake,elf}
ln -sfn bake "$seeds/bake_sealed"
if [ ! -f "$seeds/bake/sphere.h5" ]; then
  work="$(mktemp -d)"
  printf '[mesh]\ngenerate = "sphere"\ndetail = 0\n[lighting]\nconstant = [1, 1, 1]\n[basis]\nplugin = "sh"\norder = 2\n[transport]\nrays = 16\n[compressor]\nplugin = "cpca"\nclusters = 2\ncomponents = 1\n' >"$work/s.toml"
  "$build/bin/prt" -q bake "$work/s.toml" -o "$seeds/bake/sphere.h5" >/dev/null
  rm -rf "$work"
fi
cp -n "$build"/test_plugins/good/*.so "$build"/test_plugins/not_a_plugin/*.so "$seeds/elf/" 2>/dev/null || true
if [ -f "$root/data/hdri/studio.exr" ] && [ ! -f "$seeds/image/studio.exr" ]; then
  { printf '\001'; cat "$root/data/hdri/studio.exr"; } >"$seeds/image/studio.exr"
fi

# Leaks inside third-party libraries are listed, with reasons, in this file.
export LSAN_OPTIONS="suppressions=$root/tests/fuzz/lsan.supp:print_suppressions=0"
status=0
for target in $targets; do
  harness="$out/fuzz_${target%_sealed}"
  # A sealed input may loop libhdf5 in the parsing child until its own 10 s
  # processor-time limit ends it (under ASan a crash can become a loop).
  timeout=10
  if [ "$target" = bake_sealed ]; then export PRT_FUZZ_SEAL=1 timeout=30; else unset PRT_FUZZ_SEAL; fi
  corpus="$out/corpus/$target"
  artifacts="$out/artifacts/$target/"
  mkdir -p "$corpus" "$artifacts"
  regressions="$root/tests/fuzz/regressions/$target"
  # Kept crashing inputs run once each first: a fixed bug stays fixed.
  if [ -d "$regressions" ] && [ -n "$(ls -A "$regressions")" ]; then
    if ! "$harness" -rss_limit_mb=2048 -timeout=$timeout "$regressions"/* >"$out/$target.replay.log" 2>&1; then
      echo "fuzz $target: a regression input fails again (see $out/$target.replay.log)"
      status=1
      continue
    fi
  fi
  log="$out/$target.log"
  set +e
  # The working corpus first (new inputs go there), then the seeds that exist.
  dirs=("$corpus")
  for dir in "$root/tests/fuzz/corpus/$target" "$seeds/$target"; do
    [ -d "$dir" ] && dirs+=("$dir")
  done
  "$harness" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=$timeout -max_len=65536 \
    -print_final_stats=1 -artifact_prefix="$artifacts" "$@" "${dirs[@]}" >"$log" 2>&1
  code=$?
  set -e
  # The harnesses' scratch folders (/tmp/prt-fuzz-PID) of processes that are gone.
  for dir in /tmp/prt-fuzz-*; do
    [ -d "$dir" ] && ! kill -0 "${dir##*-}" 2>/dev/null && rm -rf "$dir"
  done
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  size=$(ls "$corpus" | wc -l)
  if [ "$code" -eq 0 ]; then
    echo "fuzz $target: ${execs:-?} executions in ${seconds} s, corpus $size inputs, no report"
  else
    echo "fuzz $target: REPORT after ${execs:-?} executions (exit $code); see $log and $artifacts"
    grep -m 3 -E "ERROR|runtime error|SUMMARY" "$log" | sed 's/^/    /'
    status=1
  fi
done
exit $status
