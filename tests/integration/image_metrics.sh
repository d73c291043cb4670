#!/usr/bin/env bash
# Images a paper can use, checked against independent implementations:
# PSNR and SSIM as prt computes them (`prt image-diff`, `prt render --compare`)
# against scikit-image on fixed images; the files `render --compare` writes
# (NAME.error.png with its colour bar, NAME.error.exr, NAME.truth.exr) read
# back by the OpenEXR library (prt.Environment.load) and by read_exr.py; the
# second --compare reuses the cached reference; an unknown extension is refused;
# --ground-truth's default name leaves the scene's render alone.
set -euo pipefail
prt="$1"
src="$2"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
export PRT_CACHE_DIR="$work/cache"

# 1. Fixed images: smooth shapes, and copies with noise, blur, a shift and a
#    dark contour (the artifact a good RMS hides); sizes down to SSIM's 11 x 11.
/usr/bin/python3 - "$work" <<'PY'
import sys
import numpy as np
from PIL import Image
work = sys.argv[1]
rng = np.random.default_rng(11)
for name, (h, w) in {"big": (61, 83), "small": (11, 11)}.items():
    y, x = np.mgrid[0:h, 0:w]
    base = np.stack([120 + 100 * np.sin(x / 7.0), 90 + 80 * np.cos(y / 5.0),
                     60 + 50 * np.sin((x + y) / 9.0)], axis=2)
    base[(x - w / 2) ** 2 + (y - h / 2) ** 2 < (min(h, w) / 3) ** 2] = [230, 200, 40]
    a = np.clip(base, 0, 255).astype(np.uint8)
    noisy = np.clip(base + rng.normal(0, 12, base.shape), 0, 255).astype(np.uint8)
    contour = a.copy()
    contour[h // 2, :] = 0
    shifted = np.roll(a, 2, axis=1)
    for tag, image in {"a": a, "noisy": noisy, "contour": contour, "shifted": shifted}.items():
        Image.fromarray(image).save(f"{work}/{name}_{tag}.png")
PY
for size in big small; do
  for other in a noisy contour shifted; do
    out=$("$prt" image-diff "$work/${size}_a.png" "$work/${size}_$other.png")
    /usr/bin/python3 - "$work/${size}_a.png" "$work/${size}_$other.png" "$out" <<'PY'
import math, re, sys
import numpy as np
from PIL import Image
from skimage.metrics import peak_signal_noise_ratio, structural_similarity
a = np.asarray(Image.open(sys.argv[1]).convert("RGB"))
b = np.asarray(Image.open(sys.argv[2]).convert("RGB"))
printed = sys.argv[3]
psnr = float(re.search(r"PSNR (\S+) dB", printed).group(1))
ssim = float(re.search(r"SSIM (\S+)", printed).group(1))
if (a == b).all():
    want_psnr = math.inf
else:
    want_psnr = peak_signal_noise_ratio(a, b, data_range=255)
want_ssim = structural_similarity(a, b, channel_axis=2, gaussian_weights=True, sigma=1.5,
                                  use_sample_covariance=False, data_range=255)
ok = (psnr == want_psnr or abs(psnr - want_psnr) < 1e-5) and abs(ssim - want_ssim) < 1e-7
print(f"{'ok  ' if ok else 'FAIL'} {sys.argv[2].split('/')[-1]}: PSNR {psnr} (skimage "
      f"{want_psnr:.6f}), SSIM {ssim} (skimage {want_ssim:.8f})")
sys.exit(0 if ok else 1)
PY
  done
done

# 2. A render compared twice: the files beside the image, EXR read back, the
#    reference reused the second time.
cat >"$work/box.toml" <<EOT
[mesh]
generate = "open-box"
detail = 2
[lighting]
environment = "$src/data/hdri/courtyard.exr"
[transport]
rays = 256
[basis]
plugin = "sh"
order = 4
[camera]
width = 96
height = 72
[ground_truth]
samples = 64
EOT
(cd "$work" && "$prt" -q bake box.toml -o box.h5 >/dev/null)
first=$(cd "$work" && "$prt" -q render box.toml -b box.h5 -o box.exr --compare)
second=$(cd "$work" && "$prt" -q render box.toml -b box.h5 -o box.exr --compare --force --no-budget)
grep -q "light truncation" <<<"$first" || { echo "FAIL: no error budget in: $first"; exit 1; }
grep -q "error budget" <<<"$second" && { echo "FAIL: --no-budget printed the budget"; exit 1; }
grep -q "noise floor" <<<"$first" || { echo "FAIL: no noise floor in: $first"; exit 1; }
grep -q "reused from the cache" <<<"$first" && { echo "FAIL: first run claims a cached reference"; exit 1; }
grep -q "reused from the cache" <<<"$second" || { echo "FAIL: second --compare traced again: $second"; exit 1; }
grep -q "PSNR" <<<"$second" && grep -q "SSIM" <<<"$second" || { echo "FAIL: no image metrics"; exit 1; }
for f in box.exr box.error.png box.error.exr box.truth.exr; do
  [ -s "$work/$f" ] || { echo "FAIL: --compare did not write $f"; exit 1; }
done
PYTHONPATH="$(dirname "$(dirname "$prt")")/lib/python3.11/dist-packages:$src/tests/integration" \
  /usr/bin/python3 - "$work" <<'PY'
import sys
import numpy as np
from PIL import Image
from read_exr import read_exr
work = sys.argv[1]
render, names = read_exr(f"{work}/box.exr")
truth, _ = read_exr(f"{work}/box.truth.exr")
error, _ = read_exr(f"{work}/box.error.exr")
checks = {
    "RGB float channels, 96 x 72": names == ["B", "G", "R"] and render.shape == (72, 96, 3),
    "finite, linear (not 8-bit) values": np.isfinite(render).all() and render.max() > 0
                                         and len(np.unique(render)) > 256,
    "the signed error is render - truth": np.allclose(error, render - truth, atol=1e-6),
    "the error has both signs": (error < 0).any() and (error > 0).any(),
}
try:
    import prt  # the OpenEXR library reads it back too
    env = prt.Environment.load(f"{work}/box.truth.exr")
    pixels = env.pixels
    checks["OpenEXR reads the same truth"] = np.allclose(pixels, truth[:, :, ::-1], rtol=1e-6)
except ImportError:
    print("note: the Python module is not built; OpenEXR read-back skipped")
heat = Image.open(f"{work}/box.error.png")
checks["the heat map has its colour bar"] = heat.size[0] > 96 and heat.size[1] == 72
for name, ok in checks.items():
    print(f"{'ok  ' if ok else 'FAIL'} {name}")
sys.exit(0 if all(checks.values()) else 1)
PY

# 3. An unknown extension is refused before any work.
if out=$(cd "$work" && "$prt" -q render box.toml -b box.h5 -o box.tiff 2>&1); then
  echo "FAIL: -o box.tiff accepted"; exit 1
fi
grep -q "box.tiff" <<<"$out" || { echo "FAIL: the refusal does not name the file: $out"; exit 1; }
# 4. --ground-truth without -o writes the name --compare gives the truth
#    (NAME.truth.png), not over the scene's render.
{ cat "$work/box.toml"; printf '[output]\nbake = "box.h5"\nimage = "named.png"\n'; } >"$work/named.toml"
(cd "$work" && "$prt" -q render named.toml >/dev/null && cp named.png render.png &&
  "$prt" -q render named.toml --ground-truth >/dev/null)
cmp -s "$work/named.png" "$work/render.png" ||
  { echo "FAIL: --ground-truth replaced the scene's render"; exit 1; }
[ -s "$work/named.truth.png" ] || { echo "FAIL: --ground-truth wrote no named.truth.png"; exit 1; }
echo "image metrics and outputs: ok"
