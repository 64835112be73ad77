"""Draws the picture of a finished `hooke run` (experiments/run/run_output.cpp).

Usage: /usr/bin/python3 experiments/plot/final.py OUT_DIR
Reads OUT_DIR/final.vtk (the final state: positions, springs with their strain, pinned flags, the
time, velocities; for fluids also pressure) and OUT_DIR/scene.toml (the resolved scene:
method, colliders, the [fluid] table); writes OUT_DIR/final.png.

Springs (no [fluid] table): the springs in an orthographic 3D view with axes in metres (y up),
coloured by strain with a colour bar, pinned particles as black dots, spheres as wireframes and
ground planes as shaded squares. Above 150,000 springs, an evenly spaced subset is drawn, and the
title says so.

Fluids ([fluid] table; boundary particles are the pinned ones, fluid particles the others), coloured
by pressure (Pa), or by speed |v| (m/s) when no pressure is positive, with a colour bar whose top is
the 99.5th percentile (an arrow marks the few above it):
- fluid.dimension = 2: the x-y plane at equal scale, axes in metres, fluid particles as discs of
  diameter fluid.spacing, boundary particles (tank walls, obstacles) as small grey squares;
- fluid.dimension = 3: the same orthographic view as for springs, fluid particles as dots, boundary
  particles light grey and translucent beneath them; above 30,000 boundary particles a fixed random
  subset of 30,000 is drawn, and the title says so.
The title gives the particle counts and how many fluid particles lie outside the tank (spray).
"""
import math
import os
import sys
import tomllib

import numpy as np
from matplotlib.collections import EllipseCollection, PolyCollection
from matplotlib.colors import Normalize
from matplotlib.transforms import Bbox
from mpl_toolkits.axes_grid1 import make_axes_locatable
from mpl_toolkits.mplot3d import proj3d
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

from common import plt, read_vtk, save_figure

MAX_DRAWN = 150_000
MAX_BOUNDARY_DRAWN = 30_000
ELEVATION, AZIMUTH = 20, -60


def tables(scene, kind):
    """[collision.KIND] as a list of tables (one table or an array of tables)."""
    t = scene.get("collision", {}).get(kind, [])
    return [t] if isinstance(t, dict) else list(t)


def up(p):
    """Scene coordinates (y up) to matplotlib's 3D axes (z up): (x, y, z) -> (x, z, y)."""
    p = np.asarray(p, dtype=float)
    return p[..., [0, 2, 1]]


def draw_springs(out_dir, frame, scene):
    """The spring picture: a Figure."""
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

    sub = f"orthographic view, elevation {ELEVATION}\N{DEGREE SIGN}, azimuth {AZIMUTH}\N{DEGREE SIGN}"
    if stride > 1:
        sub += f"; every {stride}th of {len(frame['lines']):,} springs drawn"
    ax.set_title(title(out_dir, frame, scene) + "\n" + sub, fontsize=9)
    fig.tight_layout()
    return fig


def title(out_dir, frame, scene):
    """First title line: output directory name, method, time."""
    method = scene.get("integrator", {}).get("method", "?")
    name = os.path.basename(os.path.normpath(out_dir))
    return f"{name}: {method}, t = {frame['t']:.6g} s"


def fluid_colour(frame, fluid):
    """Colour values of the fluid particles, their colour-bar label and a Normalize from 0 (or the
    minimum, if negative) to the 99.5th percentile, with the colour bar's extend."""
    pressure = frame.get("pressure")
    values = None if pressure is None else pressure[fluid]
    label = "pressure (Pa)"
    if values is None or not np.any(np.nan_to_num(values) > 0.0):
        values = np.linalg.norm(frame["velocity"][fluid], axis=1)
        label = "speed |v| (m/s)"
    finite = values[np.isfinite(values)]
    if len(finite) == 0:
        return values, label, Normalize(0.0, 1.0), "neither"
    lo = min(0.0, float(finite.min()))
    hi = float(np.percentile(finite, 99.5))
    hi = hi if hi > lo else lo + max(abs(lo), 1e-9)
    extend = {(False, False): "neither", (True, False): "min", (False, True): "max",
              (True, True): "both"}[(bool(finite.min() < lo), bool(finite.max() > hi))]
    return values, label, Normalize(lo, hi), extend


