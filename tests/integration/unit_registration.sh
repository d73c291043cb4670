#!/usr/bin/env bash
# Every Catch test of prt_tests is a ctest entry under its own name: Catch's
# own list against the file catch_discover_tests wrote. CMake misreads some
# names: an unbalanced '[' opens a bracket argument and merged every entry
# after it (the suite ran 31 of the unit tests), and a ';' splits a name in
# two entries whose filters match no test (two tests ran nothing).
#   unit_registration.sh <prt_tests> <its build folder>
set -euo pipefail
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# Catch 2 exits with the number of tests it lists.
{ "$1" --list-test-names-only || true; } | grep . | sort >"$work/listed"
files=("$2"/prt_tests_tests-*.cmake)
[ -f "${files[0]}" ] || { echo "FAIL: no prt_tests_tests-*.cmake in $2"; exit 1; }
grep '^add_test( \[==\[unit\.' "${files[0]}" | sed 's/^add_test( \[==\[unit\.//; s/\]==\].*//' |
  sort >"$work/registered"
if ! diff "$work/listed" "$work/registered" >"$work/diff"; then
  echo "FAIL: the unit tests ctest registers differ from prt_tests' own (a name with '[' or ';'?):"
  cat "$work/diff"
  exit 1
fi
echo "all $(wc -l <"$work/listed") unit tests are ctest entries under their own names"
