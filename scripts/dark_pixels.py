#!/usr/bin/python3
"""Far-off pixels of bakes against the ground truth, over light rotations and
cameras: the artifact a good RMS hides (issue 39's glossy speckles).

  /usr/bin/python3 scripts/dark_pixels.py SCENE BAKE [BAKE ...]
      [--rotations 0,30,...] [--cameras default,left,right,above]
      [--cache DIR] [--crops DIR] [--samples N]

For each light rotation and camera it renders every bake as `prt render`
does and the Monte Carlo ground truth (cached in --cache: the slow part), and
prints per bake the pixels darker than half the ground truth (ground-truth
luminance > 40 of 255 at the scene's exposure, as `prt render --compare`
counts them) and the relative RMS per vertex. Cameras: the scene's default
framing, the same turned -30 / +30 degrees about the vertical, and raised to
30 degrees above the horizontal. --crops writes, per configuration with dark
pixels, a crop around them: each bake, then the ground truth with the dark
pixels of the first bake in magenta.

Needs the built Python module: PYTHONPATH=build/lib/python3.11/dist-packages.
"""
import argparse
import hashlib
import json
import tomllib
import math
import pathlib
import sys

import numpy as np

import prt

CAMERAS = {"default": (0.0, None), "left": (-30.0, None), "right": (30.0, None),
           "above": (0.0, 30.0)}


def srgb8(linear, exposure):
    x = np.clip(np.nan_to_num(linear * exposure, nan=0.0), 0.0, 1.0)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(s * 255.0)


def luminance(image, exposure):
    return srgb8(image, exposure) @ np.array([0.2126, 0.7152, 0.0722])


def relative_rms(approximation, reference):
    errors = np.sum((approximation - reference) ** 2, axis=1) / 3
    energy = np.sum(reference ** 2, axis=1) / 3
    return math.sqrt(errors.mean()) / math.sqrt(energy.mean())


def camera_position(scene, mesh, turn, elevation):
    framing = scene.camera(mesh)  # the scene's own camera, or its framing of the mesh
    target = np.array(framing.target, dtype=float)
    offset = np.array(framing.position, dtype=float) - target
    distance = np.linalg.norm(offset)
    if elevation is not None:
        horizontal = np.array([offset[0], 0.0, offset[2]])
        horizontal /= np.linalg.norm(horizontal)
        e = math.radians(elevation)
        offset = distance * (math.cos(e) * horizontal + np.array([0, math.sin(e), 0]))
    t = math.radians(turn)
    rotate = np.array([[math.cos(t), 0, math.sin(t)], [0, 1, 0], [-math.sin(t), 0, math.cos(t)]])
    return (target + rotate @ offset).tolist()


def truth_key(scene):
    """What the ground truth depends on: not the bases, the compressor, the
    renderer, the output or the light's window (the truth is the full light)."""
    sections = scene.to_dict()
    for section in ("basis", "exit", "compressor", "renderer", "output"):
        sections.pop(section, None)
    sections.get("lighting", {}).pop("window", None)
    folder = pathlib.Path(scene.file).parent  # paths as files, wherever the scene is
    for section, key in (("mesh", "file"), ("lighting", "environment")):
        if key in sections.get(section, {}):
            sections[section][key] = str((folder / sections[section][key]).resolve())
    text = json.dumps(sections, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene")
    parser.add_argument("bakes", nargs="+")
    parser.add_argument("--rotations", default=",".join(str(r) for r in range(0, 360, 30)))
    parser.add_argument("--cameras", default=",".join(CAMERAS))
    parser.add_argument("--cache", default="out/ground-truth-cache")
    parser.add_argument("--crops", default=None)
    parser.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE",
                        help="change the scene for every render (a TOML value), e.g. "
                             "lighting.window='\"hanning\"'")
    parser.add_argument("--samples", type=int, default=None,
                        help="ground-truth samples per vertex (default: the scene's)")
    args = parser.parse_args()

    scene = prt.Scene(args.scene)
    bakes = [prt.read_bake(b) for b in args.bakes]
    mesh = bakes[0].mesh
    cache = pathlib.Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    exposure = float(scene.to_dict()["camera"].get("exposure", 1.0))
    names = [pathlib.Path(b).stem for b in args.bakes]
    print("rotation camera " + " ".join(f"{n}:dark {n}:relRMS" for n in names))
    totals = [0] * len(bakes)
    for rotation in [float(r) for r in args.rotations.split(",")]:
        for camera in args.cameras.split(","):
            if camera not in CAMERAS:
                sys.exit(f"dark_pixels.py: unknown camera {camera!r} ({', '.join(CAMERAS)})")
            turn, elevation = CAMERAS[camera]
            changes = {"lighting": {"rotation": rotation},
                       "camera": {"position": camera_position(scene, mesh, turn, elevation)}}
            if args.samples:
                changes["ground_truth"] = {"samples": args.samples}
            for assignment in args.set:
                name, value = assignment.split("=", 1)
                section, key = name.split(".", 1)
                changes.setdefault(section, {})[key] = tomllib.loads(f"v = {value}")["v"]
            variant = scene.replace(changes)
            key = truth_key(variant)
            cached = cache / f"{key}.npz"
            if cached.exists():
                truth = dict(np.load(cached))
            else:
                truth = prt.render_ground_truth(variant, mesh, progress=False)
                truth = {"image": truth["image"], "vertex_radiance": truth["vertex_radiance"]}
                np.savez_compressed(cached, **truth)
            expected = luminance(truth["image"], exposure)
            lit = expected > 40
            row = [f"{rotation:8.0f} {camera:7s}"]
            masks = []
            for i, data in enumerate(bakes):
                rendered = prt.render(variant, data, progress=False)
                dark = lit & (luminance(rendered["image"], exposure) < 0.5 * expected)
                masks.append((rendered["image"], dark))
                totals[i] += int(dark.sum())
                row.append(f"{int(dark.sum()):6d} "
                           f"{relative_rms(rendered['vertex_radiance'], truth['vertex_radiance']):.4f}")
            print(" ".join(row), flush=True)
            if args.crops and masks[0][1].any():
                write_crop(pathlib.Path(args.crops) / f"r{rotation:03.0f}-{camera}.png", masks,
                           truth["image"], exposure)
    print("total dark pixels: " + " ".join(f"{n} {t}" for n, t in zip(names, totals)))


def write_crop(file, masks, truth, exposure):
    from PIL import Image
    ys, xs = np.nonzero(masks[0][1])
    cy, cx = int(np.median(ys)), int(np.median(xs))
    y0, x0 = max(cy - 75, 0), max(cx - 100, 0)
    marked = srgb8(truth, exposure)
    marked[masks[0][1]] = [255, 0, 255]
    tiles = [srgb8(image, exposure) for image, _ in masks] + [srgb8(truth, exposure), marked]
    crop = np.concatenate([t[y0:y0 + 150, x0:x0 + 200] for t in tiles], axis=1)
    file.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(crop.astype(np.uint8)).resize((crop.shape[1] * 2, 300), Image.NEAREST).save(file)


if __name__ == "__main__":
    main()
