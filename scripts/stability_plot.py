#!/usr/bin/python3
"""Figure of SH ringing around a sun 1e5 times the sky, with and without windows.

  prt stability --figure-data out/ringing.csv
  scripts/stability_plot.py out/ringing.csv docs/images/ringing.png

Left: radiance along the great circle through the sun (order 15), symlog scale,
negative values shaded. Right: the negative solid angle per order and window.
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(source, target):
    curves = defaultdict(list)
    with open(source) as f:
        for row in csv.DictReader(f):
            curves[(int(row["order"]), row["window"])].append(
                (float(row["angle_degrees"]), float(row["radiance"])))
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    order = 15 if any(k[0] == 15 for k in curves) else max(k[0] for k in curves)
    for window in ("none", "hanning", "lanczos"):
        points = curves.get((order, window))
        if not points:
            continue
        angles, values = zip(*points)
        left.plot(angles, values, label=window)
    left.axhline(0, color="black", linewidth=0.5)
    left.axhspan(-1e4, 0, color="red", alpha=0.08)
    left.set_yscale("symlog", linthresh=1)
    left.set_xlabel("angle from the sun along a great circle (degrees)")
    left.set_ylabel("reconstructed radiance (sky = 1)")
    left.set_title(f"order {order} SH of a sun 1e5 x the sky")
    left.legend()
    # Negative area: the share of samples below zero along the full sphere is
    # in the report; here, the share of the great circle below zero.
    orders = sorted({k[0] for k in curves})
    width = 0.25
    for i, window in enumerate(("none", "hanning", "lanczos")):
        shares = []
        for o in orders:
            values = [v for _, v in curves.get((o, window), [])]
            shares.append(sum(v < 0 for v in values) / max(1, len(values)))
        right.bar([o + (i - 1) * width * 2 for o in orders], shares, width * 2, label=window)
    right.set_xlabel("SH order")
    right.set_ylabel("share of the circle with negative radiance")
    right.set_title("negative radiance, with and without windows")
    right.legend()
    fig.tight_layout()
    fig.savefig(target, dpi=90)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
