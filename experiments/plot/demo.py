"""Draws the picture of `hooke demo` (experiments/demo_command.cpp).

Usage: /usr/bin/python3 experiments/plot/demo.py OUT_DIR
Reads OUT_DIR/implicit/log.csv, OUT_DIR/explicit/log.csv, OUT_DIR/summary.txt and the implicit
run's VTK frames (OUT_DIR/implicit/frames.pvd); writes OUT_DIR/demo.png: left, the largest spring
strain against time for both runs (log scale: the explicit run's strain explodes within a few
steps, the implicit one stays at a few percent); right, the implicit cloth at five times, seen
obliquely (x to the right, y up, z receding up and to the right).
"""
import os
import re
import sys
import textwrap

import numpy as np

from common import num, plt, read_csv, read_vtk, save_figure


def frames(run_dir):
    """(time, path) of every frame listed in run_dir/frames.pvd."""
    with open(os.path.join(run_dir, "frames.pvd")) as f:
        text = f.read()
    return [(float(t), os.path.join(run_dir, p))
            for t, p in re.findall(r'timestep="([^"]+)" file="([^"]+)"', text)]


def main(out_dir):
    imp = read_csv(os.path.join(out_dir, "implicit", "log.csv"))
    exp = read_csv(os.path.join(out_dir, "explicit", "log.csv"))
    with open(os.path.join(out_dir, "summary.txt")) as f:
        summary = f.read().strip()
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.6), gridspec_kw={"width_ratios": [1, 1.1]})

    def strain(rows):
        t = [num(r["t"]) for r in rows if num(r["t"]) > 0]
        s = [max(100 * num(r["max_strain"]), 1e-3) for r in rows if num(r["t"]) > 0]
        return t, s

    t, s = strain(imp)
    ax.plot(t, s, color="tab:blue", lw=1.5, label="implicit (scene's method), stable")
    t, s = strain(exp)
    ax.plot(t, s, color="tab:red", lw=1.5, marker="o", ms=3, label="explicit at the same h")
    if t:
        ax.plot(t[-1], s[-1], "x", color="tab:red", ms=10, mew=2)
        ax.annotate("diverged", (t[-1], s[-1]), textcoords="offset points", xytext=(8, -4),
                    color="tab:red")
    ax.set_yscale("log")
    ax.set_xscale("log")
    ax.set_xlabel("simulated time t (s)")
    ax.set_ylabel("largest spring strain (%)")
    ax.set_title("strain of the stiffest springs", fontsize=9)
    ax.legend(loc="lower right")

    fr = frames(os.path.join(out_dir, "implicit"))
    if fr:
        end = fr[-1][0]
        wanted = [0.0, 0.1 * end, 0.25 * end, 0.5 * end, end]
        chosen = []
        for w in wanted:
            best = min(fr, key=lambda f: abs(f[0] - w))
            if best not in chosen:
                chosen.append(best)
        cmap = plt.get_cmap("viridis")
        for k, (time, path) in enumerate(chosen):
            frame = read_vtk(path)
            p, lines = frame["points"], frame["lines"]
            px = p[:, 0] + 0.35 * p[:, 2]
            py = p[:, 1] + 0.2 * p[:, 2]
            colour = cmap(k / max(1, len(chosen) - 1))
            segs = np.stack([np.stack([px[lines[:, 0]], py[lines[:, 0]]], axis=1),
                             np.stack([px[lines[:, 1]], py[lines[:, 1]]], axis=1)], axis=1)
            from matplotlib.collections import LineCollection
            ax2.add_collection(LineCollection(segs, colors=[colour], linewidths=0.25, alpha=0.8))
            ax2.plot([], [], color=colour, label=f"t = {time:.2g} s")
        ax2.autoscale()
        ax2.set_aspect("equal")
        ax2.set_xlabel("x + 0.35 z (m)")
        ax2.set_ylabel("y + 0.2 z (m)")
        ax2.set_title("the implicit run's cloth (oblique view)", fontsize=9)
        ax2.legend(loc="lower left")
    fig.suptitle("\n".join(textwrap.wrap(summary, 120)), fontsize=8.5)
    fig.tight_layout(rect=(0, 0, 1, 0.9))
    save_figure(fig, os.path.join(out_dir, "demo.png"))


if __name__ == "__main__":
    main(sys.argv[1])
