#!/usr/bin/env bash
# The AddressSanitizer + UndefinedBehaviorSanitizer configuration: the
# framework, every plug-in, the broken test plug-ins, the unit tests and the
# conformance kit, built with gcc into build-asan/ and run under ctest.
# Left out, to fit CI's budget: the apps (prt, prt-view) and the integration
# tests that drive them (the same library code runs, unsanitized, in the main
# suite; the readers they feed are fuzzed under ASan + UBSan by scripts/fuzz.sh),
# and the unit tests listed in `slow` below (each >1 min under ASan; the same
# code paths run in faster tests here).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="$root/build-asan"
flags="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if [ ! -f "$out/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$out" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_FLAGS_RELEASE="-O1 -g -DNDEBUG" -DCMAKE_CXX_FLAGS="$flags" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_MODULE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
fi
cmake --build "$out" --parallel "$(nproc)" --target prt_tests prt_basis_conformance \
  prt_compressor_conformance prt_renderer_conformance
# conformance.renderer.opengl: Mesa's llvmpipe under LeakSanitizer reports the
# driver's own allocations; the CPU renderer's kit runs here.
slow='16k clusters|iterative CPCA on the bunny|conformance.renderer.opengl'
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# Leaks inside third-party libraries only (OpenMesh, libhdf5), with reasons.
export LSAN_OPTIONS="suppressions=$root/tests/fuzz/lsan.supp:print_suppressions=0"
ctest --test-dir "$out" --output-on-failure --parallel "$(nproc)" --timeout 900 \
  -R '^(unit|conformance)\.' -E "$slow"
