"""A basis plug-in in numpy: zonal harmonics about one axis.

y_l(d) = sqrt((2l + 1) / 4 pi) P_l(d . axis), l = 0 .. order - 1: the m = 0
column of the spherical harmonics, so a zonal bake equals the SH bake's
m = 0 coefficients (tests/python/test_examples.py checks it).
Import this module and scenes can say [basis] plugin = "numpy_zonal" (the C++
SDK example of docs/writing-a-plugin.md is "zonal").
"""
import numpy as np

import prt

AXES = {"x": 0, "y": 1, "z": 2}


@prt.register_basis("numpy_zonal", description="zonal harmonics about one axis (numpy)")
class Zonal(prt.Basis):
    parameters = {
        "order": prt.integer(6, min=1, max=60, help="bands: order coefficients"),
        "axis": prt.choice("z", ["x", "y", "z"], help="the axis of symmetry"),
    }

    def __init__(self, order, axis):
        super().__init__()
        self.order, self.axis = order, AXES[axis]

    def size(self):
        return self.order

    def orthonormal(self):
        return True

    def coefficient_bands(self):
        return list(range(self.order))

    def evaluate(self, directions):
        t = np.clip(directions[:, self.axis], -1.0, 1.0)
        p = np.empty((len(t), self.order))
        p[:, 0] = 1.0
        if self.order > 1:
            p[:, 1] = t
        for l in range(2, self.order):  # Bonnet's recurrence, stable for |t| <= 1
            p[:, l] = ((2 * l - 1) * t * p[:, l - 1] - (l - 1) * p[:, l - 2]) / l
        return p * np.sqrt((2 * np.arange(self.order) + 1) / (4 * np.pi))
