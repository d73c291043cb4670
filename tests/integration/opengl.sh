#!/usr/bin/env bash
# The OpenGL renderer and prt-view under Xvfb + Mesa (llvmpipe):
#  - the OpenGL image of each encoding (exact, CPCA single-pass and
#    per-cluster, Haar's sparse form, glossy CPCA, glossy Haar) matches the CPU renderer's
#    image of the same scene and camera: mean absolute difference below 0.5
#    of 255 and under 0.5% of pixels off by more than 8 levels;
#  - prt-view renders scripted frames and exits cleanly; its screenshot
#    changes when the light rotates and when the camera orbits;
#  - a probe and a texel scene draw alike on both renderers and in prt-view;
#  - a bad scene and a missing bake get clear messages, not crashes.
set -euo pipefail
prt="$1"
viewer="$2"
src="$3"
data="$src/data"
[ -f "$data/meshes/bunny00.off" ] || { echo "FAIL: run scripts/setup.sh" >&2; exit 1; }
command -v xvfb-run >/dev/null || { echo "FAIL: xvfb-run missing; run scripts/setup.sh" >&2; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
x() { xvfb-run -a -s "-screen 0 1024x768x24" "$@"; }

scene() {  # name, material, basis, compressor
  cat >"$1.toml" <<EOT
[mesh]
file = "$data/meshes/bunny00.off"
[material]
albedo = [0.9, 0.75, 0.6]
$2
[transport]
rays = 512
[basis]
$3
[compressor]
$4
[lighting]
environment = "$data/hdri/courtyard.exr"
rotation = 90
[camera]
width = 320
height = 240
EOT
}
scene exact 'brdf = "lambert"' 'plugin = "sh"
order = 6' 'plugin = "none"'
scene cpca 'brdf = "lambert"' 'plugin = "sh"
order = 6' 'plugin = "cpca"
clusters = 64
components = 4
reclassify = true
supercluster = "greedy"'
scene haar 'brdf = "lambert"' 'plugin = "haar"
resolution = 8
k = 48' 'plugin = "none"'
scene glossy 'brdf = "phong"
diffuse = 0.4
specular = 0.6
exponent = 12' 'plugin = "sh"
order = 5
[exit]
plugin = "hsh"
reduced = true' 'plugin = "cpca"
clusters = 64
components = 4'
# Glossy transfer of a Haar light (any sphere basis serves as the light basis).
scene glossy_haar 'brdf = "phong"
diffuse = 0.4
specular = 0.6
exponent = 12' 'plugin = "haar"
resolution = 4
[exit]
plugin = "hsh"
order = 3' 'plugin = "pca"
components = 8'
sed -i 's/^rays = 512$/directions = "cubemap"\nrays = 96/' glossy_haar.toml

check_match() {  # label, cpu.png, gl.png
  line=$("$prt" image-diff "$2" "$3")
  echo "$1: $line"
  awk -v l="$line" 'BEGIN { split(l, w, " "); mad = w[4]; frac = w[12] + 0;
    if (mad > 0.5 || frac > 0.5) { print "FAIL: images differ too much"; exit 1 } }'
}

for s in exact cpca haar glossy glossy_haar; do
  "$prt" -q bake "$s.toml" >/dev/null
  "$prt" -q render "$s.toml" -o "cpu_$s.png" >/dev/null
  x "$prt" -q render "$s.toml" -r opengl -o "gl_$s.png" >/dev/null
  check_match "$s single-pass" "cpu_$s.png" "gl_$s.png"
done
out=$(x "$prt" -q render cpca.toml -r opengl --renderer-param method=per-cluster -o gl_cpca_pc.png)
check_match "cpca per-cluster" cpu_cpca.png gl_cpca_pc.png
overdraw=$(sed -n 's/^renderer overdraw: //p' <<<"$out")
expected=$("$prt" info cpca.h5 | sed -n 's/^ *supercluster_overdraw = //p')
echo "per-cluster overdraw $overdraw, compressor's supercluster overdraw $expected"
awk -v a="$overdraw" -v b="$expected" 'BEGIN { if (a - b > 1e-3 || b - a > 1e-3 || a < 1) { print "FAIL: overdraw"; exit 1 } }'
out=$(x "$prt" -q render glossy.toml -r opengl --renderer-param method=per-cluster -o gl_glossy_pc.png)
check_match "glossy per-cluster" cpu_glossy.png gl_glossy_pc.png

# The viewer: scripted frames, light rotation and camera orbit change the picture.
# (No background: only the mesh can change.)
x "$viewer" -q glossy.toml --frames 1 --screenshot v0.png >/dev/null
x "$viewer" -q glossy.toml --frames 1 --no-background --screenshot v1.png >/dev/null
x "$viewer" -q glossy.toml --frames 2 --light-step 120 --no-background --screenshot v_light.png >/dev/null
x "$viewer" -q glossy.toml --frames 2 --light-step 0 --orbit-step 30 --no-background \
  --screenshot v_orbit.png >/dev/null
