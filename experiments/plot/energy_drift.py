"""Plots the energy study written by `hooke energy` (experiments/studies/energy_drift.cpp).

Usage: /usr/bin/python3 experiments/plot/energy_drift.py OUT_DIR
Reads OUT_DIR/energy.csv and OUT_DIR/energy_summary.csv; writes OUT_DIR/energy.png and
OUT_DIR/energy.md. The figure has two panels over simulated time: the relative energy error
(E - E0) / scale on a symmetric-log axis, so that a method that gains energy (up), one that loses
it (down) and one that keeps it bounded near zero are told apart on one scale; and its magnitude
|E - E0| / scale on a log axis. One line per method; the table lists the final error, the largest
magnitude, the drift per period of the fastest mode and the wall time.
"""
import os
import sys

from common import g3, markdown_table, num, plt, read_csv, save_figure, style, write_text


def main(out_dir):
    rows = read_csv(os.path.join(out_dir, "energy.csv"))
    summary = read_csv(os.path.join(out_dir, "energy_summary.csv"))
    labels = [r["label"] for r in summary]
    fig, (ax, ax_abs) = plt.subplots(1, 2, figsize=(12.5, 5.0))
    floor = 1e-12
    for label in labels:
        mine = [r for r in rows if r["label"] == label]
        if not mine:
            continue
        t = [num(r["t"]) for r in mine]
        e = [num(r["relative_energy_error"]) for r in mine]
        st = style(label, labels)
        ax.plot(t, e, "-", lw=1.0, label=label, color=st["color"])
        ax_abs.plot(t, [max(abs(x), floor) for x in e], "-", lw=1.0, label=label,
                    color=st["color"])
    ax.set_yscale("symlog", linthresh=1e-6)
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel("(E - E0) / energy scale")
    ax.set_title("energy error (symmetric log; up: gains energy)")
    ax_abs.set_yscale("log")
    ax_abs.set_xlabel("simulated time (s)")
    ax_abs.set_ylabel("|E - E0| / energy scale")
    ax_abs.set_title("its magnitude")
    ax_abs.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.suptitle("chain without dampers (conservative), h = 1e-3 s")
    fig.tight_layout()
    save_figure(fig, os.path.join(out_dir, "energy.png"))
    plt.close(fig)
    table = [[r["label"], g3(num(r["periods"])), g3(num(r["final_error"])),
              g3(num(r["max_abs_error"])), g3(num(r["drift_per_period"])), g3(num(r["wall_s"])),
              r["status"]] for r in summary]
    write_text(os.path.join(out_dir, "energy.md"),
               markdown_table(["method", "periods", "final (E - E0) / scale", "max |E - E0| / scale",
                               "drift per period", "wall (s)", "status"], table))
    print(f"energy_drift.py: wrote {out_dir}/energy.png and energy.md")


if __name__ == "__main__":
    main(sys.argv[1])
