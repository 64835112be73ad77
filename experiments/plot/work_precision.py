"""Plots the work-precision diagrams written by `hooke workprecision` (experiments/studies/work_precision.cpp).

Usage: /usr/bin/python3 experiments/plot/work_precision.py OUT_DIR
Reads OUT_DIR/workprecision.csv and OUT_DIR/reference.csv; writes, per case,
OUT_DIR/workprecision_<case>.png and OUT_DIR/workprecision_<case>.md (every run as a table row).
The figure is one panel, error against wall time (log-log), one line per method through its RMS
position error at the final time; a whisker from each point rises to the largest RMS error over
the trajectory, so both measures are read at the same point (they were two panels that showed
the same ranking). Each point is annotated with its h or rtol. The reference's own error estimate
is a dotted line, and the points below it, which it cannot resolve, are hollow triangles on that
line rather than values. Wall times are the medians of the `repeats` runs the CSV records.

Per case with tolerance sweeps (CVODE, IDA, hooke's error-controlled methods), also
OUT_DIR/tolerance_<case>.png: is the error control honest? The largest position error over the
trajectory against the requested rtol, one line per method, beside the lines error = rtol and
error = 10 rtol (the cases' sizes are about 1 m, and atol = 1e-3 rtol x size); errors the
reference cannot resolve are left out.

Fluid cases (OUT_DIR/fluid.csv, the dam break by WCSPH over its speed of sound and IISPH and DFSPH
over their tolerance): OUT_DIR/fluid_<case>.png, wall time against the time-averaged mean density
error, one line per method, each point annotated with its c0 or tolerance and its surge-front speed
over the experiment's; and OUT_DIR/fluid_<case>.md, every run as a table row and, at each IISPH or
DFSPH point whose density error WCSPH's sweep spans, WCSPH's wall time there (log-log
interpolation) over the point's.
OUT_DIR/front.png (from OUT_DIR/fronts.csv): the surge front Z = x / a against T = t sqrt(2 g / a)
of WCSPH at c0 = 31.3 m/s and IISPH at tolerance 1e-3 (the shipped scene's settings) for every
fluid case (resolution), beside Martin and Moyce's and Koshizuka and Oka's experiments.
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
        fig, ax = plt.subplots(figsize=(9.5, 5.6))
        bound = num(ref["err_rms_final"]) if ref is not None else math.nan
        bound_traj = num(ref["err_rms_traj"]) if ref is not None else math.nan
        marked = False
        for label in dict.fromkeys(r["label"] for r in sub):
            mine = [r for r in sub if r["label"] == label and num(r["rms_err_final"]) > 0]
            pts = [r for r in mine if r.get("resolved_final", "1") == "1"]
            below = [r for r in mine if r.get("resolved_final", "1") != "1"]
            st = style(label, labels)
            colour = st.get("color", "k")
            if pts:
                ax.plot([num(r["wall_s"]) for r in pts], [num(r["rms_err_final"]) for r in pts],
                        "-", lw=1.2, ms=5, label=label, **st)
                for r in pts:
                    w, e = num(r["wall_s"]), num(r["rms_err_final"])
                    tag = f"rtol {g3(num(r['rtol']))}" if num(r["rtol"]) > 0 else f"h {g3(num(r['h']))}"
                    ax.annotate(tag, (w, e), textcoords="offset points", xytext=(3, -7),
                                fontsize=4.5, color=colour)
            # Whiskers: final error (or the reference bound, where unresolved) up to the
            # trajectory's largest error, where the reference resolves that.
            for r in mine:
                traj = num(r["rms_err_traj"])
                if r.get("resolved_traj", "1") != "1" or not traj > 0:
                    continue
                lo = num(r["rms_err_final"]) if r in pts else bound
                if lo > 0 and traj > lo:
                    ax.plot([num(r["wall_s"])] * 2, [lo, traj], "-", color=colour, lw=0.6,
                            alpha=0.6)
                    ax.plot(num(r["wall_s"]), traj, "_", color=colour, ms=5, mew=0.8)
            if below and bound > 0:
                ax.plot([num(r["wall_s"]) for r in below], [bound] * len(below), ls="none",
                        marker="v", mfc="none", ms=6, color=colour,
                        label=None if marked else "final error below the reference's (not resolved)")
                marked = True
        if bound > 0:
            ax.axhline(bound, ls=":", color="k", lw=1, label="reference error estimate (final)")
        if bound_traj > 0 and not math.isclose(bound_traj, bound, rel_tol=0.1):
            ax.axhline(bound_traj, ls=":", color="0.5", lw=1,
                       label="reference error estimate (trajectory)")
        ax.plot([], [], "-", color="0.3", lw=0.6, label="whisker: largest error over the trajectory")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time (s), median of the repeats")
        ax.set_ylabel("RMS position error vs reference (m)")
        ax.set_title(f"{case}: RMS position error at the final time (points) and over the "
                     "trajectory (whiskers)")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
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
        plot_tolerance(out_dir, case, sub, labels)
    print(f"work_precision.py: wrote {out_dir}/workprecision_*.png and workprecision_*.md")
    plot_fluid(out_dir)


def interpolate_loglog(points, x):
    """y at x on the log-log polyline through (x, y) points (None outside their span)."""
    pts = sorted(p for p in points if p[0] > 0 and p[1] > 0)
    for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
        if x0 <= x <= x1:
            if x1 == x0:
                return y0
            w = (math.log(x) - math.log(x0)) / (math.log(x1) - math.log(x0))
            return math.exp(math.log(y0) + w * (math.log(y1) - math.log(y0)))
    return None


def plot_fluid(out_dir):
    path = os.path.join(out_dir, "fluid.csv")
    rows = read_csv(path) if os.path.exists(path) else []
    labels = [r["method"] for r in rows]
    for case in dict.fromkeys(r["case"] for r in rows):
        sub = [r for r in rows if r["case"] == case and r["status"] == "ok"]
        fig, ax = plt.subplots(figsize=(8.5, 5.2))
        for method in dict.fromkeys(r["method"] for r in sub):
            mine = [r for r in sub if r["method"] == method]
            st = style(method, labels)
            ax.plot([num(r["mean_density_error"]) for r in mine], [num(r["wall_s"]) for r in mine],
                    "-", lw=1.2, ms=5, label=f"{method} (over {mine[0]['parameter']})", **st)
            for r in mine:
                tag = (f"c0 {g3(num(r['value']))}" if r["parameter"] == "sound_speed"
                       else f"tol {g3(num(r['value']))}")
                ax.annotate(f"{tag}, front x{num(r['front_speed_ratio']):.3f}",
                            (num(r["mean_density_error"]), num(r["wall_s"])),
                            textcoords="offset points", xytext=(4, 3), fontsize=5,
                            color=st.get("color", "k"))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("mean density error (time average of mean max(rho - rho0, 0) / rho0)")
        ax.set_ylabel("wall time (s), median of the repeats")
        ax.set_title(f"{case}: wall time against density error "
                     "(labels: parameter, surge-front speed / Martin and Moyce's)")
        ax.legend(loc="upper right")
        fig.tight_layout()
        save_figure(fig, os.path.join(out_dir, f"fluid_{case}.png"))
        plt.close(fig)

        table = [[r["method"], r["parameter"], g3(num(r["value"])), g3(num(r["wall_s"])), r["steps"],
                  r["substeps"], g3(num(r["particle_steps_per_s"])),
                  g3(num(r["mean_density_error"])), g3(num(r["max_density_error"])),
                  g3(num(r["pressure_iterations_per_substep"])), f"{num(r['front_speed_ratio']):.3f}",
                  f"{num(r['lead_min']):.2f}..{num(r['lead_max']):.2f}", r["status"]]
                 for r in rows if r["case"] == case]
        text = markdown_table(["method", "parameter", "value", "wall (s)", "steps", "substeps",
                               "particle-steps/s", "mean density error", "max density error",
                               "pressure iterations / substep", "front speed / MM52",
                               "lead in T", "status"], table)
        wc = [(num(r["mean_density_error"]), num(r["wall_s"])) for r in sub if r["method"] == "wcsph"]
        matched = []
        for r in sub:
            if r["method"] not in ("iisph", "dfsph"):
                continue
            e, w = num(r["mean_density_error"]), num(r["wall_s"])
            w_wc = interpolate_loglog(wc, e)
            if w_wc is not None and w > 0:
                matched.append([r["method"], g3(num(r["value"])), g3(e), g3(w), g3(w_wc),
                                f"{w_wc / w:.2f}"])
        if matched:
            text += ("\nAt matched mean density error, WCSPH's wall time (interpolated on its c0 "
                     "sweep) over the implicit method's:\n\n")
            text += markdown_table(["method", "tolerance", "mean density error", "wall (s)",
                                    "WCSPH wall (s)", "WCSPH / method"], matched)
        write_text(os.path.join(out_dir, f"fluid_{case}.md"), text)
    if rows:
        print(f"work_precision.py: wrote {out_dir}/fluid_*.png and fluid_*.md")
    plot_fronts(out_dir)


def plot_fronts(out_dir):
    path = os.path.join(out_dir, "fronts.csv")
    rows = read_csv(path) if os.path.exists(path) else []
    if not rows:
        return
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    shown = set()
    for source, marker in (("MM52", "o"), ("KO96", "s")):
        pts = [r for r in rows if r["label"] == source]
        first = pts[:len({r["T"] for r in pts})]  # the same points are written per case
        if first:
            ax.plot([num(r["T"]) for r in first], [num(r["Z"]) for r in first], marker, mfc="none",
                    color="k" if source == "MM52" else "0.5", ms=5, ls="none",
                    label={"MM52": "Martin and Moyce 1952 (a = 2 1/4 in)",
                           "KO96": "Koshizuka and Oka 1996"}[source])
    cases = list(dict.fromkeys(r["case"] for r in rows))
    runs = ["wcsph-31.3", "iisph-0.001"]
    labels = [f"{c} {m}" for c in cases for m in runs]
    for case in cases:
        for run in runs:
            pts = [r for r in rows if r["case"] == case and r["label"] == run]
            if not pts or (case, run) in shown:
                continue
            shown.add((case, run))
            st = style(f"{case} {run}", labels)
            st.pop("marker", None)
            ax.plot([num(r["T"]) for r in pts], [num(r["Z"]) for r in pts], "-", lw=1.3,
                    label=f"{run.split('-')[0].upper()}, {case}", **st)
    ax.set_xlim(0, 3.6)
    ax.set_ylim(1, 4.2)
    ax.axvspan(1.4, 3.0, color="0.93", zorder=0, label="front speed compared over 1.4 <= T <= 3")
    ax.set_xlabel("T = t sqrt(2 g / a)")
    ax.set_ylabel("Z = x_front / a")
    ax.set_title("Dam break (n^2 = 2): surge front against the experiments")
    ax.legend(loc="upper left", fontsize=7)
    fig.tight_layout()
    save_figure(fig, os.path.join(out_dir, "front.png"))
    plt.close(fig)
    print(f"work_precision.py: wrote {out_dir}/front.png")


def plot_tolerance(out_dir, case, sub, labels):
    """Achieved error against requested tolerance for the rows of a tolerance sweep."""
    # Errors below the reference's own (resolved_traj 0) are not values: left out.
    swept = [r for r in sub if num(r["rtol"]) > 0 and num(r["max_err_traj"]) > 0
             and r.get("resolved_traj", "1") == "1"]
    if not swept:
        return
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    for label in dict.fromkeys(r["label"] for r in swept):
        mine = sorted((r for r in swept if r["label"] == label), key=lambda r: num(r["rtol"]))
        ax.plot([num(r["rtol"]) for r in mine], [num(r["max_err_traj"]) for r in mine], "-",
                lw=1.2, ms=5, label=label, **style(label, labels))
    rtols = sorted({num(r["rtol"]) for r in swept})
    ax.plot(rtols, rtols, ls="--", color="k", lw=0.8, label="error = rtol (x 1 m)")
    ax.plot(rtols, [10 * r for r in rtols], ls=":", color="k", lw=0.8, label="error = 10 rtol")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("requested rtol (atol = 1e-3 rtol x the scene's size)")
    ax.set_ylabel("largest position error over the trajectory (m)")
    ax.set_title(f"{case}: achieved error against requested tolerance")
    ax.legend(loc="upper left", fontsize=7)
    fig.tight_layout()
    save_figure(fig, os.path.join(out_dir, f"tolerance_{case}.png"))
    plt.close(fig)


if __name__ == "__main__":
    main(sys.argv[1])