def fluid_counts(frame, scene, fluid):
    """Second title line: particle counts, spacing, how many fluid particles left the tank."""
    spec = scene["fluid"]
    text = (f"{int(fluid.sum()):,} fluid and {int((~fluid).sum()):,} boundary particles, "
            f"spacing {float(spec.get('spacing', 0.0)):.4g} m")
    tank = spec.get("tank")
    if tank:
        dim = 2 if int(spec.get("dimension", 3)) == 2 else 3
        p = frame["points"][fluid][:, :dim]
        lower, upper = np.array(tank["lower"], float)[:dim], np.array(tank["upper"], float)[:dim]
        outside = int(np.count_nonzero(np.any((p < lower) | (p > upper), axis=1)))
        if outside:
            text += f"; {outside:,} outside the tank"
    return text


def draw_fluid_2d(out_dir, frame, scene):
    """The 2D fluid picture (x-y plane): a Figure."""
    spacing = float(scene["fluid"].get("spacing", 0.01))
    xy = frame["points"][:, :2]
    fluid = ~frame["pinned"]
    values, label, norm, extend = fluid_colour(frame, fluid)

    # A figure whose axes have the data's aspect ratio, so that equal scales waste no space.
    lo, hi = xy.min(axis=0) - spacing, xy.max(axis=0) + spacing
    span = np.maximum(hi - lo, 1e-9)
    width = 6.0
    height = float(np.clip(width * span[1] / span[0], 2.0, 8.0))
    fig, ax = plt.subplots(figsize=(width + 1.6, height + 1.2))
    ax.set_axisbelow(True)

    # Boundary particles: grey squares of side 0.7 spacing.
    wall = xy[~fluid]
    if len(wall):
        corners = 0.35 * spacing * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
        ax.add_collection(PolyCollection(wall[:, None, :] + corners, facecolor="0.5",
                                         edgecolor="none"))
    # Fluid particles: discs of diameter spacing in data units (so the fluid looks continuous).
    n = int(fluid.sum())
    discs = EllipseCollection(np.full(n, spacing), np.full(n, spacing), np.zeros(n), units="xy",
                              offsets=xy[fluid], offset_transform=ax.transData, cmap="viridis",
                              norm=norm, edgecolor="none")
    discs.set_array(values)
    ax.add_collection(discs)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    # A colour bar axes split off the plot's, so that it keeps the plot's height at equal scales.
    cax = make_axes_locatable(ax).append_axes("right", size=0.18, pad=0.15)
    cax.grid(False)
    bar = fig.colorbar(discs, cax=cax, extend=extend)
    bar.set_label(label)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m), up")
    ax.set_title(title(out_dir, frame, scene) + "\n" + fluid_counts(frame, scene, fluid),
                 fontsize=9)
    fig.tight_layout()
    return fig


