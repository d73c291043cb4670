#!/usr/bin/python3
"""Static CPCA by scikit-learn (KMeans + per-cluster PCA) next to prt's, on the
same transfer read from a bake file, in one run.

    scripts/peer_sklearn_cpca.py out/bunny.h5 [--clusters 256] [--components 8]

Prints each side's encode time and squared error SE = sum_p |t_p - t~_p|^2
(Sloan 2003), and the ratios. prt runs as `prt compress ... --json` on a copy.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np
from sklearn.cluster import KMeans


def sklearn_static_cpca(x, clusters, components, seed):
    start = time.perf_counter()
    kmeans = KMeans(n_clusters=clusters, init="k-means++", n_init=1, max_iter=20,
                    random_state=seed).fit(x)
    se = 0.0
    for k in range(clusters):
        members = x[kmeans.labels_ == k].astype(np.float64)
        if len(members) == 0:
            continue
        centred = members - members.mean(axis=0)
        _, _, vt = np.linalg.svd(centred, full_matrices=False)
        basis = vt[:components]
        residual = centred - (centred @ basis.T) @ basis
        se += float(np.sum(residual * residual))
    return time.perf_counter() - start, se


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bake")
    parser.add_argument("--clusters", type=int, default=256)
    parser.add_argument("--components", type=int, default=8)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--prt", default=os.path.join(os.path.dirname(__file__), "..", "build",
                                                     "bin", "prt"))
    parser.add_argument("--init", default="kmeans++", help="prt's LBG start (kmeans++, as the peer, or hyperbox)")
    args = parser.parse_args()

    with h5py.File(args.bake, "r") as f:
        x = f["transfer/coefficients"][:]
    print(f"transfer: {x.shape[0]} x {x.shape[1]} from {args.bake}")

    with tempfile.TemporaryDirectory() as work:
        copy = os.path.join(work, "bake.h5")
        shutil.copy(args.bake, copy)
        start = time.perf_counter()
        out = subprocess.run(
            [args.prt, "-q", "compress", copy, "-c", "cpca", "--json",
             "-p", "method=static", "-p", f"clusters={args.clusters}",
             "-p", f"components={args.components}", "-p", f"seed={args.seed}",
             "-p", f"init={args.init}"],
            check=True, capture_output=True, text=True).stdout
        wall = time.perf_counter() - start
    ours = json.loads(out.strip().splitlines()[-1])
    peer_seconds, peer_se = sklearn_static_cpca(x, args.clusters, args.components, args.seed)

    print(f"{'':>22} {'encode s':>10} {'SE':>12}")
    print(f"{'prt cpca static':>22} {ours['encode_seconds']:>10.3f} {ours['squared_error']:>12.5f}"
          f"   (whole command incl. file I/O {wall:.3f} s)")
    print(f"{'scikit-learn':>22} {peer_seconds:>10.3f} {peer_se:>12.5f}")
    speedup = peer_seconds / ours["encode_seconds"]
    print(f"speed-up {speedup:.2f}x (limit >= 3), SE ratio prt/peer "
          f"{ours['squared_error'] / peer_se:.4f} (limit <= 1)")
    return 0 if speedup >= 3 and ours["squared_error"] <= peer_se else 1


if __name__ == "__main__":
    sys.exit(main())
