#!/usr/bin/env bash
# prt-mpi on a real CGAL mesh equals prt bake byte for byte, for 1 (the
# example scene with reclassification) to 4 (more ranks than cores: --oversubscribe): iterative CPCA with
# superclusters and an eigentransport basis fitted by the ranks together
# (also killed after the fit and resumed on other ranks; VQ killed inside
# LBG and iterative CPCA between passes, each resumed); on 3 ranks static
# CPCA from a hyper-box start, PCA, glossy VQ and a sparse Haar
# approximation with a rank that holds no vertex; transfers that couple
# vertices (diffuse bounces on 3 ranks; glossy bounces with subsurface light
# on 2), and bounces killed on 3 ranks and resumed on 2. A
# compressor that cannot run distributed is refused on every rank with one
# message, and a bad scene ends every rank (no hang).
#   mpi.sh <prt> <prt-mpi> <source dir>
set -euo pipefail
prt="$(realpath "$1")"
prt_mpi="$(realpath "$2")"
src="$(realpath "$3")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
[ -f "$src/data/meshes/bunny00.off" ] || { echo "FAIL: run scripts/setup.sh" >&2; exit 1; }
# Ranks yield while they wait (more ranks than cores here).
mpirun=(mpirun --oversubscribe --mca mpi_yield_when_idle 1)
[ "$(id -u)" -ne 0 ] || mpirun+=(--allow-run-as-root)

scene() {  # name, mesh, [basis] lines, [compressor] lines, [material] lines
  cat >"$work/$1.toml" <<SCENE
[mesh]
file = "$src/data/meshes/$2"
[material]
${5:-albedo = 0.8}
[transport]
rays = 256
[basis]
$3
[exit]
plugin = "hsh"
order = 3
[compressor]
$4
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE
}
scene iterative bunny00.off $'plugin = "sh"\norder = 8' \
  $'plugin = "cpca"\nmethod = "iterative"\nclusters = 64\ncomponents = 4\nreclassify = true\nsupercluster = "greedy"'
scene static armadillo.off $'plugin = "sh"\norder = 6' \
  $'plugin = "cpca"\nclusters = 32\ncomponents = 6\ninit = "hyperbox"\nreclassify = true\nsupercluster = "chen"'
scene pca refined_elephant.off $'plugin = "sh"\norder = 6' $'plugin = "pca"\ncomponents = 8'
scene exact ChineseDragon-10kv.off $'plugin = "sh"\norder = 4' $'plugin = "none"'
scene glossy_vq armadillo.off $'plugin = "sh"\norder = 4' $'plugin = "vq"\nclusters = 48' \
  $'brdf = "phong"\nspecular = 0.5\nexponent = 8'

# Haar's k largest (a sparse form, no compressor) on 10,000 vertices: two
# segments for three ranks, so rank 0 holds none and still writes the file.
cat >"$work/haar_sparse.toml" <<SCENE
[mesh]
file = "$src/data/meshes/ChineseDragon-10kv.off"
[transport]
directions = "cubemap"
rays = 384
[basis]
plugin = "haar"
resolution = 8
k = 24
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE

# Eigentransport fitted by the ranks together (a distributed randomized
# SVD over their shards of the visibility): the same basis, bit for bit.
cat >"$work/eigen.toml" <<SCENE
[mesh]
file = "$src/data/meshes/bunny00.off"
[transport]
directions = "cubemap"
rays = 384
[basis]
plugin = "eigen"
d = 16
[compressor]
plugin = "cpca"
clusters = 32
components = 4
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE

