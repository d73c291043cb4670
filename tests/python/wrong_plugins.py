"""Deliberately wrong Python plug-ins: the conformance kit must fail them."""
import numpy as np

import prt


@prt.register_basis("zonal_unnormalised", description="zonal harmonics missing their norm")
class UnnormalisedZonal(prt.Basis):
    """Claims orthonormality but leaves out sqrt((2l + 1) / 4 pi)."""

    def __init__(self):
        super().__init__()

    def size(self):
        return 4

    def orthonormal(self):
        return True

    def evaluate(self, directions):
        t = directions[:, 2]
        return np.stack([np.ones_like(t), t, 1.5 * t**2 - 0.5, 2.5 * t**3 - 1.5 * t], axis=1)


@prt.register_basis("wrong_shape", description="evaluate returns the wrong shape")
class WrongShape(prt.Basis):
    def __init__(self):
        super().__init__()

    def size(self):
        return 3

    def orthonormal(self):
        return False

    def evaluate(self, directions):
        return np.ones((len(directions), 2))


@prt.register_compressor("keeps_mean_only", description="claims to encode but drops rows")
class MeanOnly(prt.Compressor):
    """One cluster, no components, but reports the wrong vertex count."""

    def __init__(self):
        super().__init__()

    def encode(self, signal, mesh):
        x = signal.coefficients
        return prt.CompressedTransfer("keeps_mean_only", x.shape[1],
                                      np.zeros(len(x) - 1, np.int32),
                                      np.zeros((len(x) - 1, 0), np.float32),
                                      x.mean(0, keepdims=True), [np.zeros((0, x.shape[1]),
                                                                          np.float32)])
