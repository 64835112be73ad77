"""Shared helpers of the hooke plot scripts: CSV reading and Markdown tables (Debian's matplotlib)."""
import csv
import math
import os
import re

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

plt.rcParams.update({"figure.dpi": 110, "savefig.dpi": 110, "axes.grid": True, "grid.alpha": 0.3,
                     "legend.fontsize": 7, "font.size": 9})


def _replace(path, write):
    """Writes path through path.tmp, flushed to disk and renamed: complete or absent."""
    tmp = path + ".tmp"
    try:
        with open(tmp, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def save_figure(fig, path, **kwargs):
    """fig.savefig(path) that leaves no partial PNG (a full disk raises, as it should)."""
    fmt = os.path.splitext(path)[1].lstrip(".") or "png"
    _replace(path, lambda f: fig.savefig(f, format=fmt, **kwargs))


def write_text(path, text):
    """A Markdown table or other text file, complete or absent."""
    _replace(path, lambda f: f.write(text.encode()))


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(text):
    """Float of a CSV field; NaN for empty, '-' or 'nan'."""
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def g3(v):
    """Three significant digits, '-' for NaN, for tables."""
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.3g}"


def markdown_table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out) + "\n"


# One distinct style per method label, stable across figures: the ten strong colours of tab20
# first, then its ten tints, with twelve markers, so that up to 20 labels have 20 colours and no two
# labels share both colour and marker.
_MARKERS = "os^vD<>pP*Xh"


def style(label, labels):
    i = sorted(set(labels)).index(label)
    return {"marker": _MARKERS[i % len(_MARKERS)], "color": plt.cm.tab20((2 * i + (i // 10) % 2) % 20)}


def read_vtk(path):
    """A frame written by hooke (experiments/output/vtk_writer.cpp: legacy binary POLYDATA,
    big-endian) as a dict: t, points (n x 3), lines (m x 2 particle ids), triangles (k x 3),
    strain (per line), velocity (n x 3), pinned (n booleans), kinetic_energy (n) and, when the
    frame has them (fluid scenes), density (kg/m^3) and pressure (Pa): n each, NaN on boundary
    particles."""
    with open(path, "rb") as f:
        data = f.read()
    pos = 0

    def section(pattern):
        nonlocal pos
        m = re.compile(pattern).search(data, pos)
        if not m:
            return None
        pos = m.end()
        return m

    def array(dtype, count):
        nonlocal pos
        a = np.frombuffer(data, dtype=dtype, count=count, offset=pos)
        pos += a.nbytes
        return a

    out = {"t": float("nan"), "triangles": np.zeros((0, 3), dtype=int)}
    if section(rb"TIME 1 1 double\n"):
        out["t"] = float(array(">f8", 1)[0])
    n = int(section(rb"POINTS (\d+) double\n").group(1))
    out["points"] = array(">f8", 3 * n).reshape(n, 3)
    m = int(section(rb"\nLINES (\d+) \d+\n").group(1))
    out["lines"] = array(">i4", 3 * m).reshape(m, 3)[:, 1:].astype(int)
    tri = re.compile(rb"\nPOLYGONS (\d+) \d+\n").match(data, pos)
    if tri:
        pos = tri.end()
        k = int(tri.group(1))
        out["triangles"] = array(">i4", 4 * k).reshape(k, 4)[:, 1:].astype(int)
    cells = int(section(rb"\nCELL_DATA (\d+)\nSCALARS strain double 1\nLOOKUP_TABLE default\n")
                .group(1))
    out["strain"] = array(">f8", cells)[:m]
    section(rb"\nPOINT_DATA \d+\nVECTORS velocity double\n")
    out["velocity"] = array(">f8", 3 * n).reshape(n, 3)
    section(rb"\nSCALARS pinned int 1\nLOOKUP_TABLE default\n")
    out["pinned"] = array(">i4", n) != 0
    section(rb"\nSCALARS kinetic_energy double 1\nLOOKUP_TABLE default\n")
    out["kinetic_energy"] = array(">f8", n)
    # Further per-particle doubles follow kinetic_energy directly (density, pressure).
    extra = re.compile(rb"\nSCALARS (\w+) double 1\nLOOKUP_TABLE default\n")
    while field := extra.match(data, pos):
        pos = field.end()
        out[field.group(1).decode()] = array(">f8", n)
    return out