for name in iterative eigen static pca exact glossy_vq haar_sparse; do
  "$prt" -q bake "$work/$name.toml" -o "$work/$name.serial.h5" >/dev/null
  ranks="1 2 3 4"
  [ "$name" = iterative ] && ranks="2 3 4"  # one rank: scenes/bunny_cpca.toml below
  [ "$name" = iterative ] || [ "$name" = eigen ] || ranks="3"
  for np in $ranks; do
    "${mpirun[@]}" -np "$np" "$prt_mpi" -q bake "$work/$name.toml" -o "$work/$name.$np.h5" \
      --slab-vertices 4096 >/dev/null  # many slabs: the ranks share them out
    if ! cmp -s "$work/$name.serial.h5" "$work/$name.$np.h5"; then
      echo "FAIL: $name on $np ranks differs from prt bake"
      h5diff "$work/$name.serial.h5" "$work/$name.$np.h5" | head -20 || true
      exit 1
    fi
    [ ! -e "$work/.$name.$np.h5.checkpoint" ] || { echo "FAIL: checkpoint left behind"; exit 1; }
  done
  echo "$name: prt-mpi on $ranks ranks = prt bake, byte for byte"
done

# Messages in rounds (over MPI's 2 GB limit on a real mesh; forced here by
# a 64 KB limit: the compressed rows gathered on rank 0 take ~11 rounds).
"${mpirun[@]}" -x PRT_MPI_MAX_MESSAGE=65536 -np 3 "$prt_mpi" -q bake "$work/iterative.toml" \
  -o "$work/iterative.rounds.h5" --slab-vertices 4096 >/dev/null
cmp -s "$work/iterative.serial.h5" "$work/iterative.rounds.h5" ||
  { echo "FAIL: messages in rounds change the file"; exit 1; }
echo "messages in 64 KB rounds: prt-mpi on 3 ranks = prt bake, byte for byte"

# A budget below each rank's rows: every rank keeps its shard in a file of
# its own and compresses in passes; rank 0 writes its rows from that file.
out=$("${mpirun[@]}" -np 3 "$prt_mpi" bake "$work/iterative.toml" -o "$work/iterative.disk.h5" \
        --slab-vertices 4096 --memory 1M 2>/dev/null)
grep -q "this rank's rows of the transfer .* are kept in" <<<"$out" ||
  { echo "FAIL: --memory 1M kept no rows on disk: $out"; exit 1; }
cmp -s "$work/iterative.serial.h5" "$work/iterative.disk.h5" ||
  { echo "FAIL: out-of-core shards change the file"; exit 1; }
out=$("${mpirun[@]}" -np 3 "$prt_mpi" bake "$work/eigen.toml" -o "$work/eigen.disk.h5" \
        --memory 1M 2>/dev/null)
grep -q "this rank's rows of the transfer .* are kept in" <<<"$out" ||
  { echo "FAIL: --memory 1M kept no fitted rows on disk: $out"; exit 1; }
cmp -s "$work/eigen.serial.h5" "$work/eigen.disk.h5" ||
  { echo "FAIL: out-of-core fitted shards change the file"; exit 1; }
echo "shards kept on disk (--memory 1M): prt-mpi on 3 ranks (CPCA, eigen) = prt bake, byte for byte"

# Killed (every rank) after the fit, while compressing, and rerun on another
# number of ranks: the kept basis is loaded, not fitted again (the fit is
# the same bits on any number of ranks), and the file is the same.
sed -e 's/plugin = "cpca"/plugin = "vq"/' -e 's/^components = 4$/iterations = 400\ntolerance = 0.0/' \
  "$work/eigen.toml" >"$work/eigen_kill.toml"
