#!/usr/bin/env bash
# The basis conformance kit is not a rubber stamp: on a deliberately wrong
# basis (tests/broken_plugins/wrong_basis.cpp) it must fail exactly the checks
# that the basis violates, and pass the others.
set -uo pipefail
kit="$1"
plugins="$2"
out=$(PRT_PLUGIN_PATH="$plugins" "$kit" --plugin wrong 2>&1)
code=$?
failures=0
expect() {  # expect failed|passed "test case name": runs that one case alone
  local state="$1" name="$2" failed=0
  PRT_PLUGIN_PATH="$plugins" "$kit" --plugin wrong "$name" >/dev/null 2>&1 || failed=1
  if { [ "$state" = failed ] && [ $failed -eq 1 ]; } || { [ "$state" = passed ] && [ $failed -eq 0 ]; }; then
    echo "ok   $state: $name"
  else
    echo "FAIL expected $state: $name"
    failures=$((failures + 1))
  fi
}
[ "$code" -ne 0 ] && echo "ok   the kit exits non-zero ($code)" || { echo "FAIL the kit passed"; failures=$((failures + 1)); }
expect failed "an orthonormal basis has an identity Gram matrix"
expect failed "projection reconstructs functions in the span"
expect failed "rotation is consistent with re-projection and composes"
expect passed "basis values are finite everywhere, poles included"
expect passed "projection is linear and scales from 1e-6 to 1e6"
# A failure says what was measured and what the check allows.
gram=$(PRT_PLUGIN_PATH="$plugins" "$kit" --plugin wrong "an orthonormal basis has an identity Gram matrix" 2>&1)
if grep -q "maxCoeff() <= 1e-9: measured [0-9.e+-]*, expected at most 1e-09" <<<"$gram"; then
  echo "ok   the Gram failure prints the measured deviation and the tolerance"
else
  echo "FAIL the Gram failure does not print measured and expected values:"
  echo "$gram" | head -n 20
  failures=$((failures + 1))
fi
echo "$((6 - failures)) passed, $failures failed"
[ "$failures" -eq 0 ]
