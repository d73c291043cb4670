#!/usr/bin/python3
"""Plots and a Markdown report for `prt bench` results.

  scripts/bench_report.py <bench folder> [title] [--budget BYTES]

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
    if record.get("gpu_frame_seconds") is None:
        return "not asked (--gpu)"
    return f"{1000 * record['gpu_frame_seconds']:.1f}"


def ranking(results, fronts, budget):
    """The Pareto ranking and a one-paragraph recommendation for the budget."""
    lines = ["## Ranking", "",
             "Configurations on the front of error against bytes, from the smallest; "
             "`=` marks one tied with the row above (their RMS differ by less than the "
             "ground truth's noise floor, so this reference cannot order them).", "",
             "| rank | configuration | MB | RMS | noise floor | largest error term |",
             "|---|---|---|---|---|---|"]
    by_label = {r["label"]: r for r in results}
    previous = None
    for rank, label in enumerate(fronts["bytes"], 1):
        r = by_label[label]
        floor = r.get("noise_floor", 0.0)
        tied = previous is not None and abs(previous["rms"] - r["rms"]) < max(floor, 1e-300)
        lines.append(f"| {rank}{' =' if tied else ''} | {label} | {r['bytes'] / 1e6:.3f} | "
                     f"{r['rms']:.4g} | {floor:.3g} | {dominant_term(r)} |")
        previous = r
    fitting = [r for r in results if budget is None or r["bytes"] <= budget]
    lines += ["", "## Recommendation", ""]
    if not fitting:
        smallest = min(results, key=lambda r: r["bytes"])
        lines.append(f"No configuration fits in {budget / 1e6:.3f} MB; the smallest swept is "
                     f"`{smallest['label']}` at {smallest['bytes'] / 1e6:.3f} MB.")
        return lines
    best = min(fitting, key=lambda r: r["rms"])
    floor = best.get("noise_floor", 0.0)
    ties = [r["label"] for r in fitting if r is not best and abs(r["rms"] - best["rms"]) < floor]
    cheapest_tie = min([best] + [by_label[t] for t in ties], key=lambda r: r["bytes"])
    within = "any size" if budget is None else f"{budget / 1e6:.3f} MB"
    text = (f"Within {within}, `{best['label']}` has the smallest error (RMS {best['rms']:.4g} "
            f"per vertex, {best['bytes'] / 1e6:.3f} MB, relight {1000 * best['relight_seconds']:.2f}"
            f" ms). ")
    if ties:
        text += (f"{len(ties)} other configuration(s) lie within the ground truth's noise floor "
                 f"({floor:.3g}) of it, so this reference cannot rank them; of those "
                 f"`{cheapest_tie['label']}` is the smallest ({cheapest_tie['bytes'] / 1e6:.3f} MB). "
                 "Raise `--samples` to separate them. ")
    if not best.get("resolved", True):
        text += ("Its RMS is within twice the noise floor: the ranking is the reference's noise "
                 "as much as the configurations'. ")
    text += (f"Its largest error term is {dominant_term(best)}: "
             + {"light truncation": "a larger light basis (order) would help more than a "
                                    "larger compressed form.",
                "transfer projection": "a richer transfer basis or more rays would help more "
                                       "than a larger compressed form.",
                "compression": "a larger compression budget (clusters, components) is where "
                               "accuracy is bought."}[dominant_term(best)])
    lines.append(text)
    return lines


def dominant_term(record):
    terms = {"light truncation": record.get("light_truncation_rms", 0.0),
             "transfer projection": record.get("projection_rms", 0.0),
             "compression": record.get("compression_rms", 0.0)}
    return max(terms, key=terms.get)


def main(folder, title, budget=None):
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
    lines += [""] + ranking(results, fronts, budget)
    lines += ["", "## Images", "",
              "Ground truth | configuration | error heat-map (4 x absolute difference, inferno), "
              "one row per configuration:", "",
              "![image strip](strip.png)", ""]
    with open(os.path.join(folder, "report.md"), "w") as f:
        f.write("\n".join(lines))


if __name__ == "__main__":
    args = sys.argv[1:]
    budget = None
    if "--budget" in args:
        at = args.index("--budget")
        budget = float(args[at + 1])
        del args[at:at + 2]
    main(args[0], args[1] if len(args) > 1 else args[0], budget)
