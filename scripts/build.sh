#!/usr/bin/env bash
# Configures and builds PRT (Release) into build/.
#   scripts/build.sh [--target NAME ...] [CMAKE_ARGS ...]
# --target builds only the named targets (scripts/demo.sh: the CLI and the
# plug-ins its scene names); without it, everything (tests, benchmarks,
# fuzzers). Other arguments go to CMake when it configures.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
targets=()
cmake_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --target) targets+=(--target "$2"); shift 2 ;;
    *) cmake_args+=("$1"); shift ;;
  esac
done
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
# Configured once; again when CMake arguments are given (scripts/test.sh
# requires every optional part, which a build for the demo may have left
# out: packages installed since are found then).
if [ ! -f "$root/build/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$root/build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "${cmake_args[@]}"
elif [ ${#cmake_args[@]} -gt 0 ]; then
  cmake -S "$root" -B "$root/build" "${cmake_args[@]}"
fi
cmake --build "$root/build" --parallel "$(nproc)" "${targets[@]}"
