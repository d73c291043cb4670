#!/usr/bin/env bash
# The basis conformance kit catches the bugs researchers make: the correct
# variant basis passes every check; each broken variant fails the check that
# its bug violates, with a readable message (no bare numbers).
#   kit_catches_variants.sh <prt_basis_conformance> <variants folder>
set -uo pipefail
kit="$1"
root="$2"
failures=0
run() { PRT_PLUGIN_PATH="$root/$1" "$kit" --plugin variant "${@:2}" 2>&1; }
check() {  # variant, expected failing test case, text its message must contain
  local out
  out=$(run "$1")
  if [ $? -eq 0 ]; then
    echo "FAIL $1: the kit passed"; failures=$((failures + 1)); return
  fi
  if ! grep -qF "$2" <<<"$out" || ! grep -qF "$3" <<<"$out"; then
    echo "FAIL $1: expected a failure of \"$2\" mentioning \"$3\"; got:"
    grep -A12 "FAILED" <<<"$out" | head -30
    failures=$((failures + 1)); return
  fi
  echo "ok   $1 fails \"$2\" ($3)"
}
if out=$(run good); then echo "ok   the correct variant passes"; else
  echo "FAIL the correct variant fails:"; grep -A12 FAILED <<<"$out" | head -30; failures=$((failures + 1)); fi
check normalisation "an orthonormal basis has an identity Gram matrix" "identity"
check weights "native quadrature weights integrate 1 to the domain's measure" "weights sum to 25.13"
check size "every boolean and choice parameter value gives a consistent basis" "drop_constant=true"
check reflection "rotation is consistent with re-projection and composes" "ra * rb"
check local_fit "a distributed fit equals the one-process fit bit for bit" "visible_fraction"
check claims_orthonormal "relighting equals the integral of light times transfer" "G = I: the basis says it is orthonormal"
check gram_factor "relighting equals the integral of light times transfer" "G from the basis's rule"
check horizon "exit radiance equals the BRDF integral toward every view, grazing ones included" "exit radiance of a Phong lobe"
echo "$failures failure(s)"
[ "$failures" -eq 0 ]
