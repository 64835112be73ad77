"""Plots the work-precision diagrams written by `hooke workprecision` (experiments/work_precision.cpp).

Usage: /usr/bin/python3 experiments/plot/work_precision.py OUT_DIR
Reads OUT_DIR/workprecision.csv and OUT_DIR/reference.csv; writes, per case,
OUT_DIR/workprecision_<case>.png (RMS position error at the final time and the largest over the
trajectory against wall time, log-log, one line per method through the points the reference
resolves, each point annotated with its h or rtol; the reference's own error estimate as a dotted
line, and the points below it, which it cannot resolve, as hollow triangles on that line rather
than as values) and OUT_DIR/workprecision_<case>.md (every run as a table row). Wall times are the
medians of the `repeats` runs the CSV records.
"""
import math
import os
import sys

from common import g3, markdown_table, num, plt, read_csv, save_figure, style, write_text


def main(out_dir):
    rows = read_csv(os.path.join(out_dir, "workprecision.csv"))
    refs = {r["case"]: r for r in read_csv(os.path.join(out_dir, "reference.csv"))}
    labels = [r["label"] for r in rows]
    for case in dict.fromkeys(r["case"] for r in rows):
        sub = [r for r in rows if r["case"] == case]
        ref = refs.get(case)
        fig, axes = plt.subplots(1, 2, figsize=(13, 4.8), sharey=True)
        for ax, col, what in ((axes[0], "rms_err_final", "at the final time"),
                              (axes[1], "rms_err_traj", "max over the trajectory")):
            resolved = "resolved_final" if col == "rms_err_final" else "resolved_traj"
            bound = math.nan
            if ref is not None:
                bound = num(ref["err_rms_final" if col == "rms_err_final" else "err_rms_traj"])
            marked = False
            for label in dict.fromkeys(r["label"] for r in sub):
                mine = [r for r in sub if r["label"] == label and num(r[col]) > 0]
                pts = [r for r in mine if r.get(resolved, "1") == "1"]
                below = [r for r in mine if r.get(resolved, "1") != "1"]
                st = style(label, labels)
                if pts:
                    ax.plot([num(r["wall_s"]) for r in pts], [num(r[col]) for r in pts], "-", lw=1.2,
                            ms=5, label=label, **st)
                    for r in pts:
                        tag = f"rtol {g3(num(r['rtol']))}" if num(r["rtol"]) > 0 else f"h {g3(num(r['h']))}"
                        ax.annotate(tag, (num(r["wall_s"]), num(r[col])), textcoords="offset points",
                                    xytext=(3, 2), fontsize=4.5, color=st.get("color", "k"))
                if below and bound > 0:
                    ax.plot([num(r["wall_s"]) for r in below], [bound] * len(below), ls="none",
                            marker="v", mfc="none", ms=6, color=st.get("color", "k"),
                            label=None if marked else "below the reference error (not resolved)")
                    marked = True
            if bound > 0:
                ax.axhline(bound, ls=":", color="k", lw=1, label="reference error estimate")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("wall time (s)")
            ax.set_title(f"{case}: RMS position error {what}")
        axes[0].set_ylabel("RMS position error vs reference (m)")
        axes[1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
        fig.tight_layout()
        save_figure(fig, os.path.join(out_dir, f"workprecision_{case}.png"))
        plt.close(fig)

        table = [[r["label"], g3(num(r["h"])), g3(num(r["rtol"])) if num(r["rtol"]) > 0 else "",
                  g3(num(r["wall_s"])), r["steps"], g3(num(r["rms_err_final"])), g3(num(r["max_err_final"])),
                  g3(num(r["rms_err_traj"])), r["status"],
                  r.get("repeats", ""), "yes" if r.get("resolved_final", "1") == "1" else "no"] for r in sub]
        text = "Reference: " + ref["how"] + "\n\n" if ref is not None else ""
        text += markdown_table(["method", "h (s)", "rtol", "wall (s)", "steps", "RMS err final (m)",
                                "max err final (m)", "RMS err traj (m)", "status", "runs (median wall)",
                                "final error above the reference's"], table)
        write_text(os.path.join(out_dir, f"workprecision_{case}.md"), text)
    print(f"work_precision.py: wrote {out_dir}/workprecision_*.png and workprecision_*.md")


if __name__ == "__main__":
    main(sys.argv[1])