x "$viewer" -q glossy.toml --frames 3 --heatmap --method per-cluster --screenshot v_heat.png >/dev/null
check_match "viewer frame vs prt render" cpu_glossy.png v0.png
for f in v_light v_orbit; do
  line=$("$prt" image-diff v1.png "$f.png")
  echo "$f vs first frame: $line"
  awk -v l="$line" 'BEGIN { split(l, w, " "); if (w[4] < 1.0) { print "FAIL: no change"; exit 1 } }'
done
[ -s v_heat.png ] || { echo "FAIL: no heat-map screenshot"; exit 1; }

# A probe scene (docs/receivers.md): the OpenGL image of the probe-shaded
# scene matches the CPU's, prt-view's first frame matches prt render, and
# moving the object (the point-light keys, scripted) changes the picture.
cat >probes.toml <<EOT
[mesh]
generate = "room"
detail = 1
[receivers]
kind = "probes"
spacing = 0.8
[moving]
generate = "sphere"
position = [0.0, 0.0, 0.5]
size = 0.8
[transport]
rays = 256
[basis]
plugin = "sh"
order = 6
[exit]
plugin = "sh"
order = 3
[lighting]
environment = "$data/hdri/courtyard.exr"
rotation = 180
[camera]
position = [-1.5, 1.5, -1.5]
target = [0.0, 0.4, 0.5]
width = 320
height = 240
EOT
"$prt" -q bake probes.toml >/dev/null
"$prt" -q render probes.toml -o cpu_probes.png >/dev/null
x "$prt" -q render probes.toml -r opengl -o gl_probes.png >/dev/null
check_match "probes" cpu_probes.png gl_probes.png
x "$viewer" -q probes.toml --frames 1 --light-step 0 --screenshot vp0.png >/dev/null
check_match "viewer probe frame vs prt render" cpu_probes.png vp0.png
out=$(x "$viewer" probes.toml --frames 3 --light-step 0 --point-step 4 0 0 --screenshot vp_moved.png)
grep -q "moving object at" <<<"$out" || { echo "FAIL: no moving object in the status: $out"; exit 1; }
line=$("$prt" image-diff vp0.png vp_moved.png)
echo "moved object vs first frame: $line"
awk -v l="$line" 'BEGIN { split(l, w, " "); if (w[4] < 0.05) { print "FAIL: no change"; exit 1 } }'

# A texel scene (docs/receivers.md): the OpenGL renderer's texture lookup
# (GL_LINEAR) matches the CPU renderer's bilinear lookup, and prt-view's
# first frame matches prt render.
cat >texels.toml <<EOT
[mesh]
file = "$data/meshes/nefertiti.off"
[receivers]
kind = "texels"
resolution = 32
[transport]
rays = 256
[basis]
plugin = "sh"
order = 6
[lighting]
environment = "$data/hdri/courtyard.exr"
rotation = 90
[camera]
position = [0.0, 0.3, 8.0]
target = [0.0, 0.0, -0.4]
width = 240
height = 280
fov = 40
EOT
"$prt" -q bake texels.toml >/dev/null
"$prt" -q render texels.toml -o cpu_texels.png >/dev/null
x "$prt" -q render texels.toml -r opengl -o gl_texels.png >/dev/null
check_match "texels" cpu_texels.png gl_texels.png
x "$viewer" -q texels.toml --frames 1 --light-step 0 --screenshot vt0.png >/dev/null
check_match "viewer texel frame vs prt render" cpu_texels.png vt0.png

# Clear messages for bad input.
printf '[mesh]\nfile = "nowhere.off"\n[lighting]\nconstant = [1,1,1]\n' >bad.toml
if x "$viewer" -q bad.toml --frames 1 2>err.txt; then echo "FAIL: bad scene accepted"; exit 1; fi
grep -q "nowhere.off" err.txt || { echo "FAIL: unclear message: $(cat err.txt)"; exit 1; }
echo "bad scene: $(cat err.txt)"
sed 's/^\[transport\]/[output]\nbake = "fresh.h5"\n[transport]/' exact.toml >fresh.toml
x "$viewer" -q fresh.toml --frames 1 --screenshot fresh.png 2>err.txt >/dev/null
grep -q "baking it" err.txt && [ -s fresh.h5 ] || { echo "FAIL: missing bake not baked"; exit 1; }
if env -u DISPLAY "$prt" -q render exact.toml -r opengl -o nodisplay.png 2>err.txt; then
  echo "FAIL: no display accepted"; exit 1
fi
grep -q "xvfb-run" err.txt || { echo "FAIL: unclear no-display message: $(cat err.txt)"; exit 1; }
echo "no display: $(cat err.txt)"
echo "PASS"
