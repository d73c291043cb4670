#!/usr/bin/env bash
# A bake SIGKILLed twice at random moments and rerun with the same command
# resumes from its checkpoint and writes a file identical, byte for byte, to
# an uninterrupted bake; no partial file is ever left under the final name;
# the checkpoint is removed once the file is in place; a changed scene
# refuses the stale checkpoint with a message, and --restart discards it.
#   checkpoint.sh <prt> <source dir>
set -euo pipefail
prt="$(realpath "$1")"
src="$(realpath "$2")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
[ -f "$src/data/meshes/bunny00.off" ] || { echo "FAIL: run scripts/setup.sh" >&2; exit 1; }

# A subdivided bunny (150,818 vertices) in slabs of 8,192: 19 slabs.
"$prt" -q subdivide "$src/data/meshes/bunny00.off" -o "$work/bunny.ply" -n 150818 >/dev/null
cat >"$work/scene.toml" <<SCENE
[mesh]
file = "$work/bunny.ply"
[transport]
rays = 512
[basis]
plugin = "sh"
order = 6
[compressor]
plugin = "cpca"
clusters = 64
components = 4
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE
bake() { exec_bake "$@"; }
exec_bake() { "$prt" -q bake "$work/scene.toml" -o "$work/$1.h5" --slab-vertices 8192 "${@:2}"; }
# In the background prt itself must be the process killed (not a subshell).
bake_in_background() {
  "$prt" -q bake "$work/scene.toml" -o "$work/$1.h5" --slab-vertices 8192 >/dev/null 2>&1 &
  pid=$!
}

start=$(date +%s.%N)
bake reference >/dev/null
seconds=$(echo "$(date +%s.%N) - $start" | bc)
echo "uninterrupted bake: ${seconds} s"

RANDOM=$$  # a different pair of moments each run; printed for a rerun
finished=no
for attempt in 1 2; do
  percent=$((25 + RANDOM % 60))  # drawn here: a subshell would repeat the draw
  delay=$(echo "scale=2; $seconds * $percent / 100" | bc)
  bake_in_background resumed
  sleep "$delay"
  kill -9 "$pid" 2>/dev/null || true
  status=0
  wait "$pid" 2>/dev/null || status=$?
  if [ "$status" -eq 0 ]; then  # what was left took less than the delay: it resumed
    echo "run $attempt resumed and finished before its kill at ${delay} s"
    finished=yes
    break
  fi
  if [ -e "$work/resumed.h5" ]; then  # killed between the rename and the exit: whole, or a failure
    cmp -s "$work/reference.h5" "$work/resumed.h5" ||
      { echo "FAIL: a partial file under the final name"; exit 1; }
    echo "run $attempt resumed and wrote the whole file before its kill at ${delay} s (the rerun below clears its checkpoint)"
    break
  fi
  kept=$(ls "$work/.resumed.h5.checkpoint" 2>/dev/null | grep -c '^transfer\.' || true)
  echo "kill $attempt after ${delay} s: $kept slabs kept"
done
# A second process on the same checkpoint is refused while the first runs.
bake_in_background locked
sleep 0.3
if out=$(bake locked 2>&1); then echo "FAIL: two processes baked into one checkpoint"; exit 1; fi
grep -q 'another prt process is using this checkpoint' <<<"$out" || { echo "FAIL: $out"; exit 1; }
kill -9 "$pid"; wait "$pid" 2>/dev/null || true
out="run $attempt resumed and finished"
[ "$finished" = yes ] ||
  out=$("$prt" bake "$work/scene.toml" -o "$work/resumed.h5" --slab-vertices 8192 2>&1)
cmp "$work/reference.h5" "$work/resumed.h5" ||
  { echo "FAIL: the resumed bake differs from the uninterrupted one"; exit 1; }
[ ! -e "$work/.resumed.h5.checkpoint" ] || { echo "FAIL: checkpoint left after success"; exit 1; }
echo "resumed bake identical to the uninterrupted one ($(grep -o 'resuming: [0-9]* of [0-9]*\|run [0-9] resumed and finished' <<<"$out" || echo 'nothing kept'))"

# A stale checkpoint (the scene changed) is refused, then discarded on request.
bake_in_background stale
sleep "$(echo "scale=2; $seconds / 3" | bc)"; kill -9 "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true
if [ -d "$work/.stale.h5.checkpoint" ]; then
  sed -i 's/^order = 6$/order = 5/' "$work/scene.toml"
  if out=$(bake stale 2>&1); then echo "FAIL: a stale checkpoint was used"; exit 1; fi
  grep -q 'a checkpoint of a different run' <<<"$out" || { echo "FAIL: $out"; exit 1; }
  bake stale --restart >/dev/null
  echo "stale checkpoint refused, --restart discards it"
fi

