"""Plots the stability map written by `hooke stability` (see experiments/studies/stability_map.cpp).

Usage: /usr/bin/python3 experiments/plot/stability.py OUT_DIR
Reads OUT_DIR/stability.csv; writes, per case, OUT_DIR/stability_<case>.png (largest stable h
against k, log-log, one line per method, the theoretical explicit limits y / omega_max dashed; for
a fluid case k is the speed of sound c0 and the dashed line the CFL step) and
OUT_DIR/stability_<case>.md (the same numbers as a table: k across, methods down).
"""
import math
import os
import sys
import textwrap

from common import g3, markdown_table, num, plt, read_csv, save_figure, style, write_text


def main(out_dir):
    rows = read_csv(os.path.join(out_dir, "stability.csv"))
    labels = [r["label"] for r in rows]
    for case in dict.fromkeys(r["case"] for r in rows):
        sub = [r for r in rows if r["case"] == case]
        # What k is (stability.csv's parameter column): a stiffness, or a fluid's speed of sound.
        parameter = sub[0].get("parameter") or "k (N/m)"
        fluid = parameter.startswith("c0")
        fig, ax = plt.subplots(figsize=(10, 5.5))
        order = list(dict.fromkeys(r["label"] for r in sub))
        h_lo = min((num(r["h_unstable"]) for r in sub if num(r["h_unstable"]) > 0), default=1e-5)
        always = [lab for lab in order if all(r["bound"] == "above" for r in sub if r["label"] == lab)]
        for label in order:
            if label in always:
                continue
            pts = [r for r in sub if r["label"] == label]
            k = [num(r["k"]) for r in pts]
            h = [num(r["h_stable"]) if num(r["h_stable"]) > 0 else math.nan for r in pts]
            st = style(label, labels)
            explicit = any(num(r["h_theory"]) >= 0 for r in pts)
            # Explicit methods: large hollow markers; others: small filled ones, so that curves
            # that coincide (implicit-b0 and symplectic-euler) both stay visible.
            ax.plot(k, h, "-", lw=1.2, ms=9 if explicit else 4, mfc="none" if explicit else st["color"],
                    label=label, **st)
            # Censored points: stable at the largest h tried (triangle up), unstable at the smallest.
            for r in pts:
                if r["bound"] == "above":
                    ax.plot(num(r["k"]), num(r["h_stable"]), marker="^", ms=10, mfc="none", color=st["color"])
                if r["bound"] == "below":
                    ax.plot(num(r["k"]), num(r["h_unstable"]) / 2, marker="v", ms=10, mfc="none", color=st["color"])
            theory = [num(r["h_theory"]) for r in pts]
            if any(t > 0 for t in theory):
                what = "CFL 0.4 dx / (c0 + v)" if fluid else "theory y / omega_max"
                ax.plot(k, [t if t > 0 else math.nan for t in theory], "--", lw=2.2, alpha=0.55,
                        color=st["color"], label=f"{label}: {what}")
        h_max = max(num(r["h_stable"]) for r in sub)
        ax.axhline(h_max, color="0.5", lw=0.8, ls=":")
        note = ""
        if always:  # below the axes, never over the data
            note = ("Stable at h = " + g3(h_max) + " s (the largest tried) for every k, so not drawn: "
                    + ", ".join(always))
            fig.text(0.01, 0.01, "\n".join(textwrap.wrap(note, 160)), fontsize=7, ha="left", va="bottom")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("speed of sound " + parameter if fluid else "stiffness " + parameter)
        ax.set_ylabel("largest stable time step h (s)")
        ax.set_title(f"Stability map: {case}  (hollow triangles: stable at the largest / unstable at the smallest h tried)",
                     fontsize=9)
        ax.set_ylim(bottom=min(h_lo / 3, 1e-5), top=h_max * 3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
        fig.tight_layout(rect=(0, 0.06 if note else 0, 1, 1))
        save_figure(fig, os.path.join(out_dir, f"stability_{case}.png"))
        plt.close(fig)

        ks = list(dict.fromkeys(r["k"] for r in sub))
        table = []
        for label in order:
            cells = []
            for kk in ks:
                r = next((x for x in sub if x["label"] == label and x["k"] == kk), None)
                if r is None:
                    cells.append("")
                elif r["bound"] == "above":
                    cells.append(">= " + g3(num(r["h_stable"])))
                elif r["bound"] == "below":
                    cells.append("< " + g3(num(r["h_unstable"])))
                else:
                    t = num(r["h_theory"])
                    cells.append(g3(num(r["h_stable"])) + (f" ({g3(t)})" if t > 0 else ""))
            table.append([label] + cells)
        if not fluid:  # a fluid has no natural frequency: its limit is the CFL step (in brackets)
            omega = [g3(num(next(x for x in sub if x["k"] == kk)["omega_max"])) for kk in ks]
            table.append(["omega_max (rad/s)"] + omega)
        write_text(os.path.join(out_dir, f"stability_{case}.md"),
                   markdown_table([f"method \\ {parameter}"] + [g3(num(kk)) for kk in ks], table))
    print(f"stability.py: wrote {out_dir}/stability_*.png and stability_*.md")


if __name__ == "__main__":
    main(sys.argv[1])
