#!/usr/bin/env bash
# A basis that is not orthonormal relights right (issue 39's acceptance): the
# cosine-lobe example (examples/cosine_lobe_basis, 25 lobes ((1 + w.d)/2)^4)
# is baked on the bunny under the courtyard map as it is, and again
# orthonormalised (G^-1/2 B, the same span, which claims orthonormality);
# the vertex radiance toward the scene's camera must agree within 1e-3
# relative RMS. Before the metric was applied the raw lobes gave 146.8.
# The same for glossy transfer (Phong, hsh exit basis): the light side of
# the transfer matrices must hold least-squares coefficients too.
#   basis_metric.sh <prt> <folder of libprt-basis-lobes.so> <source dir>
set -euo pipefail
prt="$(realpath "$1")"
plugins="$(realpath "$2")"
src="$(realpath "$3")"
build="$(dirname "$(dirname "$prt")")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
export PYTHONPATH="$(echo "$build"/lib/python3*/dist-packages)"
export PRT_PLUGIN_PATH="$plugins"
for variant in false true; do
  for kind in diffuse glossy; do
  material='brdf = "lambert"'
  [ "$kind" = diffuse ] || material=$'brdf = "phong"\ndiffuse = 0.4\nspecular = 0.6\nexponent = 12\n[exit]\nplugin = "hsh"\norder = 3'
  name="lobes_${kind}_$variant"
  cat >"$work/$name.toml" <<EOT
[mesh]
file = "$src/data/meshes/bunny00.off"
[material]
$material
[lighting]
environment = "$src/data/hdri/courtyard.exr"
[basis]
plugin = "lobes"
orthonormalise = $variant
[transport]
rays = 1024
[compressor]
plugin = "none"
[output]
bake = "$work/$name.h5"
image = "$work/$name.png"
EOT
  done
done
# The CLI bakes and renders the raw lobes without a word about the metric.
"$prt" -q bake "$work/lobes_diffuse_false.toml" >/dev/null
"$prt" -q render "$work/lobes_diffuse_false.toml" >/dev/null
[ -s "$work/lobes_diffuse_false.png" ] || { echo "FAIL: no image"; exit 1; }
# A bake travels alone: prt compress re-compresses it in the rendered metric
# of its bases (made from the bake's records) without its scene's mesh.
mkdir "$work/alone"
cp "$src/data/meshes/bunny00.off" "$work/alone/mesh.off"
sed "s|$src/data/meshes/bunny00.off|$work/alone/mesh.off|; s|$work/lobes_diffuse_false|$work/alone/bake|" \
  "$work/lobes_diffuse_false.toml" >"$work/alone/scene.toml"
"$prt" -q bake "$work/alone/scene.toml" >/dev/null
rm "$work/alone/mesh.off"
out=$("$prt" compress "$work/alone/bake.h5" -c pca -p components=4 -o "$work/alone/pca.h5")
grep -q "in the rendered metric" <<<"$out" ||
  { echo "FAIL: prt compress of a bake without its mesh: $out"; exit 1; }
echo "ok: a bake without its mesh re-compresses in the rendered metric"
/usr/bin/python3 - "$work" <<'PY'
import sys
import numpy as np
import prt

work = sys.argv[1]
failed = False
for kind in ("diffuse", "glossy"):
  radiance = {}
  for variant in ("false", "true"):
    scene = prt.Scene(f"{work}/lobes_{kind}_{variant}.toml")
    data = prt.bake(scene, progress=False)
    relighting = prt.Relighting(scene, data)
    light = relighting.light(scene.load_environment())
    radiance[variant] = np.asarray(relighting.relight(data.compressed, light,
                                                      scene.camera(data.mesh)))
  raw, ortho = radiance["false"], radiance["true"]
  scale = np.sqrt(np.mean(ortho ** 2))
  relative = np.sqrt(np.mean((raw - ortho) ** 2)) / scale
  print(f"{kind}: raw lobes against their orthonormalised span: relative RMS {relative:.2e} "
        f"(radiance RMS {scale:.4f}, {raw.shape[0]} vertices)")
  if not np.isfinite(relative) or relative > 1e-3:
    print(f"FAIL ({kind}): a basis that is not orthonormal relights differently from its span")
    failed = True
sys.exit(1 if failed else 0)
PY
