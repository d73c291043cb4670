#!/usr/bin/python3
"""Writes docs/table1.md from scripts/table1.sh's results beside Sloan et al.
2003's Table 1.   table1_report.py results.tsv docs/table1.md"""
import datetime
import math
import platform
import subprocess
import sys

PAPER = """| model | BRDF | m_p | transfer | m_c | n' | static cpu | static SE | iterative cpu | iterative SE | fps |
|---|---|---|---|---|---|---|---|---|---|---|
| Buddha | gloss-iso | 49990 | 16x25 | 256 | 6 | 3m30s | 563 | 1h51m | 451 | 42.8 |
| Buddha | gloss-anis | 49990 | 24x25 | 256 | 8 | 6m7s | 10996 | 4h34m | 8524 | 24.2 |
| Buddha | subsurf+gloss-iso | 49990 | 25x25 | 256 | 8 | 6m21s | 1992 | 4h32m | 1439 | 27 |
| bird | gloss-anis | 48688 | 24x25 | 256 | 8 | 6m34s | 898 | 3h43m | 294 | 45 |
| bird | diffuse | 48688 | 1x100 | 256 | 8 | 43s | 3.14 | 3m26s | 0.668 | 227 |
| head | gloss-iso | 50060 | 16x25 | 256 | 6 | 4m20s | 78.8 | 2h12m | 43.7 | 58.5 |
| polys | diffuse | 58624 | 1x100 | 32 | 4 | 14s | 0.492 | 3m26s | 0.432 | 294 |"""


def duration(seconds):
    seconds = float(seconds)
    if seconds < 60:
        return f"{seconds:.1f}s"
    return f"{int(seconds // 60)}m{seconds % 60:04.1f}s"


def fps(ms):
    ms = float(ms)
    return f"{1000 / ms:.1f}" if ms > 0 and math.isfinite(ms) else "n/a"


def cpu():
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return platform.machine()


def main():
    results, output = sys.argv[1], sys.argv[2]
    rows = [line.rstrip("\n").split("|") for line in open(results) if line.strip()]
    opengl = rows[0][11] if rows and len(rows[0]) > 11 and rows[0][11] else "unknown"
    lines = []
    ordered = 0
    for r in rows:
        mesh, vertices, name, transfer, components = r[:5]
        se_s, t_s, ms_s, se_i, t_i, ms_i = r[5:11]
        holds = float(se_i) < float(se_s)
        ordered += holds
        lines.append(
            f"| {mesh} | {name} | {vertices} | {transfer} | 256 | {components} | {duration(t_s)} | "
            f"{float(se_s):.4g} | {duration(t_i)} | {float(se_i):.4g} | "
            f"{float(se_i) / float(se_s):.3f} | {'yes' if holds else '**no**'} | "
            f"{fps(ms_s)} / {fps(ms_i)} |")
    reductions = [float(r[8]) / float(r[5]) for r in rows]
    speed = [float(r[9]) / max(float(r[6]), 1e-9) for r in rows]
    with open(output, "w") as f:
        f.write(f"""# Table 1 of Sloan et al. 2003, reproduced

Made by one command, `scripts/table1.sh` (it bakes, compresses and renders
every row; logs, scenes and bakes in out/table1/) on {cpu()},
{subprocess.run(['nproc'], capture_output=True, text=True).stdout.strip()} cores, {datetime.date.today().isoformat()}.
Frame rates are prt-view's OpenGL path
(scripted frames with the light turning, median frame time, no panel) on
{opengl.strip()}.

Every row: the courtyard map, order-5 SH light for glossy rows (order 10,
1 x 100, for diffuse), 1024 Fibonacci directions per vertex, exact transfer
baked once, then CPCA with 256 clusters and n' components, static (§4.1)
and iterative (§4.2, 10 iterations per component). SE is the squared error
summed over all vertices, as in the paper, but for glossy rows in the
rendered metric: since issue 39 the exit basis's metric (the hemispherical
SH are not orthonormal over the hemisphere) is part of what CPCA minimises
and reports (docs/bases.md), so glossy SE is the function-space error of the
rendered exit radiance: 28x to 40x below the coefficient-space SE these
rows had before (the bunny's gloss-iso static: 2180 then, 54 now); diffuse rows (orthonormal SH) are unchanged.
Glossy rows: Phong (kd 0.4, ks
0.6, exponent 12) for gloss-iso, Ward (alpha 0.1 x 0.3) for gloss-anis, both
with the hemispherical SH exit basis of the row's size (16 = order 4, 24 =
order 5 reduced, 25 = order 5); subsurface adds the Jensen-Buhler dipole
(marble, each mesh scaled to 100 mm across).

## This tool

| mesh | BRDF | m_p | transfer | m_c | n' | static cpu | static SE | iterative cpu | iterative SE | iterative / static SE | iterative < static | fps static / iterative |
|---|---|---|---|---|---|---|---|---|---|---|---|---|
""")
        f.write("\n".join(lines) + "\n")
        f.write(f"""
Iterative CPCA has lower SE than static on {ordered} of {len(rows)} rows.

## The paper (2.2 GHz Pentium IV, ATI Radeon 9700)

{PAPER}

## Where and why they differ

- **SE ordering** {"is the paper's: iterative below static on every row here" if ordered == len(rows) else "departs from the paper's on " + str(len(rows) - ordered) + " rows: iterative below static"}
  ({ordered}/{len(rows)}), by a factor {min(reductions):.2f}-{max(reductions):.2f}
  (the paper: 0.21-0.88). Iterative CPCA re-assigns vertices to the cluster
  whose affine subspace reconstructs them best, which static CPCA (clusters
  fixed by VQ on the raw signal) cannot.
- **SE values** are not comparable across the tables: SE scales with the
  transfer's units (ours: exit radiance per unit light coefficient with
  albedo 1, 1024 rays), the meshes (CGAL's bunny, armadillo and Chinese
  dragon, not the Buddha, bird and head scans) and the BRDF parameters, which
  the paper does not give.
- **Encode time**: iterative costs {min(speed):.1f}-{max(speed):.1f}x static here
  against 5-45x in the paper; both are minutes to hours faster in absolute
  terms (two 2020s cores against a 2003 Pentium IV, and CPCA's per-cluster
  eigen-solves in Eigen; docs/performance.md).
- **Frame rates** {"come from a software rasteriser (Mesa llvmpipe on the CPU cores, no GPU): they measure the same per-vertex weighted sums and per-cluster constants as the paper's, but are not a GPU's numbers, and they vary with other load on the machine" if "llvmpipe" in opengl else "are " + opengl + "'s"}. Glossy rows are slower than diffuse, as in the paper,
  because each vertex reads N_r exit-basis values and sums N_r x n' products.
""")


if __name__ == "__main__":
    main()
