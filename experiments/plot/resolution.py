"""Plots the resolution study written by `hooke resolution` (experiments/studies/resolution_study.cpp).

Usage: /usr/bin/python3 experiments/plot/resolution.py OUT_DIR
Reads OUT_DIR/resolution.csv (and OUT_DIR/cantilever.csv if there); writes OUT_DIR/resolution.png
(static sag of the centre of mass and first swing period against the grid size n, one line per
scaling rule, log2 x axis) and OUT_DIR/resolution.md (the same numbers as a table, and the
cantilevers' sags against beam theory).
"""
import os
import sys

from common import g3, markdown_table, num, plt, read_csv, save_figure, style, write_text


def main(out_dir):
    rows = read_csv(os.path.join(out_dir, "resolution.csv"))
    variants = list(dict.fromkeys(r["variant"] for r in rows))
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    # Line style and marker size differ per variant so that coinciding curves (unscaled and
    # membrane have the same static sag) both stay visible.
    looks = [("-", 11, "none"), ("--", 6, None), (":", 6, None)]
    for i, v in enumerate(variants):
        pts = [r for r in rows if r["variant"] == v]
        n = [num(r["n"]) for r in pts]
        st = style(v, variants)
        ls, ms, mfc = looks[i % len(looks)]
        kw = dict(label=v, ms=ms, lw=1.6, **st)
        if mfc:
            kw["mfc"] = mfc
        axes[0].plot(n, [num(r["sag_com_m"]) for r in pts], ls, **kw)
        axes[1].plot(n, [num(r["period_s"]) for r in pts], ls, **kw)
        missing = [r["n"] for r in pts if not num(r["period_s"]) > 0]
        if missing:
            axes[1].text(0.02, 0.02 + 0.06 * i, f"{v}: no swing found at n = {', '.join(missing)} (over-damped)",
                         transform=axes[1].transAxes, fontsize=7)
    for ax, ylabel, title in ((axes[0], "static sag of the centre of mass (m)", "Static sag"),
                              (axes[1], "first swing period (s)", "First swing period")):
        ax.set_xscale("log", base=2)
        ax.set_xticks(sorted({num(r["n"]) for r in rows}))
        ax.get_xaxis().set_major_formatter(plt.matplotlib.ticker.ScalarFormatter())
        ax.set_xlabel("grid size n (n x n particles)")
        ax.set_ylabel(ylabel)
        ax.set_title(title + " against resolution")
        ax.legend()
    fig.tight_layout()
    save_figure(fig, os.path.join(out_dir, "resolution.png"))
    plt.close(fig)
    table = [[r["variant"], r["n"], r["particles"], g3(num(r["k_structural"])), g3(num(r["drag"])),
              g3(num(r["sag_com_m"])), g3(num(r["sag_lowest_m"])), g3(num(r["period_s"])), g3(num(r["wall_s"]))]
             for r in rows]
    text = markdown_table(["variant", "n", "particles", "k structural (N/m)", "drag (kg/s per particle)",
                           "sag CoM (m)", "sag lowest (m)", "period (s)", "wall (s)"], table)
    cantilever = os.path.join(out_dir, "cantilever.csv")
    if os.path.exists(cantilever):
        crows = read_csv(cantilever)
        ctable = [[r["mesh"], r["model"], r["diagonals"] or "-", r["n_along"], r["particles"], g3(num(r["sag_m"])),
                   g3(num(r["beam_m"])), "%+.2e" % (num(r["ratio"]) - 1.0), g3(num(r["wall_s"]))] for r in crows]
        text += ("\nBending cantilevers (cantilever.csv): the settled tip sag against the Euler-Bernoulli beam of "
                 "the same rigidity.\n\n" +
                 markdown_table(["mesh", "model", "diagonals", "n along", "particles", "tip sag (m)", "beam (m)",
                                 "sag / beam - 1", "wall (s)"], ctable))
    write_text(os.path.join(out_dir, "resolution.md"), text)
    print(f"resolution.py: wrote {out_dir}/resolution.png and resolution.md")


if __name__ == "__main__":
    main(sys.argv[1])
