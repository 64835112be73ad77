"""Plots the scaling study written by `hooke scaling` (experiments/studies/scaling_study.cpp).

Usage: /usr/bin/python3 experiments/plot/scaling.py OUT_DIR
Reads OUT_DIR/scaling.csv; writes OUT_DIR/scaling.png (time per iteration and per step against
springs, log-log, one colour per method, solid 2 threads, dashed 1 thread) and OUT_DIR/scaling.md
(the fitted exponent of time per iteration against springs per method and thread count, least
squares in log-log over the sizes run, with the exponent of the factor's entries for methods that
stream a Cholesky factor, and every run's numbers).
"""
import math
import os
import sys

import numpy as np

from common import g3, markdown_table, num, plt, read_csv, save_figure, style, write_text


def fit_exponent(springs, seconds):
    pts = [(math.log(s), math.log(t)) for s, t in zip(springs, seconds) if s > 0 and t > 0]
    if len(pts) < 2:
        return math.nan
    x, y = zip(*pts)
    return float(np.polyfit(x, y, 1)[0])


def main(out_dir):
    rows = [r for r in read_csv(os.path.join(out_dir, "scaling.csv")) if r["status"] == "ok"]
    methods = list(dict.fromkeys(r["method"] for r in rows))
    threads = sorted({int(r["threads"]) for r in rows})
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    fits = []
    for m in methods:
        st = style(m, methods)
        for t in threads:
            # The size: springs for cloths, fluid particles for fluids (springs 0).
            pts = sorted((num(r["springs"]) or num(r["particles"]), num(r["iteration_s"]),
                          num(r["step_s"]),
                          num(r.get("factor_nnz") or "0"))
                         for r in rows if r["method"] == m and int(r["threads"]) == t)
            if not pts:
                continue
            s, it, step, fill = zip(*pts)
            ls = "-" if t == max(threads) else "--"
            label = f"{m}, {t} thread{'s' if t > 1 else ''}"
            axes[0].loglog(s, it, ls, label=label, **st)
            axes[1].loglog(s, step, ls, label=label, **st)
            fill_p = fit_exponent(s, fill) if all(f > 0 for f in fill) else math.nan
            fits.append((m, t, len(s), g3(s[0]), g3(s[-1]), g3(fit_exponent(s, it)), g3(it[-1]),
                         g3(fill_p)))
    axes[0].set_title("time per iteration (PCG / local-global iteration; a step otherwise)")
    axes[0].set_ylabel("seconds per iteration")
    axes[1].set_title("time per step (h = 0.01 s)")
    axes[1].set_ylabel("seconds per step")
    for ax in axes:
        ax.set_xlabel("springs (fluids: particles)")
    axes[1].legend(loc="upper left", ncol=1)
    fig.tight_layout()
    save_figure(fig, os.path.join(out_dir, "scaling.png"))
    md = ["Fitted exponent p of time per iteration ~ size^p, the size springs (cloths) or "
          "particles (fluids) (least squares, log-log):\n",
          markdown_table(["method", "threads", "sizes", "smallest", "largest", "exponent p",
                          "s / iteration at largest", "factor entries: exponent"], fits),
          "\nEvery run (seconds per step, split; peak resident memory of the run):\n",
          markdown_table(["method", "threads", "springs", "s/step", "iterations/step", "s/iteration",
                          "assembly", "factor", "solve", "local", "global", "peak MiB"],
                         [(r["method"], r["threads"], r["springs"], g3(num(r["step_s"])),
                           g3(num(r["iterations_per_step"])), g3(num(r["iteration_s"])),
                           g3(num(r["assembly_s"])), g3(num(r["factor_s"])), g3(num(r["solve_s"])),
                           g3(num(r["local_s"])), g3(num(r["global_s"])), g3(num(r["peak_mib"])))
                          for r in rows])]
    write_text(os.path.join(out_dir, "scaling.md"), "".join(md))


if __name__ == "__main__":
    main(sys.argv[1])
