"""Draws the picture of a finished `hooke run` (experiments/run_output.cpp).

Usage: /usr/bin/python3 experiments/plot/final.py OUT_DIR
Reads OUT_DIR/final.vtk (the final state: positions, springs with their strain, pinned flags, the
time) and OUT_DIR/scene.toml (the resolved scene: method, colliders); writes OUT_DIR/final.png:
the springs in an orthographic 3D view with axes in metres (y up), coloured by strain with a
colour bar, pinned particles as black dots, spheres as wireframes and ground planes as shaded
squares. Above 150,000 springs, an evenly spaced subset is drawn, and the title says so.
"""
import math
import os
import sys
import tomllib

import numpy as np
from matplotlib.colors import Normalize
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

from common import plt, read_vtk, save_figure

MAX_DRAWN = 150_000
ELEVATION, AZIMUTH = 20, -60


def tables(scene, kind):
    """[collision.KIND] as a list of tables (one table or an array of tables)."""
    t = scene.get("collision", {}).get(kind, [])
    return [t] if isinstance(t, dict) else list(t)


def up(p):
    """Scene coordinates (y up) to matplotlib's 3D axes (z up): (x, y, z) -> (x, z, y)."""
    p = np.asarray(p, dtype=float)
    return p[..., [0, 2, 1]]


def main(out_dir):
    frame = read_vtk(os.path.join(out_dir, "final.vtk"))
    with open(os.path.join(out_dir, "scene.toml"), "rb") as f:
        scene = tomllib.load(f)
    points, lines, strain = frame["points"], frame["lines"], frame["strain"]
    stride = max(1, math.ceil(len(lines) / MAX_DRAWN))
    lines, strain = lines[::stride], strain[::stride]

    fig = plt.figure(figsize=(7.6, 6.2))
    ax = fig.add_subplot(projection="3d", proj_type="ortho")
    ax.view_init(elev=ELEVATION, azim=AZIMUTH)
    lo, hi = points.min(axis=0), points.max(axis=0)

    # Colliders, beneath the cloth.
    for s in tables(scene, "sphere"):
        c, r = np.array(s.get("center", [0, 0, 0]), float), float(s.get("radius", 0.5))
        u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
        sph = c + r * np.stack([np.cos(u) * np.sin(v), np.cos(v), np.sin(u) * np.sin(v)], axis=-1)
        sph = up(sph)
        ax.plot_wireframe(sph[..., 0], sph[..., 1], sph[..., 2], color="0.55", lw=0.4)
        lo, hi = np.minimum(lo, c - r), np.maximum(hi, c + r)
    span = max(float(np.max(hi - lo)), 1e-9)
    centre = 0.5 * (lo + hi)
    for g in tables(scene, "ground"):
        n = np.array(g.get("normal", [0, 1, 0]), float)
        n /= np.linalg.norm(n)
        h = float(g.get("height", 0.0))
        foot = centre - (n @ centre - h) * n
        t1 = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(n, t1)
        a = 0.6 * span
        quad = [foot + a * (s1 * t1 + s2 * t2) for s1, s2 in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        ax.add_collection3d(Poly3DCollection([up(np.array(quad))], facecolor="0.6", alpha=0.25,
                                             edgecolor="0.4", lw=0.5))
        lo, hi = np.minimum(lo, np.min(quad, axis=0)), np.maximum(hi, np.max(quad, axis=0))

    top = max(float(strain.max()) if len(strain) else 0.0, 1e-6)
    norm = Normalize(vmin=0.0, vmax=top)
    if len(lines):
        segs = up(np.stack([points[lines[:, 0]], points[lines[:, 1]]], axis=1))
        coll = Line3DCollection(segs, cmap="plasma", norm=norm, linewidths=0.7)
        coll.set_array(strain)
        ax.add_collection3d(coll)
        compressed = len(strain) and float(strain.min()) < 0.0
        bar = fig.colorbar(coll, ax=ax, shrink=0.65, pad=0.08,
                           extend="min" if compressed else "neither")
        bar.set_label("spring strain (l - L) / L" + ("; compressed below 0" if compressed else ""))
    pinned = points[frame["pinned"]]
    if len(pinned):
        p = up(pinned)
        ax.scatter(p[:, 0], p[:, 1], p[:, 2], color="black", s=10, depthshade=False,
                   label=f"pinned ({len(pinned)})")
        ax.legend(loc="upper left", fontsize=8)

    # Equal scales on the three axes, over the particles and the colliders.
    lo3, hi3 = up(lo), up(hi)
    mid, half = 0.5 * (lo3 + hi3), 0.5 * max(float(np.max(hi3 - lo3)), 1e-9)
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_zlabel("y (m), up")

    method = scene.get("integrator", {}).get("method", "?")
    name = os.path.basename(os.path.normpath(out_dir))
    title = f"{name}: {method}, t = {frame['t']:.6g} s"
    sub = f"orthographic view, elevation {ELEVATION}\N{DEGREE SIGN}, azimuth {AZIMUTH}\N{DEGREE SIGN}"
    if stride > 1:
        sub += f"; every {stride}th of {len(frame['lines']):,} springs drawn"
    ax.set_title(title + "\n" + sub, fontsize=9)
    fig.tight_layout()
    save_figure(fig, os.path.join(out_dir, "final.png"))


if __name__ == "__main__":
    main(sys.argv[1])
