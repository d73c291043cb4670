#!/usr/bin/env bash
# prt bench: a 2 x 3 sweep on a generated scene writes CSV, JSON, plots and the
# report; rerunning with one more value resumes (only the new configurations
# run); a bad sweep key is refused before any work.
# prt stability: reaches l = 100 with finite values, names the highest orders
# within 1e-10, and windowing shrinks the sun's negative area.
set -euo pipefail
prt="$1"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
cat >box.toml <<'EOT'
[mesh]
generate = "open-box"
detail = 1
[transport]
rays = 256
[basis]
plugin = "sh"
order = 4
[compressor]
plugin = "cpca"
clusters = 4
components = 2
[lighting]
constant = [1, 0.9, 0.8]
[camera]
width = 96
height = 72
position = [0.5, 2.5, 2.0]
target = [0, -0.5, 0]
[ground_truth]
samples = 64
EOT
"$prt" -q bench box.toml --out sweep --sweep 'basis=sh order=3|sh order=5' \
  --sweep 'compressor=none|vq clusters=8|cpca clusters=4 components=2' >/dev/null
for f in results.csv results.json report.md error_vs_bytes.png error_vs_relight.png \
  error_vs_bake.png strip.png; do
  [ -s "sweep/$f" ] || { echo "FAIL: sweep/$f missing"; exit 1; }
done
rows=$(($(wc -l <sweep/results.csv) - 1))
[ "$rows" = 6 ] || { echo "FAIL: $rows rows, expected 6"; exit 1; }
# Transfer SE, RMS error and its noise floor are numbers (no NaN, no empty
# fields); the GPU column is null when --gpu was not asked.
/usr/bin/python3 - sweep <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(f"{sys.argv[1]}/results.csv")))
report = open(f"{sys.argv[1]}/report.md").read()
numeric = lambda v: math.isfinite(float(v))
checks = {
    "transfer SE, RMS, noise floor are numbers": all(
        numeric(r["transfer_se"]) and numeric(r["rms"]) and float(r["noise_floor"]) > 0
        for r in rows),
    "resolved is a verdict": all(r["resolved"] in ("true", "false") for r in rows),
    "no GPU time without --gpu": all(r["gpu_frame_seconds"] == "null" for r in rows),
    "the report has the noise floor and the error budget": "noise floor" in report
        and "truncation" in report and "compression" in report,
    "the report ranks and recommends": "## Ranking" in report and "## Recommendation" in report
        and "has the smallest error" in report,
}
for name, ok in checks.items():
    print(f"{'ok  ' if ok else 'FAIL'} {name}")
sys.exit(0 if all(checks.values()) else 1)
PY
stamp=$(stat -c %Y sweep/images/sh_order_3_none.png)
sleep 1
"$prt" -q bench box.toml --out sweep --sweep 'basis=sh order=3|sh order=5|sh order=6' \
  --sweep 'compressor=none|vq clusters=8|cpca clusters=4 components=2' >/dev/null
rows=$(($(wc -l <sweep/results.csv) - 1))
[ "$rows" = 9 ] || { echo "FAIL: resumed sweep has $rows rows, expected 9"; exit 1; }
[ "$(stat -c %Y sweep/images/sh_order_3_none.png)" = "$stamp" ] || { echo "FAIL: done work redone"; exit 1; }
echo "bench: 6 configurations, resumed to 9 without redoing the first 6"
if "$prt" -q bench box.toml --sweep basis.ordr=3,5 2>err.txt; then echo "FAIL: bad key"; exit 1; fi
grep -q 'ordr' err.txt || { echo "FAIL: unclear message: $(cat err.txt)"; exit 1; }
echo "bad sweep: $(cat err.txt)"

out=$("$prt" stability --orders 5,20,101 --hemisphere-order 6)
grep -q '^| 101 | 100 | .* | yes |' <<<"$out" || { echo "FAIL: no finite l = 100 row"; exit 1; }
grep -q 'Highest l within 1e-10 (of those measured): \*\*100\*\*' <<<"$out" ||
  { echo "FAIL: evaluation not within 1e-10 at l = 100"; exit 1; }
grep -q 'Highest l within 1e-10 for rotation (of those measured): \*\*100\*\*' <<<"$out" ||
  { echo "FAIL: whole rotation not within 1e-10 at order 101"; exit 1; }
grep -q 'Highest single band within 1e-10 for rotation: \*\*1000\*\*' <<<"$out" ||
  { echo "FAIL: rotation not within 1e-10 to l = 1000"; exit 1; }
grep -q 'Highest band within 1e-10, all finite: \*\*1000\*\*' <<<"$out" ||
  { echo "FAIL: SH evaluation not finite and within 1e-10 at l = 1000"; exit 1; }
grep -E '^\| 20 \| (none|hanning) \|' <<<"$out" | awk -F'|' '
  { area[$3] = $4 }
  END { if (!(area[" hanning "] < area[" none "])) { print "FAIL: window did not help"; exit 1 }
        print "stability: negative area at order 20, none" area[" none "] ", hanning" area[" hanning "] }'
echo PASS
