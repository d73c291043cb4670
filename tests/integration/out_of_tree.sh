#!/usr/bin/env bash
# Installs the framework from the build tree into a scratch prefix, builds
# examples/zonal_basis against it with find_package(PRT), and runs the
# conformance tests that prt_add_plugin registered for it.
set -euo pipefail
build="$1"
src="$2"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$src/examples/zonal_basis" -B "$work/zonal" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_CXX_FLAGS="$(grep -q march=native "$build/CMakeCache.txt" && echo -march=native)" >/dev/null
cmake --build "$work/zonal" >/dev/null
ctest --test-dir "$work/zonal" --output-on-failure
# The installed prt finds the example through PRT_PLUGIN_PATH, next to its own plug-ins.
PRT_PLUGIN_PATH="$work/zonal/plugins" "$work/prefix/bin/prt" plugins | grep -E "^(basis|compressor|renderer) "
# The installed binaries and libraries load code only from where they belong.
bash "$src/tests/integration/load_paths.sh" "$work/prefix"