def draw_fluid_3d(out_dir, frame, scene):
    """The 3D fluid picture (orthographic, as for springs): a Figure and the Bbox (inches) to
    save. mplot3d keeps its axes square, so a long tank would leave bands of white above and below
    it: the picture is cut to the box with its axis labels, the colour bar and the title."""
    spacing = float(scene["fluid"].get("spacing", 0.01))
    points = frame["points"]
    fluid = ~frame["pinned"]
    values, label, norm, extend = fluid_colour(frame, fluid)
    wall = points[~fluid]
    if len(wall) > MAX_BOUNDARY_DRAWN:
        # A fixed random subset: every k-th particle of a lattice would draw stripes.
        pick = np.random.default_rng(0).choice(len(wall), MAX_BOUNDARY_DRAWN, replace=False)
        wall = wall[np.sort(pick)]

    fig = plt.figure(figsize=(7.6, 6.2))
    # Drawn in the order added (boundary, then fluid): mplot3d sorts whole collections by their
    # mean depth, which would put the walls in front of the fluid half of the time.
    ax = fig.add_subplot(projection="3d", proj_type="ortho", computed_zorder=False)
    fig.subplots_adjust(left=0.0, right=0.86, bottom=0.0, top=1.0)
    ax.view_init(elev=ELEVATION, azim=AZIMUTH)
    lo3, hi3 = up(points.min(axis=0)), up(points.max(axis=0))
    span3 = np.maximum(hi3 - lo3, spacing)
    ax.set_xlim(lo3[0], lo3[0] + span3[0])
    ax.set_ylim(lo3[1], lo3[1] + span3[1])
    ax.set_zlim(lo3[2], lo3[2] + span3[2])
    ax.set_box_aspect(span3.copy())  # equal scales (a copy: matplotlib 3.6 scales it in place)
    ax.set_xlabel("x (m)", labelpad=10)
    ax.set_ylabel("z (m)", labelpad=10)
    ax.set_zlabel("y (m), up")
    walls = None
    if len(wall):
        w = up(wall)
        walls = ax.scatter(w[:, 0], w[:, 1], w[:, 2], color="0.6", alpha=0.12, linewidths=0,
                           depthshade=False)
    f = up(points[fluid])
    dots = ax.scatter(f[:, 0], f[:, 1], f[:, 2], c=values, cmap="viridis", norm=norm,
                      linewidths=0, depthshade=False)

    # Marker diameter: 1.25 particle spacings (one leaves the lattice's gaps open in this oblique
    # view), from the screen width of the drawn box (the view's horizontal direction is
    # (-sin azimuth, cos azimuth, 0) in matplotlib's axes).
    renderer = fig.canvas.get_renderer()
    fig.canvas.draw()
    # The box's corners, panes included: mplot3d (3.6) draws them 1/48 of each range outside.
    margin = span3 / 48.0
    corners = np.array(np.meshgrid(*[(lo3[k] - margin[k], lo3[k] + span3[k] + margin[k])
                                     for k in range(3)])).reshape(3, -1)
    px, py, _ = proj3d.proj_transform(*corners, ax.get_proj())
    screen = ax.transData.transform(np.column_stack([px, py]))
    az = math.radians(AZIMUTH)
    across = abs(math.sin(az)) * span3[0] + abs(math.cos(az)) * span3[1]
    points_per_metre = float(np.ptp(screen[:, 0])) / (across * 50.0 / 48.0) * 72.0 / fig.dpi
    size = (1.25 * spacing * points_per_metre) ** 2
    dots.set_sizes([size])
    if walls is not None:
        walls.set_sizes([0.4 * size])

    # The colour bar beside the box, 80% of its height; the title just above the box.
    parts = Bbox.union([a.get_tightbbox(renderer) for a in (ax.xaxis, ax.yaxis, ax.zaxis)]
                       + [Bbox([screen.min(axis=0), screen.max(axis=0)])])
    gap = 6.0 * fig.dpi / 72.0  # 6 points, in pixels
    to_figure = fig.transFigure.inverted()
    x0, y0 = to_figure.transform((parts.x1 + 2 * gap, parts.y0 + 0.1 * parts.height))
    x1, y1 = to_figure.transform((parts.x1 + 5 * gap, parts.y1 - 0.1 * parts.height))
    cax = fig.add_axes([x0, y0, x1 - x0, y1 - y0])
    cax.grid(False)
    bar = fig.colorbar(dots, cax=cax, extend=extend)
    bar.set_label(label)
    sub = fluid_counts(frame, scene, fluid)
    sub += (f"\northographic view, elevation {ELEVATION}\N{DEGREE SIGN}, "
            f"azimuth {AZIMUTH}\N{DEGREE SIGN}")
    if len(wall) < len(points) - len(f):
        sub += f"; {len(wall):,} of the {len(points) - len(f):,} boundary particles drawn"
    x, y = to_figure.transform((0.5 * (parts.x0 + parts.x1), parts.y1 + gap))
    head = fig.text(x, y, title(out_dir, frame, scene) + "\n" + sub, fontsize=9, ha="center",
                    va="bottom", multialignment="center")
    fig.canvas.draw()
    keep = Bbox.union([parts, bar.ax.get_tightbbox(renderer), head.get_window_extent(renderer)])
    keep = Bbox.from_extents(keep.x0 - gap, keep.y0 - gap, keep.x1 + gap, keep.y1 + gap)
    return fig, keep.transformed(fig.dpi_scale_trans.inverted())


def main(out_dir):
    frame = read_vtk(os.path.join(out_dir, "final.vtk"))
    with open(os.path.join(out_dir, "scene.toml"), "rb") as f:
        scene = tomllib.load(f)
    path = os.path.join(out_dir, "final.png")
    if "fluid" not in scene:
        save_figure(draw_springs(out_dir, frame, scene), path)
        return
    if int(scene["fluid"].get("dimension", 3)) == 2:
        fig, keep = draw_fluid_2d(out_dir, frame, scene), "tight"
    else:
        fig, keep = draw_fluid_3d(out_dir, frame, scene)
    save_figure(fig, path, bbox_inches=keep, pad_inches=0.15)


if __name__ == "__main__":
    main(sys.argv[1])
