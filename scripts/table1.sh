#!/usr/bin/env bash
# Sloan et al. 2003, Table 1, reproduced on CGAL meshes: for each mesh and
# row (diffuse 1x100; gloss-iso 16x25; gloss-anis 24x25; subsurface +
# gloss-iso 25x25), the exact transfer is baked once, then compressed by
# static and by iterative CPCA (256 clusters, n' 6 or 8). Each row gets SE
# (squared error summed over vertices), encode time and the frame rate of the
# OpenGL path (prt-view, scripted frames; xvfb-run and Mesa when there is no
# display). Writes docs/table1.md beside the paper's figures; logs and bakes
# in out/table1/.
#
#   scripts/table1.sh                 # bunny, armadillo, Chinese dragon; ~35 min on 2 cores
#   scripts/table1.sh bunny00         # one mesh (a name in data/meshes, no .off)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="${PRT_BIN:-$root/build/bin}"  # PRT_BIN: another build's bin folder
out="$root/out/table1"
mkdir -p "$out"
[ -x "$bin/prt" ] && [ -x "$bin/prt-view" ] || bash "$root/scripts/build.sh" >/dev/null
gl=()
[ -n "${DISPLAY:-}" ] || gl=(xvfb-run -a)
meshes=("$@")
[ ${#meshes[@]} -gt 0 ] || meshes=(bunny00 armadillo ChineseDragon-10kv)
frames=40

# row name | transfer | n' | [material] keys | [basis] order | [exit] keys
rows=(
  "diffuse|1x100|8|brdf = \"lambert\"|10|"
  "gloss-iso|16x25|6|brdf = \"phong\"\ndiffuse = 0.4\nspecular = 0.6\nexponent = 12|5|plugin = \"hsh\"\norder = 4"
  "gloss-anis|24x25|8|brdf = \"ward\"\ndiffuse = 0.4\nspecular = 0.6\nanisotropic_roughness = [0.1, 0.3]|5|plugin = \"hsh\"\norder = 5\nreduced = true"
  "subsurf+gloss-iso|25x25|8|brdf = \"phong\"\ndiffuse = 0.4\nspecular = 0.6\nexponent = 12\nsubsurface = true\nmm_per_unit = MM_PER_UNIT|5|plugin = \"hsh\"\norder = 5"
)

write_scene() {  # mesh, row name, material, order, exit, n', method, bake file -> scene file
  local file="$out/$1.$2.$7.toml"
  {
    printf '[mesh]\nfile = "%s"\n\n' "$root/data/meshes/$1.off"
    printf '[material]\nalbedo = [0.85, 0.8, 0.75]\n%b\n\n' "$3"
    printf '[transport]\ndirections = "fibonacci"\nrays = 1024\n\n'
    printf '[basis]\nplugin = "sh"\norder = %s\n\n' "$4"
    [ -z "$5" ] || printf '[exit]\n%b\n\n' "$5"
    if [ "$7" = none ]; then printf '[compressor]\nplugin = "none"\n\n'; else
      printf '[compressor]\nplugin = "cpca"\nmethod = "%s"\nclusters = 256\ncomponents = %s\n\n' "$7" "$6"; fi
    printf '[lighting]\nenvironment = "%s"\nrotation = 90.0\n\n' "$root/data/hdri/courtyard.exr"
    printf '[camera]\nwidth = 640\nheight = 480\nfov = 35\n\n'
    printf '[output]\nbake = "%s"\n' "$8"
  } >"$file"
  echo "$file"
}

results="$out/results.tsv"
: >"$results"
for mesh in "${meshes[@]}"; do
  [ -f "$root/data/meshes/$mesh.off" ] || { echo "table1: no mesh data/meshes/$mesh.off" >&2; exit 1; }
  vertices=$(sed -n '2p' "$root/data/meshes/$mesh.off" | awk '{ print $1 }')
  # Subsurface: every mesh 100 mm across (the dipole's point sum needs vertex
  # spacing near the mean free path, a few mm for marble).
  mm=$(/usr/bin/python3 -c '
import sys
words = open(sys.argv[1]).read().split()
n = int(words[1]); xyz = [float(w) for w in words[4:4 + 3 * n]]
extent = max(max(xyz[a::3]) - min(xyz[a::3]) for a in range(3))
print(100.0 / extent)' "$root/data/meshes/$mesh.off")
  for row in "${rows[@]}"; do
    IFS='|' read -r name transfer components material order exit <<<"$row"
    material=${material//MM_PER_UNIT/$mm}
    exact="$out/$mesh.$name.exact.h5"
    scene=$(write_scene "$mesh" "$name" "$material" "$order" "$exit" "$components" none "$exact")
    echo "table1: $mesh $name $transfer: bake" >&2
    "$bin/prt" -q bake "$scene" --force -o "$exact" >"$out/$mesh.$name.bake.log" 2>&1
    # Exact transfer once; each method compresses it (prt compress reports SE and time).
    line="$mesh|$vertices|$name|$transfer|$components"
    for method in static iterative; do
      bake="$out/$mesh.$name.$method.h5"
      scene=$(write_scene "$mesh" "$name" "$material" "$order" "$exit" "$components" "$method" "$bake")
      echo "table1: $mesh $name: $method CPCA" >&2
      json=$("$bin/prt" -q compress "$exact" -c cpca -p clusters=256 -p components="$components" \
        -p method="$method" -o "$bake" --force --json)
      se=$(/usr/bin/python3 -c 'import json,sys; print(json.loads(sys.argv[1])["squared_error"])' "$json")
      seconds=$(/usr/bin/python3 -c 'import json,sys; print(json.loads(sys.argv[1])["encode_seconds"])' "$json")
      # Frame rate: median frame time of scripted frames (the light turning).
      "${gl[@]}" "$bin/prt-view" "$scene" --frames "$frames" --no-panel \
        --screenshot "$out/$mesh.$name.$method.png" >"$out/$mesh.$name.$method.view.log" 2>&1
      ms=$(sed -n 's/.*| frame \([0-9.]*\) ms.*/\1/p' "$out/$mesh.$name.$method.view.log" | tail -n +5 |
        sort -g | awk '{ a[NR] = $1 } END { print (NR ? a[int((NR + 1) / 2)] : "nan") }')
      line="$line|$se|$seconds|$ms"
      opengl=$(sed -n 's/^OpenGL: //p' "$out/$mesh.$name.$method.view.log" | head -1)
    done
    line="$line|$opengl"
    echo "$line" >>"$results"
  done
done
/usr/bin/python3 "$root/scripts/table1_report.py" "$results" "$root/docs/table1.md"
echo "table1: wrote docs/table1.md" >&2
