#!/usr/bin/env bash
# The message catalogue of docs/user-guide.md ("## Messages") matches what is
# printed: each case below makes one bad input, runs prt and takes the first
# line on stderr; the catalogue row of the same name must match it ("…" in the
# catalogue stands for any text). `messages.sh PRT DOC --print` prints the rows.
set -u
prt="$(realpath "$1")"
doc="$(realpath "$2")"
mode="${3:-check}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
out="$work/cases.tsv"
: >"$out"

scene() {  # scene NAME [extra TOML lines]: a small valid scene plus the extras
  local name="$1"
  shift
  { printf '[mesh]\n%s\n[lighting]\nconstant = [1, 1, 1]\n[basis]\nplugin = "sh"\norder = 3\n[transport]\nrays = 64\n' "${MESH:-generate = \"sphere\"}"
    for line in "$@"; do printf '%s\n' "$line"; done; } >"$name"
}
case_() {  # case_ NAME -- ARGS: runs prt, records the first stderr line
  local name="$1"
  shift 2
  "$prt" -q "$@" >/dev/null 2>stderr
  printf '%s\t%s\n' "$name" "$(head -n 1 stderr)" >>"$out"
}

scene good.toml
"$prt" -q bake good.toml -o good.h5 >/dev/null
printf '[mesh]\ngenerate = "sphere"\n[lighting]\nconstant = [1, 1, 1]\n[basis]\nplugin = "sh"\nordr = 3\n' >s.toml
case_ "misspelt key" -- bake s.toml
printf '[mesh]\ngenerate = "sph\xffre"\n' >utf8.toml
case_ "not UTF-8 text" -- bake utf8.toml
printf '[mesh]\ngenerate = sph\xc3\xa9re\n' >bare.toml
case_ "non-ASCII outside a string" -- bake bare.toml
mkdir -p folder
case_ "a directory as the scene" -- bake folder
MESH='file = "folder"' scene dirmesh.toml
case_ "a directory as the mesh" -- bake dirmesh.toml
printf '[lighting]\nconstant = [1, 1, 1]\n' >nomesh.toml
case_ "no mesh section" -- bake nomesh.toml
scene camera.toml '[camera]' 'position = [0, 0, 3]' 'target = [0, 0, 3]'
case_ "camera at its target" -- render camera.toml --ground-truth -o camera.png
printf 'OFF\n1000000000000 1 0\n0 0 0\n' >big.off
MESH='file = "big.off"' scene big.toml
case_ "OFF header of 10^12 vertices" -- bake big.toml
{ printf 'OFF\n400 200 0\n'; for i in $(seq 1 100); do echo "$i 0 0"; done; } >cut.off
MESH='file = "cut.off"' scene cut.toml
case_ "truncated OFF" -- bake cut.toml
printf 'ply\nformat ascii 1.0\nelement vertex 100000000\n' >noend.ply
MESH='file = "noend.ply"' scene noend.toml
case_ "PLY without end_header" -- bake noend.toml
{ printf 'ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n'
  printf '\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x80\x3f\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x80\x3f\0\0\0\0'
  printf '\x03\0\0\0\0\x01\0\0\0\x3f\x42\x0f\0'; } >index.ply
MESH='file = "index.ply"' scene index.toml
case_ "binary PLY index out of range" -- bake index.toml
printf 'solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nfacet normal 0 0 1\n' >cut.stl
MESH='file = "cut.stl"' scene stl.toml
case_ "truncated ASCII STL" -- bake stl.toml
{ printf '#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 32 +X 16\n'; head -c 1000 /dev/zero; } >sky.hdr
sed 's|constant = \[1, 1, 1\]|environment = "sky.hdr"|' good.toml >sky.toml
case_ ".hdr with missing pixels" -- render sky.toml --ground-truth -o sky.png
"$prt" -q render good.toml --bake good.h5 -o image.png >/dev/null 2>&1
cp image.png png.hdr
sed 's|constant = \[1, 1, 1\]|environment = "png.hdr"|' good.toml >png.toml
case_ "a PNG named .hdr" -- render png.toml --ground-truth -o png.png
cp good.h5 flipped.h5
printf '\x55' | dd of=flipped.h5 bs=1 seek=2000 conv=notrunc status=none
case_ "bit-flipped bake" -- info flipped.h5
# Sealed with a valid checksum; libhdf5 1.10 crashes parsing it (kept by fuzzing).
cp "$(dirname "$doc")/../tests/fuzz/regressions/bake_sealed/hdf5_sigsegv_1.h5" crash.h5
case_ "crafted bake that crashes libhdf5" -- info crash.h5
head -c 3000 good.h5 >cut.h5
case_ "truncated bake" -- info cut.h5
case_ "output over an input" -- bake good.toml -o good.toml
mkfifo fifo
case_ "output over a FIFO" -- bake good.toml -o fifo
case_ "output over another kind" -- bake good.toml -o image.png
scene large.toml '[transport]' 'rays = 4194304'
sed -i '0,/^rays = 64$/{/^rays = 64$/d}; 0,/^\[transport\]$/{/^\[transport\]$/d}; s/^order = 3$/order = 150/' large.toml
case_ "too large for the machine" -- bake large.toml
mkdir -p plugins && chmod 755 plugins && echo junk >plugins/libprt-basis-junk.so
PRT_PLUGIN_PATH="$work/plugins" "$prt" plugins >/dev/null 2>stderr
printf '%s\t%s\n' "bad plug-in file on the path" "$(head -n 1 stderr | sed "s|$work/||")" >>"$out"

if [ "$mode" = "--print" ]; then
  awk -F'\t' '{ printf "| %s | `%s` |\n", $1, $2 }' "$out"
  exit 0
fi
/usr/bin/python3 - "$doc" "$out" <<'PY'
import re, sys
doc, cases = sys.argv[1], sys.argv[2]
text = open(doc, encoding="utf-8").read()
section = text.split("## Messages", 1)[1].split("\n## ", 1)[0]
rows = {}
for line in section.splitlines():
    m = re.match(r"\| (.+?) \| `(.*)` \|$", line)
    if m:
        rows[m.group(1)] = m.group(2)
passed = failed = 0
for line in open(cases, encoding="utf-8"):
    name, printed = line.rstrip("\n").split("\t", 1)
    expected = rows.get(name)
    pattern = None if expected is None else "^" + ".*".join(re.escape(p) for p in expected.split("…")) + "$"
    if expected is None:
        print(f"FAIL {name}: no catalogue row; printed: {printed}")
        failed += 1
    elif not re.match(pattern, printed):
        print(f"FAIL {name}:\n    catalogue: {expected}\n    printed:   {printed}")
        failed += 1
    else:
        print(f"ok   {name}: {printed}")
        passed += 1
print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed else 0)
PY
