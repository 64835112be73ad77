"""The largest stable step of symplectic Euler against spring stiffness, on the two-particle
spring, found by bisection and plotted against the theory h = 2 / omega (omega = sqrt(2 k / m)).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/stable_step_sweep.py [OUT_DIR]
Writes OUT_DIR/stable_step.png (default: out/examples).
"""
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import hooke  # noqa: E402

SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "problems", "scenes",
                     "two_particle.toml")


def stable(k, h):
    """True if 200 steps of size h keep the spring's stretch bounded (below its rest length)."""
    scene = hooke.load_scene(SCENE, {"springs.stiffness": k, "integrator.method": "symplectic-euler",
                                     "time.dt": h, "time.duration": 200 * h})
    sim = hooke.Simulation(scene)
    for _ in range(200):
        try:
            sim.step()
        except hooke.StepError:
            return False
        if abs(sim.x[1, 0] - sim.x[0, 0]) > 2.0:  # rest length 1 m: stretched past 100%
            return False
    return True


def largest_stable_step(k):
    lo, hi = 1e-6, 1.0
    for _ in range(30):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if stable(k, mid) else (lo, mid)
    return lo


def main(out_dir):
    ks = np.logspace(1, 5, 9)
    h = [largest_stable_step(k) for k in ks]
    theory = 2.0 / np.sqrt(2.0 * ks / 1.0)  # two 1 kg particles: omega = sqrt(2 k / m)
    for k, hk, ht in zip(ks, h, theory):
        print(f"k = {k:9.3g} N/m: largest stable h = {hk:.4g} s, theory 2 / omega = {ht:.4g} s")
        assert abs(hk / ht - 1.0) < 0.02, "symplectic Euler's limit is 2 / omega"
    fig, ax = plt.subplots(figsize=(5.5, 4))
    ax.loglog(ks, h, "o", label="measured (bisection)")
    ax.loglog(ks, theory, "-", label="theory 2 / omega")
    ax.set_xlabel("spring stiffness k (N/m)")
    ax.set_ylabel("largest stable step h (s)")
    ax.set_title("symplectic Euler on the two-particle spring")
    ax.legend()
    os.makedirs(out_dir, exist_ok=True)
    fig.savefig(os.path.join(out_dir, "stable_step.png"), dpi=110)
    print("wrote", os.path.join(out_dir, "stable_step.png"))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join("out", "examples"))
