"""Assembles the paper from its source and the experiments' output.

Usage: /usr/bin/python3 paper/assemble.py paper/paper.md OUT
Writes OUT/findings_*.md (key numbers derived from the CSV files the experiments wrote) and
OUT/paper.md, in which every line `<!-- include FILE -->` of the source is replaced by OUT/FILE.
Nothing in the paper's tables is typed by hand: a missing file is an error.
"""
import math
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "experiments", "plot"))
from common import g3, markdown_table, num, read_csv  # noqa: E402


def stability_findings(out):
    rows = read_csv(os.path.join(out, "stability", "stability.csv"))
    table = []
    for case in dict.fromkeys(r["case"] for r in rows):
        for label in dict.fromkeys(r["label"] for r in rows if r["case"] == case):
            ratios = [num(r["h_stable"]) / num(r["h_theory"]) for r in rows
                      if r["case"] == case and r["label"] == label and r["bound"] == "bracketed"
                      and num(r["h_theory"]) > 0]
            if ratios:
                table.append([case, label, len(ratios), g3(min(ratios)), g3(sorted(ratios)[len(ratios) // 2]),
                              g3(max(ratios))])
    text = markdown_table(["case", "method", "k values", "min h/h_theory", "median", "max"], table)
    # Implicit methods the linear theory calls unconditionally stable (not beta < 1/2) that still
    # failed at some step: where, and why (the first failure's message).
    odd = []
    for r in rows:
        m = re.fullmatch(r"implicit-b([0-9.]+)", r["label"])
        if num(r["h_theory"]) == num(r["h_theory"]) or (m and float(m.group(1)) < 0.5) or r["bound"] != "bracketed":
            continue
        odd.append([r["case"], r["label"], g3(num(r["k"])), g3(num(r["h_stable"])), g3(num(r["h_unstable"])),
                    r["reason"][:110]])
    if odd:
        text += ("\nRuns of methods that are unconditionally stable in the linear theory, which failed at some "
                 "step all the same (h unstable), with the reason of the failure:\n\n")
        text += markdown_table(["case", "method", "k (N/m)", "h stable (s)", "h unstable (s)", "reason"], odd)
    # beta < 1/2 against the linear theory y = 2 / sqrt(1 - 2 beta) on the two-particle spring.
    beta_rows = []
    for r in rows:
        m = re.fullmatch(r"implicit-b([0-9.]+)", r["label"])
        if r["case"] == "two_particle" and m and float(m.group(1)) < 0.5 and r["bound"] == "bracketed":
            y = 2.0 / math.sqrt(1.0 - 2.0 * float(m.group(1)))
            beta_rows.append([r["label"], g3(num(r["k"])), g3(num(r["h_stable"])),
                              g3(y / num(r["omega_max"])), g3(num(r["h_stable"]) * num(r["omega_max"]) / y)])
    if beta_rows:
        text += "\nThe beta scheme with one Newton step on the linear spring, against y = 2 / sqrt(1 - 2 beta):\n\n"
        text += markdown_table(["method", "k (N/m)", "h measured (s)", "h theory (s)", "ratio"], beta_rows)
    with open(os.path.join(out, "findings_stability.md"), "w") as f:
        f.write(text)


def work_precision_findings(out):
    rows = read_csv(os.path.join(out, "workprecision", "workprecision.csv"))
    table = []
    for case in dict.fromkeys(r["case"] for r in rows):
        for label in dict.fromkeys(r["label"] for r in rows if r["case"] == case):
            # Only errors the reference resolves (above its own error estimate) are values.
            pts = [r for r in rows if r["case"] == case and r["label"] == label and num(r["rms_err_final"]) > 0
                   and r.get("resolved_final", "1") == "1"]
            order = "-"
            if len(pts) >= 2 and num(pts[0]["rtol"]) == 0:
                xs = [math.log(num(r["h"])) for r in pts]
                ys = [math.log(num(r["rms_err_final"])) for r in pts]
                mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
                sxx = sum((x - mx) ** 2 for x in xs)
                if sxx > 0:
                    order = g3(sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx)
            best = {}
            for tol in (1e-3, 1e-6):
                ok = [r for r in pts if num(r["rms_err_final"]) <= tol]
                best[tol] = g3(min(num(r["wall_s"]) for r in ok)) if ok else "-"
            stable = sum(1 for r in rows if r["case"] == case and r["label"] == label and r["status"] != "" and
                         not r["status"].startswith("diverged") and not r["status"].startswith("failed"))
            total = sum(1 for r in rows if r["case"] == case and r["label"] == label)
            table.append([case, label, f"{stable}/{total}", order, best[1e-3], best[1e-6]])
    with open(os.path.join(out, "findings_workprecision.md"), "w") as f:
        f.write(markdown_table(["case", "method", "runs completed", "fitted order (final error vs h)",
                                "wall (s) to reach 1e-3 m", "wall (s) to reach 1e-6 m"], table))


def tolerance_findings(out):
    """Achieved error over requested tolerance for every run swept over rtol, over each case's
    own time (workprecision/) and over 2 s (tolerance-2s/): the largest position error over the
    trajectory divided by rtol (the cases' sizes are about 1 m)."""
    runs = {}
    for folder, span in (("workprecision", "case's own"), ("tolerance-2s", "2 s")):
        for r in read_csv(os.path.join(out, folder, "workprecision.csv")):
            if num(r["rtol"]) > 0:
                resolved = r.get("resolved_traj", "1") == "1" and num(r["max_err_traj"]) > 0
                runs[(r["case"], r["label"], r["rtol"], span)] = (
                    g3(num(r["max_err_traj"]) / num(r["rtol"])) if resolved else "below ref.")
    table = []
    for case, label, rtol in dict.fromkeys((c, l, t) for c, l, t, _ in runs):
        table.append([case, label, rtol, runs.get((case, label, rtol, "case's own"), "-"),
                      runs.get((case, label, rtol, "2 s"), "-")])
    with open(os.path.join(out, "findings_tolerance.md"), "w") as f:
        f.write(markdown_table(["case", "method", "rtol", "max error / rtol, case's own time",
                                "max error / rtol, 2 s"], table))


def resolution_findings(out):
    rows = read_csv(os.path.join(out, "resolution", "resolution.csv"))
    table = []
    for v in dict.fromkeys(r["variant"] for r in rows):
        pts = [r for r in rows if r["variant"] == v]
        sags = [num(r["sag_com_m"]) for r in pts if num(r["sag_com_m"]) > 0]
        per = [num(r["period_s"]) for r in pts if num(r["period_s"]) > 0]

        def spread(xs):
            return g3(max(xs) / min(xs) - 1) if xs else "-"
        table.append([v, ", ".join(r["n"] for r in pts), g3(min(sags)) if sags else "-", g3(max(sags)) if sags else "-",
                      spread(sags), spread(per)])
    with open(os.path.join(out, "findings_resolution.md"), "w") as f:
        f.write(markdown_table(["variant", "n", "smallest sag (m)", "largest sag (m)", "sag max/min - 1",
                                "period max/min - 1"], table))


def bending_findings(out):
    """The cantilevers against beam theory (resolution/cantilever.csv) and the explicit step limit
    under strand bending against the spacing (stability/stability.csv, cases bending_strand_N)."""
    rows = read_csv(os.path.join(out, "resolution", "cantilever.csv"))
    table = []
    for key in dict.fromkeys((r["mesh"], r["model"], r["diagonals"]) for r in rows):
        pts = [r for r in rows if (r["mesh"], r["model"], r["diagonals"]) == key]
        devs = [num(r["ratio"]) - 1.0 for r in pts]
        order = "-"
        if len(pts) >= 2 and devs[-1] != 0 and devs[-2] / devs[-1] > 0:
            spacing = (num(pts[-1]["n_along"]) - 1) / (num(pts[-2]["n_along"]) - 1)
            order = g3(math.log(devs[-2] / devs[-1]) / math.log(spacing))
        table.append([key[0], key[1], key[2] or "-", ", ".join(r["n_along"] for r in pts),
                      ", ".join("%+.2e" % d for d in devs), order])
    text = markdown_table(["mesh", "model", "diagonals", "particles along", "tip sag / beam - 1",
                           "order (last two)"], table)
    stab = [r for r in read_csv(os.path.join(out, "stability", "stability.csv"))
            if re.fullmatch(r"bending_strand_[0-9]+", r["case"]) and r["bound"] == "bracketed"]
    slopes = []
    for label in dict.fromkeys(r["label"] for r in stab):
        by_n = {}
        for r in stab:
            if r["label"] == label:
                by_n.setdefault(int(r["case"].rsplit("_", 1)[1]), {})[r["k"]] = num(r["h_stable"])
        ns = sorted(by_n)
        for a, b in zip(ns, ns[1:]):
            common = [k for k in by_n[a] if k in by_n[b]]
            fits = [math.log(by_n[a][k] / by_n[b][k]) / math.log((b - 1) / (a - 1)) for k in common]
            if fits:
                slopes.append([label, f"{a} -> {b}", len(fits), g3(min(fits)), g3(max(fits))])
    if slopes:
        text += ("\nThe largest stable step under strand bending against the spacing: the slope of log h over "
                 "log spacing between two strands at the same EI (2 for a limit set by bending):\n\n" +
                 markdown_table(["method", "particles", "EI values", "slope min", "slope max"], slopes))
    with open(os.path.join(out, "findings_bending.md"), "w") as f:
        f.write(text)


def dips_findings(out):
    """The single-k dips runs of build.sh: the largest spring strain and total energy over each."""
    table = []
    for k in ("1e3", "1e4", "1e5"):
        for beta in ("0.5", "1"):
            run = os.path.join(out, "dips", f"k{k}-beta{beta}")
            rows = read_csv(os.path.join(run, "log.csv"))
            finished = os.path.exists(os.path.join(run, "final.csv"))
            table.append([k, "1/2" if beta == "0.5" else "1 (backward Euler)",
                          g3(max(num(r["max_strain"]) for r in rows)),
                          g3(max(num(r["total"]) for r in rows)),
                          "finished" if finished else f"stopped at t = {g3(num(rows[-1]['t']))} s"])
    text = markdown_table(["k (N/m)", "beta", "largest strain", "largest total energy (J)", "run"], table)
    with open(os.path.join(out, "findings_dips.md"), "w") as f:
        f.write(text)


def timings(out):
    rows = read_csv(os.path.join(out, "timings.csv"))
    with open(os.path.join(out, "timings.md"), "w") as f:
        f.write(markdown_table(["command", "wall time (s)"], [[f"`hooke {r['experiment']}`", g3(num(r["seconds"]))]
                                                              for r in rows]))


# The network the projection assumes (a commodity cluster, stated in the paper): per message
# latency and bandwidth of one node's link, and the time of one global reduction per tree level.
NET_LATENCY_S = 2e-6
NET_BANDWIDTH_B_PER_S = 12.5e9  # 100 Gb/s
PROJECT_SPRINGS = 1e8
PROJECT_NODES = 64


def mpi_findings(out):
    """Strong scaling 1 -> 2 processes and the communication model, projected to PROJECT_NODES
    nodes for a cloth of PROJECT_SPRINGS springs (scaling-mpi/scaling.csv)."""
    rows = [r for r in read_csv(os.path.join(out, "scaling-mpi", "scaling.csv")) if r["status"] == "ok"]
    table = []
    for m in dict.fromkeys(r["method"].rsplit(" x", 1)[0] for r in rows):
        one = {int(r["springs"]): r for r in rows if r["method"] == m + " x1"}
        two = {int(r["springs"]): r for r in rows if r["method"] == m + " x2"}
        for s in sorted(set(one) & set(two)):
            side = round(math.sqrt(int(two[s]["particles"])))
            table.append([m, s, g3(num(one[s]["step_s"])), g3(num(two[s]["step_s"])),
                          g3(num(one[s]["step_s"]) / num(two[s]["step_s"])), two[s]["ghosts"],
                          4 * side, two[s]["exchange_bytes"]])
    text = markdown_table(["method", "springs", "s/step, 1 process", "2 processes", "speed-up",
                           "ghosts (measured)", "ghosts (model: 4 side)", "bytes per exchange"], table)
    # Projection: a square cloth of PROJECT_SPRINGS springs (6 per particle) in strips over
    # PROJECT_NODES processes; compute time from the 1-process rate per spring at the largest size.
    n = PROJECT_SPRINGS / 6.0
    side = math.sqrt(n)
    proj = []
    for m in dict.fromkeys(r["method"].rsplit(" x", 1)[0] for r in rows):
        ones = sorted((int(r["springs"]), r) for r in rows if r["method"] == m + " x1")
        if not ones:
            continue
        springs, r = ones[-1]
        per_iteration = num(r["iteration_s"]) / springs  # s per spring and iteration
        compute = per_iteration * PROJECT_SPRINGS / PROJECT_NODES
        ghost_bytes = 4 * side * 24  # an interior strip: two rows above, two below
        exchange = 2 * NET_LATENCY_S + ghost_bytes / NET_BANDWIDTH_B_PER_S
        # A CG iteration adds two global reductions (log2 P tree levels each).
        reductions = 2 * math.log2(PROJECT_NODES) * NET_LATENCY_S if m.startswith("implicit") else 0.0
        comm = exchange + reductions
        proj.append([m, g3(compute), g3(ghost_bytes), g3(comm), g3(comm / compute)])
    text += ("\n\nProjected to %d nodes (one process each) for a cloth of %s springs (%s x %s particles, "
             "strips of the particle order), per iteration (a step for symplectic Euler, a CG iteration "
             "for backward Euler, whose multigrid cycle's own messages are not modelled), with %g s "
             "latency and %g GB/s per link:\n\n" % (PROJECT_NODES, g3(PROJECT_SPRINGS), g3(side), g3(side),
                                                    NET_LATENCY_S, NET_BANDWIDTH_B_PER_S / 1e9))
    text += markdown_table(["method", "compute per process (s)", "ghost bytes per exchange",
                            "communication (s)", "communication / compute"], proj)
    with open(os.path.join(out, "findings_mpi.md"), "w") as f:
        f.write(text + "\n")


def main(source, out):
    stability_findings(out)
    mpi_findings(out)
    work_precision_findings(out)
    tolerance_findings(out)
    resolution_findings(out)
    bending_findings(out)
    dips_findings(out)
    timings(out)
    lines = []
    with open(source) as f:
        for line in f:
            m = re.fullmatch(r"\s*<!-- include (\S+) -->\s*", line)
            if m:
                path = os.path.join(out, m.group(1))
                if not os.path.exists(path):
                    sys.exit(f"assemble.py: {source}: includes {path}, which the experiments did not write")
                with open(path) as inc:
                    lines.append(inc.read().rstrip("\n") + "\n")
            else:
                for img in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", line):
                    if not os.path.exists(os.path.join(out, img)):
                        sys.exit(f"assemble.py: {source}: figure {img} was not written into {out}")
                lines.append(line)
    with open(os.path.join(out, "paper.md"), "w") as f:
        f.writelines(lines)
    print(f"assemble.py: wrote {out}/paper.md")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
