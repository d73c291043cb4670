#!/usr/bin/python3
"""Bakes the bunny once, compresses its transfer many ways (C++ plug-ins and
the numpy k-means + SVD one), plots squared error against bytes, and shows
the image of each compressor's best setting beside the exact one.

    export PYTHONPATH=$PWD/build/lib/python3.11/dist-packages
    /usr/bin/python3 examples/python/error_vs_bytes.py [--quick] [--out out/python]
"""
import argparse
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")  # files, no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).parent))
import kmeans_svd  # noqa: E402,F401  registers compressor "kmeans_svd"
import prt  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", default=ROOT / "scenes" / "bunny.toml", type=pathlib.Path)
    parser.add_argument("--out", default=ROOT / "out" / "python", type=pathlib.Path)
    parser.add_argument("--quick", action="store_true", help="fewer settings (for tests)")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    # Bake the exact transfer once; every compressor then starts from it.
    scene = prt.Scene(args.scene)
    data = prt.bake(scene, compress=False)
    print(f"baked {data.mesh.vertex_count} vertices x {data.transfer.dimension} coefficients")

    budgets = [(8, 2), (32, 4)] if args.quick else [(8, 2), (16, 4), (32, 4), (64, 8), (128, 8)]
    settings = {
        "cpca (C++)": [("cpca", dict(clusters=k, components=n)) for k, n in budgets],
        "kmeans_svd (numpy)": [("kmeans_svd", dict(clusters=k, components=n))
                               for k, n in budgets],
        "pca (C++)": [("pca", dict(components=n)) for n in ([4, 16] if args.quick
                                                              else [2, 4, 8, 16, 32])],
    }
    results = {}
    for label, runs in settings.items():
        for name, params in runs:
            compressed, report = prt.compress(data.transfer, name, mesh=data.mesh, **params)
            results.setdefault(label, []).append((report.stored_bytes, report.squared_error,
                                                  compressed, params))
            print(f"{label:20s} {params}: {report.stored_bytes / 1e6:7.2f} MB, "
                  f"SE {report.squared_error:.5g}, {report.encode_seconds:.2f} s")

    figure, axis = plt.subplots(figsize=(6, 4))
    for label, points in results.items():
        axis.loglog([p[0] / 1e6 for p in points], [p[1] for p in points], "o-", label=label)
    axis.set_xlabel("stored MB (float32)")
    axis.set_ylabel("squared error")
    axis.set_title(f"{args.scene.name}: error against bytes")
    axis.legend()
    figure.tight_layout()
    figure.savefig(args.out / "error_vs_bytes.png", dpi=120)
    print(f"plot -> {args.out / 'error_vs_bytes.png'}")

    # The images: exact transfer and each compressor's largest budget.
    relighting = prt.Relighting(scene, data)
    light = relighting.light(scene.load_environment())
    camera = scene.camera(data.mesh)
    camera.width, camera.height = 400, 300
    renderer = prt.create_renderer("cpu")
    panels = [("exact", data.compressed)] + [(label, points[-1][2])
                                             for label, points in results.items()]
    figure, axes = plt.subplots(1, len(panels), figsize=(3.2 * len(panels), 2.6))
    for axis, (label, transfer) in zip(axes, panels):
        image = relighting.render(transfer, light, camera, renderer)["image"]
        axis.imshow(np.clip(0.7 * image, 0, 1) ** (1 / 2.2))
        axis.set_title(label, fontsize=9)
        axis.axis("off")
    figure.tight_layout()
    figure.savefig(args.out / "images.png", dpi=120)
    print(f"images -> {args.out / 'images.png'}")


if __name__ == "__main__":
    main()
