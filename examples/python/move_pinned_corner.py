"""A hanging cloth whose pinned corner is moved from Python between steps: the corner at x = 1 m
is carried 0.3 m further along x over the first second, then held; the cloth follows.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/move_pinned_corner.py
(A motion known in advance can also be given in the scene as [[pin_motion]].)
"""
import os

import numpy as np

import hooke

SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "problems", "scenes",
                     "falling_stiff_cloth.toml")


def main():
    scene = hooke.load_scene(SCENE, {"mesh.nx": 16, "mesh.ny": 16, "time.duration": 2.0})
    sim = hooke.Simulation(scene)
    x = sim.x  # a view: it follows every step, and writing it moves the particles
    pinned = np.flatnonzero(sim.system.pinned)
    corner = pinned[np.argmax(x[pinned, 0])]  # the pinned corner at x = 1
    start = x[corner].copy()
    while sim.t < scene.duration - 1e-12:
        s = min(sim.t + scene.dt, 1.0)
        x[corner] = start + [0.3 * s, 0.0, 0.0]  # where the corner is at the end of the step
        sim.step()
    far_edge = x[-16:]  # row j = 15, opposite the pinned row
    print(f"t = {sim.t:.3g} s: corner at {x[corner]}, far edge's mean x = "
          f"{far_edge[:, 0].mean():.3f} m, kinetic energy {sim.kinetic_energy:.3g} J")
    assert abs(x[corner, 0] - 1.3) < 1e-12 and np.all(np.isfinite(x))


if __name__ == "__main__":
    main()
