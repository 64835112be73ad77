"""Checks hooke's analytic Jacobians K = df/dx and D = df/dv against central differences of its
forces, on a damped cloth in a random stretched and compressed state, with scipy.sparse.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/jacobian_check.py
"""
import os

import numpy as np
import scipy.sparse as sp

import hooke

SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "problems", "scenes",
                     "hanging_cloth_16.toml")


def main():
    scene = hooke.load_scene(SCENE, {"mesh.nx": 6, "mesh.ny": 6, "springs.damping": 0.5})
    system = hooke.Simulation(scene).system
    rng = np.random.default_rng(1)
    n = scene.num_particles
    x = hooke.Simulation(scene).x + 0.03 * rng.standard_normal((n, 3))
    v = rng.standard_normal((n, 3))
    K, D = system.stiffness(x, v), system.damping(x, v)
    assert sp.issparse(K) and K.shape == (3 * n, 3 * n)
    eps = 1e-6
    fd_K, fd_D = np.zeros((3 * n, 3 * n)), np.zeros((3 * n, 3 * n))
    for j in range(3 * n):
        e = np.zeros(3 * n)
        e[j] = eps
        e = e.reshape(n, 3)
        fd_K[:, j] = (system.forces(x + e, v) - system.forces(x - e, v)).ravel() / (2 * eps)
        fd_D[:, j] = (system.forces(x, v + e) - system.forces(x, v - e)).ravel() / (2 * eps)
    err_K = abs(K.toarray() - fd_K).max() / abs(fd_K).max()
    err_D = abs(D.toarray() - fd_D).max() / abs(fd_D).max()
    print(f"{n} particles, {K.nnz} stored entries of K: largest relative differences "
          f"K {err_K:.2e}, D {err_D:.2e}")
    assert err_K < 1e-7 and err_D < 1e-7


if __name__ == "__main__":
    main()