"$prt" -q bake "$work/eigen_kill.toml" -o "$work/eigen_kill.serial.h5" >/dev/null
# kill_when <scene> <output> <part> <flags...>: a 3-rank bake of the scene,
# every rank killed as soon as the part is kept in its checkpoint.
kill_when() {
  setsid "${mpirun[@]}" -np 3 "$prt_mpi" -q bake "$work/$1.toml" -o "$work/$2.h5" "${@:4}" \
    >/dev/null 2>&1 &
  pid=$!
  for _ in $(seq 3000); do  # at most a minute, polled often: the window before the end is short
    [ -e "$work/.$2.h5.checkpoint/$3" ] && break
    sleep 0.02
  done
  kill -9 -- "-$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  pkill -9 -f "$work/$2.h5" 2>/dev/null || true
  [ -e "$work/.$2.h5.checkpoint/$3" ] || { echo "FAIL ($2): no $3 kept"; exit 1; }
  [ ! -e "$work/$2.h5" ] || { echo "FAIL ($2): the killed bake finished first"; exit 1; }
}
kill_when eigen_kill eigen_kill fitted-basis
out=$("${mpirun[@]}" -np 2 "$prt_mpi" bake "$work/eigen_kill.toml" -o "$work/eigen_kill.h5" 2>&1)
grep -q "resuming: the fitted basis kept" <<<"$out" || { echo "FAIL: did not resume: $out"; exit 1; }
grep -q "fit basis" <<<"$out" && { echo "FAIL: fitted again after resuming: $out"; exit 1; }
cmp -s "$work/eigen_kill.serial.h5" "$work/eigen_kill.h5" ||
  { echo "FAIL: the resumed distributed fit changes the file"; exit 1; }
echo "killed after the distributed fit on 3 ranks, resumed on 2: the file is identical"

# Killed (every rank) inside LBG and rerun on as many ranks: each rank kept
# its labels and rank 0 the means, so LBG resumes where it was, to the file
# of prt bake.
sed -e 's/plugin = "cpca"/plugin = "vq"\niterations = 400\ntolerance = 0.0/' \
  -e 's/^clusters = 64$/clusters = 128/' -e '/^method\|^components\|^supercluster/d' \
  "$work/iterative.toml" >"$work/vq_kill.toml"
"$prt" -q bake "$work/vq_kill.toml" -o "$work/vq_kill.serial.h5" >/dev/null
kill_when vq_kill vq_kill lbg.state --checkpoint-seconds 0
out=$("${mpirun[@]}" -np 3 "$prt_mpi" bake "$work/vq_kill.toml" -o "$work/vq_kill.h5" 2>&1)
grep -q "resuming: LBG at iteration" <<<"$out" || { echo "FAIL: LBG did not resume: $out"; exit 1; }
cmp -s "$work/vq_kill.serial.h5" "$work/vq_kill.h5" ||
  { echo "FAIL: the resumed distributed LBG changes the file"; exit 1; }
echo "killed inside distributed LBG on 3 ranks, resumed: $(grep -o 'resuming: LBG at iteration [0-9]*' <<<"$out"); the file is identical"
# The same between passes of iterative CPCA (each rank's labels and the
# labels its models were fitted to; rank 0 the models).
kill_when iterative cpca_kill cpca.state --slab-vertices 4096 --checkpoint-seconds 0
out=$("${mpirun[@]}" -np 3 "$prt_mpi" bake "$work/iterative.toml" -o "$work/cpca_kill.h5" \
        --slab-vertices 4096 2>&1)
grep -q "resuming: CPCA at" <<<"$out" || { echo "FAIL: CPCA did not resume: $out"; exit 1; }
cmp -s "$work/iterative.serial.h5" "$work/cpca_kill.h5" ||
  { echo "FAIL: the resumed distributed CPCA changes the file"; exit 1; }
echo "killed between distributed CPCA passes on 3 ranks, resumed: $(grep -o 'resuming: CPCA at [^,]*, pass [0-9]*' <<<"$out"); the file is identical"

# The example scene with reclassification and superclusters, as issue 42
# states it: 1, 2 and 3 ranks give prt bake's file.
"$prt" -q bake "$src/scenes/bunny_cpca.toml" -o "$work/bunny_cpca.serial.h5" >/dev/null
for np in 1 2 3; do
  "${mpirun[@]}" -np "$np" "$prt_mpi" -q bake "$src/scenes/bunny_cpca.toml" \
    -o "$work/bunny_cpca.$np.h5" >/dev/null
  cmp -s "$work/bunny_cpca.serial.h5" "$work/bunny_cpca.$np.h5" ||
    { echo "FAIL: scenes/bunny_cpca.toml on $np ranks differs from prt bake"; exit 1; }
done
grep -q 'reclassified_vertices' < <("$prt" info "$work/bunny_cpca.2.h5") ||
  { echo "FAIL: scenes/bunny_cpca.toml was not reclassified"; exit 1; }
