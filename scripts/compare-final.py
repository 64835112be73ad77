#!/usr/bin/env python3
"""Runs every registered method on every shipped scene with two hooke binaries and compares the
final.csv files they write: the check of a change that must not change behaviour (a move, a
carve, an interface change), as CONTRIBUTING.md's "Behaviour unchanged" asks.

Usage: compare-final.py OLD NEW [--steps N] [--scenes A,B] [--methods A,B] [--work DIR]

Each run is `hooke run SCENE --set integrator.method=M` shortened to N steps of the scene's dt
(default 20), without frames or pictures. For each pair it prints one row: `same` (the same bits),
`close` (every number within 1e-12 relative, with the largest difference), `DIFFERENT` (with the
largest difference), `stopped` (both stopped with the same exit code and message, e.g. an
explicit method diverging, and their log.csv rows agree to 1e-12), `refused` (both refused the
scene with the same message: the method does not take it) or `MISMATCH` (the exit codes or
messages differ). Exits 1 if any pair is DIFFERENT or MISMATCH, else 0.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib

CLOSE = 1e-12


def methods_of(binary):
    text = subprocess.run([binary, "run", "--help"], capture_output=True, text=True).stdout
    m = re.search(r"^Methods: (.*)$", text, re.M)
    if not m:
        sys.exit(f"compare-final: {binary} run --help lists no methods")
    return [s.strip() for s in m.group(1).split(",")]


def scenes_of(binary):
    text = subprocess.run([binary, "scenes"], capture_output=True, text=True).stdout
    names, folder = [], None
    for line in text.splitlines():
        m = re.match(r"\(in (.*); run one with", line)
        if m:
            folder = m.group(1)
        elif line and not line.startswith(" "):
            names.append(line.split()[0])
    return names, folder


def short_duration(path, steps):
    with open(path, "rb") as f:
        scene = tomllib.load(f)
    time = scene.get("time", {})
    dt = float(time.get("dt", 0.001))
    return min(float(time.get("duration", 1.0)), steps * dt)


def run(binary, scene, method, duration, out):
    args = [binary, "run", scene, "--out", out, "--no-progress", "--force",
            "--set", f"integrator.method={method}", "--set", f"time.duration={duration!r}",
            "--set", "output.vtk=false", "--set", "output.png=false", "--set", "output.every=0"]
    p = subprocess.run(args, capture_output=True, text=True)
    final = os.path.join(out, "final.csv" if p.returncode == 0 else "log.csv")
    text = open(final).read() if os.path.exists(final) else None
    if text is not None and p.returncode != 0:  # log.csv: all but its wall_time column
        rows = [line.split(",") for line in text.splitlines()]
        keep = [i for i, name in enumerate(rows[0]) if name != "wall_time"] if rows else []
        text = "\n".join(",".join(r[i] for i in keep if i < len(r)) for r in rows)
    # The message without the binary's and the output folder's own paths.
    err = p.stderr.replace(binary, "hooke").replace(out, "OUT").strip().splitlines()
    return p.returncode, text, err[-1] if err else ""


def numbers(text):
    return [float(t) for t in re.findall(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|nan|inf",
                                         text)]


def compare(a, b):
    if a == b:
        return "same", 0.0
    na, nb = numbers(a), numbers(b)
    if len(na) != len(nb):
        return "DIFFERENT", float("inf")
    worst = 0.0
    for x, y in zip(na, nb):
        if x != y:
            worst = max(worst, abs(x - y) / max(abs(x), abs(y), 1e-300))
    return ("close" if worst <= CLOSE else "DIFFERENT"), worst


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--scenes", default="")
    ap.add_argument("--methods", default="")
    ap.add_argument("--work", default="")
    o = ap.parse_args()
    old, new = os.path.abspath(o.old), os.path.abspath(o.new)
    methods = o.methods.split(",") if o.methods else methods_of(new)
    names, folder = scenes_of(new)
    if o.scenes:
        names = o.scenes.split(",")
    work = o.work or tempfile.mkdtemp(prefix="hooke-compare-")
    bad = 0
    counts = {}
    for scene in names:
        path = os.path.join(folder, scene + ".toml")
        duration = short_duration(path, o.steps)
        for method in methods:
            ra = run(old, path, method, duration, os.path.join(work, "old", scene, method))
            rb = run(new, path, method, duration, os.path.join(work, "new", scene, method))
            if ra[0] != rb[0] or (ra[0] != 0 and ra[2] != rb[2]):
                verdict, detail = "MISMATCH", f"old exit {ra[0]}: {ra[2]} | new exit {rb[0]}: {rb[2]}"
            elif ra[1] is not None and rb[1] is not None:
                verdict, worst = compare(ra[1], rb[1])
                detail = f"{worst:.3g}" if verdict != "same" else ""
                if ra[0] != 0:  # both stopped the same way: their log.csv compared
                    detail = f"stopped (exit {ra[0]}), log.csv {verdict} {detail}".rstrip()
                    verdict = "stopped" if verdict != "DIFFERENT" else verdict
            elif ra[1] is None and rb[1] is None:
                verdict, detail = "refused", f"exit {ra[0]}"
            else:
                verdict, detail = "MISMATCH", f"old exit {ra[0]}: {ra[2]} | new exit {rb[0]}: {rb[2]}"
            counts[verdict] = counts.get(verdict, 0) + 1
            bad += verdict in ("DIFFERENT", "MISMATCH")
            print(f"{scene:28s} {method:18s} {verdict:9s} {detail}", flush=True)
    if not o.work:
        shutil.rmtree(work, ignore_errors=True)
    print("compare-final: " + ", ".join(f"{n} {k}" for k, n in sorted(counts.items())))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
