"""A compressor plug-in in numpy: k-means clusters, then per-cluster PCA by SVD.

The C++ "cpca" plug-in with method = "static" does the same (Sloan et al.
2003, section 4.2: VQ, then PCA in each cluster); this one is the textbook
version in ~50 lines, for comparison (tests/python/test_examples.py).
Import this module and scenes can say [compressor] plugin = "kmeans_svd".
"""
import numpy as np

import prt


def kmeans(x, k, iterations, rng):
    """Lloyd's k-means with k-means++ seeding; returns the label of each row."""
    k = min(k, len(x))
    centres = [x[rng.integers(len(x))]]
    distance = ((x - centres[0]) ** 2).sum(1)
    for _ in range(1, k):  # k-means++: far points are likelier seeds
        if distance.sum() <= 0:
            break
        centres.append(x[rng.choice(len(x), p=distance / distance.sum())])
        distance = np.minimum(distance, ((x - centres[-1]) ** 2).sum(1))
    centres = np.array(centres)
    for _ in range(iterations):
        d = (x**2).sum(1)[:, None] - 2 * x @ centres.T + (centres**2).sum(1)[None, :]
        labels = d.argmin(1)
        sums = np.zeros_like(centres)
        np.add.at(sums, labels, x)
        counts = np.bincount(labels, minlength=len(centres))[:, None]
        centres = np.where(counts > 0, sums / np.maximum(counts, 1), centres)
    return np.unique(labels, return_inverse=True)[1]  # no empty clusters


@prt.register_compressor("kmeans_svd", description="k-means, then PCA per cluster (numpy)")
class KMeansSVD(prt.Compressor):
    parameters = {
        "clusters": prt.integer(64, min=1, max=1 << 20, help="k-means clusters"),
        "components": prt.integer(8, min=0, max=4096, help="PCA components per cluster"),
        "iterations": prt.integer(20, min=0, max=1000, help="Lloyd iterations"),
        "seed": prt.integer(1, min=0, max=2**31, help="k-means++ seed"),
    }

    def __init__(self, clusters, components, iterations, seed):
        super().__init__()
        self.clusters, self.components = clusters, components
        self.iterations, self.seed = iterations, seed

    def encode(self, signal, mesh):
        x = signal.coefficients.astype(np.float64)
        labels = kmeans(x, self.clusters, self.iterations, np.random.default_rng(self.seed))
        n_comp = min(self.components, x.shape[1])
        weights = np.zeros((len(x), n_comp), np.float32)
        means, representatives = [], []
        for k in range(labels.max() + 1):
            members = np.flatnonzero(labels == k)
            mean = x[members].mean(0)
            centred = x[members] - mean
            _, _, vt = np.linalg.svd(centred, full_matrices=False)
            basis = vt[: min(n_comp, len(members))]
            weights[members, : len(basis)] = centred @ basis.T
            means.append(mean)
            representatives.append(basis.astype(np.float32))
        return prt.CompressedTransfer("kmeans_svd", x.shape[1], labels.astype(np.int32), weights,
                                      np.array(means, np.float32), representatives)