echo "scenes/bunny_cpca.toml (reclassify, greedy superclusters): prt-mpi on 1, 2 and 3 ranks = prt bake"

# Transfers that couple vertices (issue 42): the ranks share each stage's
# slabs (trace, bounces, subsurface term, glossy matrices) through the
# checkpoint and each reads the others', so every rank holds the whole
# transfer as prt bake computes it. Diffuse bounces compressed by PCA;
# glossy bounces with subsurface light, exact.
sed -e 's/^rays = 256/rays = 256\nbounces = 2/' "$work/pca.toml" |
  sed -e 's|refined_elephant.off|ChineseDragon-10kv.off|' >"$work/coupled_bounces.toml"
scene coupled_glossy ChineseDragon-10kv.off $'plugin = "sh"\norder = 4' $'plugin = "none"' \
  $'albedo = [0.9, 0.88, 0.85]\nbrdf = "phong"\ndiffuse = 0.2\nspecular = 0.3\nexponent = 6\nsubsurface = true\nsigma_a = 0.0041\nsigma_s = 2.62\neta = 1.5\nmm_per_unit = 100'
sed -i -e 's/^rays = 256/rays = 256\nbounces = 1/' "$work/coupled_glossy.toml"
for name in coupled_bounces coupled_glossy; do
  np=3
  [ "$name" = coupled_bounces ] || np=2
  "$prt" -q bake "$work/$name.toml" -o "$work/$name.serial.h5" >/dev/null
  "${mpirun[@]}" -np "$np" "$prt_mpi" -q bake "$work/$name.toml" -o "$work/$name.$np.h5" \
    --slab-vertices 2048 >/dev/null
  if ! cmp -s "$work/$name.serial.h5" "$work/$name.$np.h5"; then
    echo "FAIL: $name on $np ranks differs from prt bake"
    h5diff "$work/$name.serial.h5" "$work/$name.$np.h5" | head -20 || true
    exit 1
  fi
  [ ! -e "$work/.$name.$np.h5.checkpoint" ] || { echo "FAIL: checkpoint left behind"; exit 1; }
  echo "$name: prt-mpi on $np ranks = prt bake, byte for byte"
done
# $work/NAME.toml on 3 ranks, in slabs of 256 rows, against prt bake: byte for byte.
three_ranks_as_bake() {
  "$prt" -q bake "$work/$1.toml" -o "$work/$1.serial.h5" >/dev/null
  "${mpirun[@]}" -np 3 "$prt_mpi" -q bake "$work/$1.toml" -o "$work/$1.3.h5" \
    --slab-vertices 256 >/dev/null
  cmp -s "$work/$1.serial.h5" "$work/$1.3.h5" ||
    { echo "FAIL: $1 on 3 ranks differ from prt bake"; exit 1; }
  echo "$1: prt-mpi on 3 ranks = prt bake, byte for byte"
}
# Probes (docs/receivers.md): the ranks take the grid's slabs as they come
# free and compress their shards with CPCA; the file is prt bake's.
cat >"$work/probes.toml" <<SCENE
[mesh]
generate = "room"
detail = 1
[[mesh.add]]
file = "$src/data/meshes/elephant.off"
position = [0.5, 0, 0]
size = 0.7
[receivers]
kind = "probes"
spacing = 0.45
[transport]
rays = 256
[basis]
plugin = "sh"
order = 6
[exit]
plugin = "sh"
order = 3
[compressor]
plugin = "cpca"
clusters = 16
components = 4
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE
three_ranks_as_bake probes
# Texels (docs/receivers.md): slabs of texels, traced against the mesh,
# CPCA over the ranks' shards; the file is prt bake's.
cat >"$work/texels.toml" <<SCENE
[mesh]
file = "$src/data/meshes/nefertiti.off"
[receivers]
kind = "texels"
resolution = 48
[transport]
rays = 256
[basis]
plugin = "sh"
order = 6
[compressor]
plugin = "cpca"
clusters = 16
components = 4
[lighting]
environment = "$src/data/hdri/courtyard.exr"
SCENE
three_ranks_as_bake texels
# Killed between bounces on 3 ranks, resumed on 2: the same file.
# (The bunny, three bounces: bounce 1's state lives while bounce 2 runs.)
sed -e 's/^bounces = 2/bounces = 3/' -e 's|ChineseDragon-10kv.off|bunny00.off|' \
  -e 's/^plugin = "pca"/plugin = "none"/' -e '/^components = 8$/d' "$work/coupled_bounces.toml" \
  >"$work/coupled_kill.toml"
