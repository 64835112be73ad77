#!/usr/bin/python3
"""Plots hooke step-convergence output: objective error against iterations and against wall time,
one row per stiffness k (at h = 1e-2 s when present, else the smallest h), one line per method.
Usage: step_convergence.py DIR (reads DIR/step_convergence.csv, writes DIR/step_convergence.png)"""
import csv
import sys
from collections import defaultdict

from common import plt, save_figure

rows = list(csv.DictReader(open(sys.argv[1] + "/step_convergence.csv")))
hs = sorted({float(r["h"]) for r in rows})
h = 1e-2 if 1e-2 in hs else hs[0]
ks = sorted({float(r["k"]) for r in rows})
curves = defaultdict(list)
for r in rows:
    if float(r["h"]) == h:
        curves[(float(r["k"]), r["method"])].append(
            (int(r["iterations"]), float(r["wall_seconds"]), abs(float(r["objective_error"]))))
methods = sorted({m for (_, m) in curves})
style = {m: ["-", "--", "-.", ":"][i % 4] for i, m in enumerate(methods)}
fig, axes = plt.subplots(len(ks), 2, figsize=(11, 3.2 * len(ks)), squeeze=False)
for row, k in enumerate(ks):
    for m in methods:
        pts = curves.get((k, m), [])
        if not pts:
            continue
        it = [p[0] for p in pts]
        wall = [1e3 * p[1] for p in pts]
        err = [max(p[2], 1e-17) for p in pts]
        marker = "o" if m.startswith(("newton", "xpbd")) else None
        axes[row][0].loglog(it, err, style[m], marker=marker, ms=3, label=m)
        axes[row][1].loglog(wall, err, style[m], marker=marker, ms=3, label=m)
    axes[row][0].set_ylabel(f"objective error (k = {k:g} N/m)" if k > 0 else "objective error")
    for c in range(2):
        axes[row][c].axhline(1e-6, color="grey", lw=0.6)
        axes[row][c].grid(True, which="major", lw=0.3)
axes[-1][0].set_xlabel("iterations (Newton: iterations; xpbd: substeps)")
axes[-1][1].set_xlabel("wall time of the step (ms)")
axes[0][1].legend(fontsize=7, loc="best")
fig.suptitle(f"One backward-Euler step, h = {h:g} s: error (g(x) - g*) / (g(y) - g*) against the "
             "exact step (Ceres)", fontsize=10)
fig.tight_layout()
save_figure(fig, sys.argv[1] + "/step_convergence.png", dpi=110)