# Killed while compressing: LBG and the CPCA passes keep their state (here
# before every pass), and the rerun continues from it to the same file.
kill_inside() {  # kill_inside <name> <part to wait for> <message> <compressor lines>
  cat >"$work/$1.toml" <<SCENE
[mesh]
file = "$work/bunny.ply"
[transport]
rays = 64
[basis]
plugin = "sh"
order = 10
[compressor]
$4
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE
  "$prt" -q bake "$work/$1.toml" -o "$work/$1-reference.h5" >/dev/null
  "$prt" -q bake "$work/$1.toml" -o "$work/$1.h5" --checkpoint-seconds 0 >/dev/null 2>&1 &
  pid=$!
  for _ in $(seq 600); do  # until a state is kept (at most a minute)
    [ -e "$work/.$1.h5.checkpoint/$2" ] && break
    sleep 0.1
  done
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  [ -e "$work/.$1.h5.checkpoint/$2" ] || { echo "FAIL ($1): no $2 kept"; exit 1; }
  [ ! -e "$work/$1.h5" ] || { echo "FAIL ($1): the killed bake finished first"; exit 1; }
  out=$("$prt" bake "$work/$1.toml" -o "$work/$1.h5" 2>&1)
  grep -q "$3" <<<"$out" || { echo "FAIL ($1): did not resume: $out"; exit 1; }
  cmp "$work/$1-reference.h5" "$work/$1.h5" ||
    { echo "FAIL ($1): the bake resumed inside compression differs"; exit 1; }
  echo "killed inside $1: $(grep -o "$3[^,]*" <<<"$out"); the file is identical"
}
kill_inside lbg lbg.state 'resuming: LBG at iteration' \
  $'plugin = "vq"\nclusters = 128\niterations = 30\ntolerance = 0.0'
kill_inside iterative cpca.state 'resuming: CPCA at component' \
  $'plugin = "cpca"\nmethod = "iterative"\nclusters = 64\ncomponents = 2\ntolerance = 0.0'
kill_inside adaptive cpca.state 'resuming: CPCA at adaptive pass' \
  $'plugin = "cpca"\nmethod = "adaptive"\nclusters = 64\ncomponents = 1\niterations_per_component = 1\nadaptive_iterations = 6'

# A fitted basis (eigentransport): its visibility bits are traced in slabs
# and kept, and the fit keeps its state after each power iteration. Killed
# while tracing, then inside the fit, the rerun loads both and writes the
# file of an uninterrupted bake.
cat >"$work/eigen.toml" <<SCENE
[mesh]
file = "$work/bunny.ply"
[transport]
directions = "cubemap"
rays = 1536
[basis]
plugin = "eigen"
d = 24
power_iterations = 8
[compressor]
plugin = "pca"
components = 4
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE
"$prt" -q bake "$work/eigen.toml" -o "$work/eigen-reference.h5" >/dev/null
slab=16384
# kill_at <scene> <part name pattern>: a bake killed once a part matching it
# is kept (a bounce's slabs last only while it runs: watched closely, and the
# part may be gone by the time the kill lands).
kill_at() {
  "$prt" -q bake "$work/$1.toml" -o "$work/$1.h5" --slab-vertices "$slab" >/dev/null 2>&1 &
  pid=$!
  seen=no
  for _ in $(seq 3000); do  # at most a minute
    if ls "$work/.$1.h5.checkpoint" 2>/dev/null | grep -q "$2"; then seen=yes; break; fi
    sleep 0.02
  done
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  [ "$seen" = yes ] || { echo "FAIL ($1): no $2 kept"; exit 1; }
  [ ! -e "$work/$1.h5" ] || { echo "FAIL ($1): the killed bake finished first"; exit 1; }
}
resume() {  # resume <scene> <what the rerun must say>...: the rerun's file equals the reference
  out=$("$prt" bake "$work/$1.toml" -o "$work/$1.h5" --slab-vertices "$slab" 2>&1)
  for said in "${@:2}"; do
    grep -q "$said" <<<"$out" || { echo "FAIL ($1): did not resume ($said): $out"; exit 1; }
  done
  cmp "$work/$1-reference.h5" "$work/$1.h5" ||
    { echo "FAIL ($1): the bake resumed inside its stages differs"; exit 1; }
}
kill_at eigen '^bits\.rows'
kill_at eigen '^eigen\.iteration$'
resume eigen 'slabs of visibility bits kept' 'resuming: the eigentransport fit after power iteration'
echo "killed while tracing and inside the eigentransport fit: $(grep -o 'resuming: the eigentransport fit after power iteration [0-9]* of [0-9]*' <<<"$out"); the file is identical"

# Stages that couple vertices: marble's three channel transfers, each with
# two bounces and subsurface light, on the 37,706-vertex bunny in 10 slabs. The trace is kept in slabs (rows and
# hits), each bounce and the scattering a slab at a time, each channel once
# done. Killed while tracing, inside channel 1's second bounce and inside
# channel 2's subsurface scattering, the rerun writes the same file.
cat >"$work/coupled.toml" <<SCENE
[mesh]
file = "$src/data/meshes/bunny00.off"
[material]
subsurface = true
preset = "marble"
[transport]
rays = 128
bounces = 2
[basis]
plugin = "sh"
order = 4
[compressor]
plugin = "pca"
components = 2
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE
"$prt" -q bake "$work/coupled.toml" -o "$work/coupled-reference.h5" >/dev/null
slab=4096
kill_at coupled '^trace-rays\.rows'
kill_at coupled '^channel-1\.bounce-2\.rows'
kill_at coupled '^channel-2\.subsurface\.rows'
resume coupled 'slabs of the trace kept' 'resuming: channel transfer 1 of 3 kept' \
  'slabs of subsurface scattering kept'
echo "killed while tracing, inside a bounce and inside subsurface scattering: the file is identical"