"$prt" -q bake "$work/coupled_kill.toml" -o "$work/coupled_kill.serial.h5" >/dev/null
kill_when coupled_kill coupled_kill bounce-1 --slab-vertices 4096
out=$("${mpirun[@]}" -np 2 "$prt_mpi" bake "$work/coupled_kill.toml" -o "$work/coupled_kill.h5" \
  --slab-vertices 4096 2>&1)
grep -q 'resuming: inter-reflection after bounce [12] of 3' <<<"$out" ||
  { echo "FAIL: the killed bounces were not resumed: $out"; exit 1; }
cmp -s "$work/coupled_kill.serial.h5" "$work/coupled_kill.h5" ||
  { echo "FAIL: the resumed distributed bounces change the file"; exit 1; }
echo "killed after a distributed bounce on 3 ranks, resumed on 2: the file is identical"

# Refusals end every rank with one clear message and no output.
scene coherent bunny00.off $'plugin = "sh"\norder = 4' \
  $'plugin = "vq"\nclusters = 8\nalpha = 0.5'
if out=$(timeout 120 "${mpirun[@]}" -np 2 "$prt_mpi" -q bake "$work/coherent.toml" \
           -o "$work/coherent.h5" 2>&1); then
  echo "FAIL: geometry-coherent clustering accepted under prt-mpi"; exit 1
fi
grep -q 'cannot run distributed: it clusters by geometry' <<<"$out" || { echo "FAIL: $out"; exit 1; }
[ ! -e "$work/coherent.h5" ] || { echo "FAIL: output written"; exit 1; }
sed -e 's/^\[compressor\]/[material]\nbrdf = "phong"\nspecular = 0.5\n[exit]\nplugin = "hsh"\norder = 3\n[compressor]/' \
  "$work/eigen.toml" >"$work/eigen_glossy.toml"
if out=$(timeout 120 "${mpirun[@]}" -np 2 "$prt_mpi" -q bake "$work/eigen_glossy.toml" \
           -o "$work/eigen_glossy.h5" 2>&1); then
  echo "FAIL: a glossy fitted bake accepted under prt-mpi"; exit 1
fi
grep -q 'fits a basis for diffuse transfer only' <<<"$out" || { echo "FAIL: $out"; exit 1; }
[ ! -e "$work/eigen_glossy.h5" ] || { echo "FAIL: output written"; exit 1; }
printf '[mesh]\nfile = "missing.off"\n' >"$work/bad.toml"
if out=$(timeout 120 "${mpirun[@]}" -np 3 "$prt_mpi" -q bake "$work/bad.toml" -o "$work/bad.h5" 2>&1); then
  echo "FAIL: a missing mesh accepted"; exit 1
fi
grep -q 'missing.off' <<<"$out" || { echo "FAIL: $out"; exit 1; }
if out=$(timeout 120 "${mpirun[@]}" -x PRT_MPI_MAX_MESSAGE=12 -np 2 "$prt_mpi" -q bake \
           "$work/iterative.toml" -o "$work/bad_limit.h5" 2>&1); then
  echo "FAIL: a 12-byte message limit accepted"; exit 1
fi
grep -q 'PRT_MPI_MAX_MESSAGE="12"' <<<"$out" || { echo "FAIL: $out"; exit 1; }
[ ! -e "$work/bad_limit.h5" ] || { echo "FAIL: output written"; exit 1; }
echo "refusals: one message, non-zero exit, no output"
