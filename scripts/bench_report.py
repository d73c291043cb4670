#!/usr/bin/env python3
"""Plots and a Markdown report for `prt bench` results.

  scripts/bench_report.py <bench folder> [title]

Reads <folder>/results.json and <folder>/images/, writes error_vs_bytes.png,
error_vs_relight.png, error_vs_bake.png (Pareto front marked, each point
labelled), strip.png (ground truth | configuration | error x4, one row per
configuration) and report.md embedding them with the table.
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from PIL import Image, ImageDraw  # noqa: E402


def pareto(points):
    """Indices of points not dominated in (cost, error), sorted by cost."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], float("inf")
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def plot(results, cost_key, cost_label, path, scale=1.0):
    costs = [r[cost_key] * scale for r in results]
    errors = [r["rms"] for r in results]
    front = pareto(list(zip(costs, errors)))
    fig, ax = plt.subplots(figsize=(10, 7))
    # Colour by basis setting, marker by compressor, where the labels say so.
    compressors = ("none", "vq", "pca", "cpca")
    markers = dict(zip(compressors, "sDo^"))
    groups = {}
    for r, x, y in zip(results, costs, errors):
        words = r["label"].split()
        cut = next((k for k, w in enumerate(words) if w in compressors), len(words))
        basis = " ".join(words[:cut]) or "scene"
        marker = markers.get(words[cut], "o") if cut < len(words) else "o"
        groups.setdefault((basis, marker), []).append((x, y))
    colours = {}
    for (basis, marker), points in groups.items():
        colour = colours.setdefault(basis, f"C{len(colours) % 10}")
        ax.scatter(*zip(*points), color=colour, marker=marker, zorder=2, alpha=0.8,
                   label=basis if marker == "o" or basis not in [b for b, _ in list(groups)[:0]] else None)
    ax.plot([costs[i] for i in front], [errors[i] for i in front], color="tab:red",
            marker="o", zorder=3, label="Pareto front")
    for r, x, y in zip(results, costs, errors):
        ax.annotate(r["label"], (x, y), fontsize=5.5, xytext=(3, 2), textcoords="offset points",
                    alpha=0.8)
    floors = [r.get("noise_floor", 0.0) for r in results]
    if max(floors) > 0:  # below it the ground truth cannot rank configurations
        ax.axhline(2 * max(floors), color="grey", linestyle="--", zorder=1,
                   label="2 x noise floor of the ground truth")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(cost_label)
    ax.set_ylabel("RMS error per vertex vs ground truth (linear radiance)")
    ax.grid(True, which="both", alpha=0.3)
    handles, names = ax.get_legend_handles_labels()
    unique = dict(zip(names, handles))
    # Colours follow the basis part of each label; when every configuration
    # has its own, say so.
    by = "configuration" if len(colours) == len(results) else "basis setting"
    ax.legend(unique.values(), unique.keys(), fontsize=8,
              title=f"colour: {by}; marker: none s, vq D, pca o, cpca ^", title_fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return [results[i]["label"] for i in front]


def heat(grey):
    """A grey error image as a heat map (black/blue small, red/yellow large)."""
    colour = matplotlib.colormaps["inferno"]
    lut = [tuple(int(255 * c) for c in colour(v / 255.0)[:3]) for v in range(256)]
    out = Image.new("RGB", grey.size)
    out.putdata([lut[v] for v in grey.getdata()])
    return out


def strip(folder, results, path, width=160):
    images = os.path.join(folder, "images")
    truth = Image.open(os.path.join(images, "ground_truth.png")).convert("RGB")
    height = int(truth.height * width / truth.width)
    rows = []
    for r in results:
        error = Image.open(os.path.join(images, f"{r['image']}.error.png")).convert("L")
        cells = [truth,
                 Image.open(os.path.join(images, f"{r['image']}.png")).convert("RGB"),
                 heat(error)]
        row = Image.new("RGB", (3 * width, height + 14), "white")
        for k, cell in enumerate(cells):
            row.paste(cell.resize((width, height)), (k * width, 14))
        ImageDraw.Draw(row).text((2, 1), r["label"], fill="black")
        rows.append(row)
    sheet = Image.new("RGB", (3 * width, sum(r.height for r in rows)), "white")
    y = 0
    for row in rows:
        sheet.paste(row, (0, y))
        y += row.height
    sheet.save(path)


def gpu_text(record):
    """The GPU frame time, or why there is none."""
    if "gpu_frame_seconds" not in record:
        return "not asked (--gpu)"
    return f"{1000 * record['gpu_frame_seconds']:.1f}"


def main(folder, title):
    with open(os.path.join(folder, "results.json")) as f:
        results = json.load(f)
    fronts = {
        "bytes": plot(results, "bytes", "bytes of the compressed form (4 x stored floats, bytes)",
                      os.path.join(folder, "error_vs_bytes.png")),
        "relight": plot(results, "relight_seconds", "CPU relight time per frame (ms)",
                        os.path.join(folder, "error_vs_relight.png"), 1000.0),
        "bake": plot(results, "bake_seconds", "bake time (s): trace + project + encode",
                     os.path.join(folder, "error_vs_bake.png")),
    }
    strip(folder, results, os.path.join(folder, "strip.png"))
    lines = [f"# Speed/accuracy sweep: {title}", "",
             f"{len(results)} configurations, errors averaged over {results[0]['lights']} "
             "light(s) (the scene's and rotated copies).", ""]
    for key, name, label in (("bytes", "error_vs_bytes.png", "bytes"),
                             ("relight", "error_vs_relight.png", "relight time"),
                             ("bake", "error_vs_bake.png", "bake time")):
        lines += [f"## Error vs {label}", "", f"![error vs {label}]({name})", "",
                  "Pareto front: " + ", ".join(f"`{x}`" for x in fronts[key]), ""]
    lines += ["## Table", "",
              "RMS is per vertex against the Monte Carlo ground truth; its **noise floor** is "
              "the ground truth's own standard error (per-vertex RMS): an RMS within twice it "
              "is not resolved (marked *), and configurations whose RMS differ by less than it "
              "are tied. The budget splits the RMS into light truncation, transfer projection "
              "and compression (`prt render --compare` prints the same terms).", "",
              "| configuration | bake s | encode s | MB (compressed) | file MB | bytes/vertex "
              "| relight ms | GPU frame ms | transfer SE | RMS | noise floor | truncation "
              "| projection | compression | p99 | max | image error |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        floor = r.get("noise_floor", 0.0)
        mark = "" if r.get("resolved", True) else " *"
        lines.append(
            f"| {r['label']} | {r['bake_seconds']:.2f} | {r['encode_seconds']:.2f} | "
            f"{r['bytes'] / 1e6:.3f} | {r['file_bytes'] / 1e6:.2f} | {r['bytes_per_vertex']:.1f} | "
            f"{1000 * r['relight_seconds']:.2f} | "
            f"{gpu_text(r)} | {r['transfer_se']:.4g} | {r['rms']:.4g}{mark} | {floor:.3g} | "
            f"{r['light_truncation_rms']:.3g} | {r['projection_rms']:.3g} | "
            f"{r['compression_rms']:.3g} | "
            f"{r['p99']:.4g} | {r['max']:.4g} | {r['image_error']:.4g} |")
    lines += ["", "## Images", "",
              "Ground truth | configuration | error heat-map (4 x absolute difference, inferno), "
              "one row per configuration:", "",
              "![image strip](strip.png)", ""]
    with open(os.path.join(folder, "report.md"), "w") as f:
        f.write("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else sys.argv[1])
