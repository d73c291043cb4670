#!/usr/bin/env bash
# End to end on a real CGAL mesh under a real Blender HDRI at a small ray
# count: bake, info, render, and the accuracy trade: the per-vertex RMS error
# against the Monte Carlo ground truth falls as the SH order grows (3 > 5 > 10).
set -euo pipefail
prt="$1"
src="$2"
data="$src/data"
if [ ! -f "$data/meshes/bunny00.off" ] || [ ! -f "$data/hdri/sunrise.exr" ]; then
  echo "FAIL: real data missing in $data; run scripts/setup.sh" >&2
  exit 1
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

declare -A rms
for order in 3 5 10; do
  cat >"$work/bunny$order.toml" <<EOT
[mesh]
file = "$data/meshes/bunny00.off"
[lighting]
environment = "$data/hdri/sunrise.exr"
rotation = 90
[transport]
rays = 512
[basis]
plugin = "sh"
order = $order
[camera]
width = 320
height = 240
[ground_truth]
samples = 256
EOT
  (cd "$work" && "$prt" -q bake "bunny$order.toml" >/dev/null)
  out=$(cd "$work" && "$prt" -q render "bunny$order.toml" --compare)
  line=$(grep "RMS per vertex" <<<"$out")
  echo "order $order: $line"
  rms[$order]=$(sed -E 's/.*RMS per vertex ([0-9.eE+-]+).*/\1/' <<<"$line")
  [ -s "$work/bunny$order.png" ] || { echo "FAIL: no image for order $order"; exit 1; }
done
"$prt" info "$work/bunny10.h5" | grep -q "37706 vertices" || { echo "FAIL: info"; exit 1; }

# Compress the order-10 bake with static CPCA, then render from the compressed form.
json=$("$prt" -q compress "$work/bunny10.h5" -o "$work/cpca.h5" -c cpca \
  -p clusters=64 -p components=4 -p reclassify=true -p supercluster=greedy --json)
echo "cpca: $json"
out=$(cd "$work" && "$prt" -q render bunny10.toml --bake cpca.h5 -o cpca.png --compare)
echo "cpca render: $(grep "RMS per vertex" <<<"$out")"
python3 - "$json" "$(sed -E 's/.*RMS per vertex ([0-9.eE+-]+).*/\1/' <<<"$(grep "RMS per vertex" <<<"$out")")" "${rms[10]}" <<'PY'
import json, sys
r = json.loads(sys.argv[1])
rms_cpca, rms_exact = float(sys.argv[2]), float(sys.argv[3])
checks = {
    "SE is positive and finite": 0 < r["squared_error"] < float("inf"),
    "64 clusters": r["clusters"] == 64,
    "storage = v n' + m_c (n'+1) n": r["stored_floats"] == 37706 * 4 + 64 * 5 * 100,
    "superclusters lower overdraw": r["supercluster_overdraw"] < r["overdraw"],
    "compression costs accuracy, within reason": rms_exact <= rms_cpca < 3 * rms_exact + 0.05,
}
for name, ok in checks.items():
    print(f"{'ok  ' if ok else 'FAIL'} {name}")
sys.exit(0 if all(checks.values()) else 1)
PY
# Several encodings of one bake ranked, nothing written (the bake keeps its bytes).
before=$(md5sum <"$work/bunny10.h5")
sweep=$("$prt" -q compress "$work/bunny10.h5" --json \
  --sweep 'vq clusters=64|pca components=4|cpca clusters=16 components=4' --sweep 'pca components=16')
[ "$(md5sum <"$work/bunny10.h5")" = "$before" ] || { echo "FAIL: --sweep rewrote the bake"; exit 1; }
python3 - "$sweep" <<'PY'
import json, sys
rows = {r["configuration"]: r for r in json.loads(sys.argv[1])}
v = 37706
checks = {
    "four configurations": len(rows) == 4,
    "VQ and CPCA count a 32-bit cluster id per vertex": all(
        rows[c]["index_bytes"] == 4 * v for c in ("vq clusters=64", "cpca clusters=16 components=4")),
    "global PCA needs no index": rows["pca components=4"]["index_bytes"] == 0,
    "total = floats + indices": all(
        r["total_bytes"] == r["stored_bytes"] + r["index_bytes"] for r in rows.values()),
    "SE relative to the energy, in (0, 1)": all(
        0 < r["relative_squared_error"] < 1 for r in rows.values()),
    "more PCA components, less error": rows["pca components=16"]["relative_squared_error"]
        < rows["pca components=4"]["relative_squared_error"],
    "the front is sorted by bytes with falling error": [
        r["relative_squared_error"] for r in sorted(rows.values(), key=lambda r: r["total_bytes"])
        if r["pareto_front"]] == sorted([r["relative_squared_error"] for r in rows.values()
                                         if r["pareto_front"]], reverse=True),
}
for name, ok in checks.items():
    print(f"{'ok  ' if ok else 'FAIL'} compress --sweep: {name}")
sys.exit(0 if all(checks.values()) else 1)
PY
python3 - "${rms[3]}" "${rms[5]}" "${rms[10]}" <<'PY'
import sys
r3, r5, r10 = map(float, sys.argv[1:])
ok = r10 < r5 < r3
print(f"RMS order 3 {r3:.5g} > order 5 {r5:.5g} > order 10 {r10:.5g}: {'ok' if ok else 'FAIL'}")
sys.exit(0 if ok else 1)
PY
