"""The Python module against the library it binds and against independent checks: the views follow
the state, Simulation.run() gives `hooke run`'s final state bit for bit, the Jacobians match
finite differences of the forces, every registered method steps, bad input raises InputError with
hooke's message, a failed step raises StepError, Ctrl-C stops a long run between steps, and memory
stays flat over 10^4 steps.

Run by CTest (Python.pytest) with PYTHONPATH=build/python, HOOKE_BIN (the hooke command) and
HOOKE_SCENES (problems/scenes); by hand: PYTHONPATH=build/python /usr/bin/python3 -m pytest
tests/python.
"""
import csv
import inspect
import os
import re
import signal
import subprocess

import numpy as np
import pytest

import hooke

SCENES = os.environ.get("HOOKE_SCENES", os.path.join(os.path.dirname(__file__), "..", "..",
                                                     "problems", "scenes"))
CLOTH = os.path.join(SCENES, "hanging_cloth_16.toml")


def cloth(**overrides):
    sets = {"time.duration": 0.01}
    sets.update(overrides)
    return hooke.load_scene(CLOTH, sets)


def test_views_follow_the_state_after_every_step():
    sim = hooke.Simulation(cloth(**{"integrator.method": "symplectic-euler"}))
    x, v = sim.x, sim.v
    assert x.shape == (256, 3) and x.dtype == np.float64
    before = x.copy()
    for _ in range(3):  # an odd and an even number of steps: no double buffer shows through
        sim.step()
        assert np.shares_memory(x, sim.x) and np.shares_memory(v, sim.v)
        assert np.array_equal(x, sim.x)
    assert not np.array_equal(x, before)
    assert sim.t == pytest.approx(3 * 5e-4)


def test_writing_a_view_moves_the_particle():
    sim = hooke.Simulation(cloth(**{"integrator.method": "symplectic-euler"}))
    sim.v[100] = [0.0, 1.0, 0.0]
    y = sim.x[100, 1]
    sim.step(5e-4)
    assert sim.x[100, 1] > y + 4e-4


def read_final(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    x = np.array([[float(r["x"]), float(r["y"]), float(r["z"])] for r in rows])
    v = np.array([[float(r["vx"]), float(r["vy"]), float(r["vz"])] for r in rows])
    return x, v


@pytest.mark.parametrize("method", ["symplectic-euler", "rk4", "implicit", "bdf2"])
def test_run_gives_the_final_state_of_hooke_run_bit_for_bit(tmp_path, method):
    sets = {"time.duration": 0.0123, "time.dt": 1e-3, "integrator.method": method}
    sim = hooke.Simulation(hooke.load_scene(CLOTH, sets))
    sim.run()
    assert sim.t == 0.0123 and sim.steps_taken == 13  # the last step shortened, as hooke run does
    cmd = [os.environ["HOOKE_BIN"], "run", CLOTH, "--out", str(tmp_path), "--no-progress",
           "--set", "output.vtk=false", "--set", "output.png=false"]
    for k, val in sets.items():
        cmd += ["--set", f"{k}={val}"]
    subprocess.run(cmd, check=True, capture_output=True)
    x, v = read_final(tmp_path / "final.csv")
    assert np.array_equal(sim.x, x) and np.array_equal(sim.v, v)


def test_jacobians_match_central_differences_of_the_forces():
    # A damped cloth, perturbed so that springs are stretched and compressed.
    scene = hooke.load_scene(CLOTH, {"mesh.nx": 4, "mesh.ny": 4, "springs.damping": 0.7})
    system = hooke.Simulation(scene).system
    rng = np.random.default_rng(7)
    x = hooke.Simulation(scene).x + 0.05 * rng.standard_normal((16, 3))
    v = rng.standard_normal((16, 3))
    K = system.stiffness(x, v).toarray()
    D = system.damping(x, v).toarray()
    eps = 1e-6
    for j in range(48):
        dx = np.zeros(48)
        dx[j] = eps
        dx = dx.reshape(16, 3)
        fd_x = (system.forces(x + dx, v) - system.forces(x - dx, v)).ravel() / (2 * eps)
        fd_v = (system.forces(x, v + dx) - system.forces(x, v - dx)).ravel() / (2 * eps)
        assert np.allclose(K[:, j], fd_x, rtol=1e-6, atol=1e-6 * np.abs(K).max()), j
        assert np.allclose(D[:, j], fd_v, rtol=1e-6, atol=1e-6 * np.abs(D).max()), j
    # The potential's gradient is minus the conservative force (drag and dampers off at v = 0).
    zero = np.zeros((16, 3))
    g = np.array([(system.energy(x + e) - system.energy(x - e)) / (2 * eps)
                  for e in (np.eye(48)[j].reshape(16, 3) * eps for j in range(48))])
    assert np.allclose(-g, system.forces(x, zero).ravel(), rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("scene_name, sets", [
    ("curly_hair_rod", {"mesh.n": 8}),
    ("cloth_dihedral", {"mesh.nx": 4, "mesh.ny": 4}),
    ("cloth_dihedral", {"mesh.nx": 4, "mesh.ny": 4, "bending.model": "quadratic"}),
    ("cloth_dihedral", {"mesh.nx": 4, "mesh.ny": 4, "bending.model": "shell",
                        "bending.poisson": 0.3}),
])
def test_bending_energy_gradient_and_hessian_match_central_differences(scene_name, sets):
    # [bending] reaches Python as part of the system: its energy, -gradient (forces at v = 0, no
    # drag) and stiffness K = -Hessian (exact: clamp_compressed off), bent away from rest.
    sets = dict(sets, **{"forces.drag": 0.0, "springs.damping": 0.0})
    scene = hooke.load_scene(scene_name, sets)
    sim = hooke.Simulation(scene)
    system = sim.system
    n = sim.x.shape[0]
    rng = np.random.default_rng(54)
    x = sim.x + 0.02 * rng.standard_normal((n, 3))
    zero = np.zeros((n, 3))
    K = system.stiffness(x, zero).toarray()
    eps = 1e-6
    for j in range(3 * n):
        dx = np.eye(3 * n)[j].reshape(n, 3) * eps
        fd = (system.forces(x + dx, zero) - system.forces(x - dx, zero)).ravel() / (2 * eps)
        assert np.allclose(K[:, j], fd, rtol=1e-6, atol=1e-6 * np.abs(K).max()), j
        g = (system.energy(x + dx) - system.energy(x - dx)) / (2 * eps)
        f = system.forces(x, zero).ravel()
        assert abs(-g - f[j]) <= 1e-6 * max(1.0, np.abs(f).max()), j


def test_every_registered_method_steps():
    names = [m["name"] for m in hooke.methods()]
    assert {"rk4", "implicit", "symplectic-euler"} <= set(names)
    assert all(m["description"] for m in hooke.methods())
    fluid = {m["name"] for m in hooke.methods() if m["kind"] == "fluid"}
    assert fluid == {"wcsph", "iisph", "dfsph"}
    assert fluid == {m["name"] for m in hooke.methods() if m["family"] == "sph"}
    for name in names:
        sets = {"integrator.method": name, "time.dt": 1e-3}
        if name in fluid:  # they step fluids only: the dam break, with its CFL substeps
            scene = hooke.load_scene(os.path.join(SCENES, "dam_break_2d.toml"),
                                     dict(sets, **{"time.duration": 0.01}))
        else:
            scene = cloth(**sets)
        sim = hooke.Simulation(scene)
        summary = sim.step()
        assert summary["status"] in ("converged", "not-converged"), (name, summary)
        assert np.all(np.isfinite(sim.x)) and sim.t == 1e-3
    solvers = hooke.linear_solvers()
    assert {"pcg", "cg", "jacobi"} <= {s["name"] for s in solvers}  # built in every configuration
    assert all(s["description"] for s in solvers)


def test_a_shipped_scene_loads_by_name_as_hooke_run_finds_it():
    by_name = hooke.load_scene("hanging_cloth_16", {"time.duration": 0.01})
    by_path = hooke.load_scene(CLOTH, {"time.duration": 0.01})
    assert np.array_equal(hooke.Simulation(by_name).x, hooke.Simulation(by_path).x)
    with pytest.raises(hooke.InputError):
        hooke.load_scene("no_such_scene")


def test_the_namespace_is_the_api():
    public = {name for name in dir(hooke) if not name.startswith("_")}
    assert not {"os", "csv", "tempfile"} & public
    assert set(hooke.__all__) <= public


def documentation(obj, name):
    """obj's own documentation: for a function of the compiled module, what pybind11 puts after
    the signature line it writes first; for a class, property or Python function, its docstring."""
    doc = obj.__doc__ or ""
    if inspect.isclass(obj) or inspect.isfunction(obj) or isinstance(obj, property):
        return doc.strip()
    first, _, rest = doc.partition("\n")
    assert first.startswith(name + "("), (name, first)  # pybind11's signature line
    return rest.strip()


def test_every_public_name_is_documented_and_listed_in_help():
    undocumented = []
    for name in hooke.__all__:
        obj = getattr(hooke, name)
        if not documentation(obj, name):
            undocumented.append(name)
        if inspect.isclass(obj):  # its own public methods and properties, not inherited ones
            for member in vars(obj):
                if not member.startswith("_") and not documentation(getattr(obj, member), member):
                    undocumented.append(f"{name}.{member}")
    assert not undocumented, f"no docstring: {', '.join(undocumented)}"
    # help(hooke) lists the API: every name of __all__ starts a line of the docstring's API section.
    api = hooke.__doc__.partition("\nAPI\n---\n")[2]
    assert api, "hooke.__doc__ has no API section"
    unlisted = [name for name in hooke.__all__ if not re.search(rf"^{name}\b", api, re.M)]
    assert not unlisted, f"not in hooke.__doc__'s API section: {', '.join(unlisted)}"


def test_bad_input_raises_input_error_with_hookes_message():
    with pytest.raises(hooke.InputError) as e:
        hooke.load_scene(CLOTH, {"mesh.nxx": 4})
    assert e.value.key == "mesh.nxx" and e.value.file == CLOTH
    assert str(e.value).startswith(CLOTH + ": mesh.nxx: unknown key")
    with pytest.raises(hooke.InputError) as e:
        hooke.Scene.from_toml("[mesh]\ntype = 'grid'\nnx = 1\n", "inline.toml")
    assert e.value.key == "mesh.nx" and "must be in [2, 1000000000], got 1" in e.value.reason
    with pytest.raises(hooke.InputError) as e:
        hooke.Scene.from_dict({"mesh": {"type": "grid"}, "time": {"dt": -1.0}})
    assert e.value.key == "time.dt"


def test_a_dict_and_toml_text_give_the_same_scene():
    d = hooke.Scene.from_dict({"mesh": {"type": "grid", "nx": 5, "ny": 4},
                               "collision": {"sphere": [{"center": [0.5, -1.0, 0.5],
                                                         "radius": 0.3}]},
                               "forces": {"gravity": np.array([0.0, -9.81, 0.0])}})
    t = hooke.Scene.from_toml("[mesh]\ntype = 'grid'\nnx = 5\nny = 4\n"
                              "[[collision.sphere]]\ncenter = [0.5, -1.0, 0.5]\nradius = 0.3\n"
                              "[forces]\ngravity = [0.0, -9.81, 0.0]\n")
    a, b = hooke.Simulation(d), hooke.Simulation(t)
    for _ in range(20):
        a.step()
        b.step()
    assert np.array_equal(a.x, b.x) and d.num_particles == 20


def test_a_failed_step_raises_step_error_and_keeps_the_state():
    sim = hooke.Simulation(cloth(**{"integrator.method": "rk4", "time.dt": 0.05,
                                     "time.duration": 10.0}))
    with pytest.raises(hooke.StepError):
        for _ in range(2000):
            sim.step()
            if not np.all(np.isfinite(sim.x)):
                break
    assert np.all(np.isfinite(sim.x))


def test_ctrl_c_stops_a_long_run_between_steps():
    sim = hooke.Simulation(cloth(**{"time.duration": 1e4, "integrator.method": "symplectic-euler"}))
    signal.setitimer(signal.ITIMER_REAL, 0.3)
    old = signal.signal(signal.SIGALRM, lambda *_: os.kill(os.getpid(), signal.SIGINT))
    try:
        with pytest.raises(KeyboardInterrupt):
            sim.run()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    assert 0 < sim.t < 1e4 and np.all(np.isfinite(sim.x))


def resident_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_memory_stays_flat_over_ten_thousand_steps():
    sim = hooke.Simulation(cloth(**{"integrator.method": "implicit", "time.dt": 1e-3,
                                     "time.duration": 100.0, "mesh.nx": 8, "mesh.ny": 8}))
    for _ in range(200):
        sim.step()
        sim.x.sum()
    start = resident_bytes()
    for _ in range(10_000):
        sim.step()
        sim.x.sum()  # a view per step, as a user's loop makes
    assert resident_bytes() - start < 2 << 20


def test_set_method_continues_from_the_current_state():
    # Half the run by symplectic Euler, half by RK4, equals the two halves run separately.
    sets = {"integrator.method": "symplectic-euler", "time.dt": 1e-3}
    a = hooke.Simulation(cloth(**sets))
    for _ in range(5):
        a.step()
    a.set_method("rk4")
    assert a.method == "rk4"
    for _ in range(5):
        a.step()
    b = hooke.Simulation(cloth(**sets))
    for _ in range(5):
        b.step()
    c = hooke.Simulation(cloth(**{"integrator.method": "rk4", "time.dt": 1e-3}))
    c.x[:] = b.x
    c.v[:] = b.v
    for _ in range(5):
        c.step()
    assert np.array_equal(a.x, c.x) and np.array_equal(a.v, c.v)
    with pytest.raises(hooke.InputError) as e:
        a.set_method("rk5")
    assert e.value.key == "integrator.method"


def test_write_vtk_writes_the_current_state(tmp_path):
    sim = hooke.Simulation(cloth())
    sim.step()
    path = tmp_path / "state.vtk"
    sim.write_vtk(str(path))
    data = path.read_bytes()
    assert data.startswith(b"# vtk DataFile Version 3.0\n") and b"POINTS 256 double\n" in data
    start = data.index(b"POINTS 256 double\n") + len(b"POINTS 256 double\n")
    points = np.frombuffer(data, dtype=">f8", count=768, offset=start).reshape(256, 3)
    assert np.array_equal(points, sim.x)


@pytest.mark.parametrize("method", ["bdf2", "rk4"])
def test_a_checkpoint_continues_bit_for_bit(tmp_path, method):
    sets = {"integrator.method": method, "time.dt": 1e-3, "time.duration": 0.02}
    whole = hooke.Simulation(cloth(**sets))
    whole.run()
    first = hooke.Simulation(cloth(**sets))
    for _ in range(7):
        first.step()
    first.save_checkpoint(str(tmp_path / "c.bin"))
    second = hooke.Simulation(cloth(**sets))
    x = second.x
    second.load_checkpoint(str(tmp_path / "c.bin"))
    assert second.steps_taken == 7 and np.array_equal(x, first.x)
    second.run()
    assert np.array_equal(second.x, whole.x) and np.array_equal(second.v, whole.v)
    other = hooke.Simulation(cloth(**{"integrator.method": method, "time.dt": 2e-3}))
    with pytest.raises(hooke.InputError) as e:
        other.load_checkpoint(str(tmp_path / "c.bin"))
    assert "time.dt" in e.value.reason


def test_advance_lands_on_the_time_without_a_sliver_step():
    sim = hooke.Simulation(cloth(**{"integrator.method": "symplectic-euler", "time.dt": 5e-3}))
    sim.advance(0.25)  # 50 steps of 5 ms: their sum is not exactly 0.25
    assert sim.t == 0.25 and sim.steps_taken == 50
    sim.advance(0.25)
    assert sim.steps_taken == 50
    sim.advance(0.2512)  # one shortened step
    assert sim.t == 0.2512 and sim.steps_taken == 51


def test_the_studies_return_their_tables():
    rows = hooke.stability(cases=["two_particle"], methods=["symplectic-euler", "rk4"], k=[1e4])
    assert [r["method"] for r in rows] == ["symplectic-euler", "rk4"]
    for r in rows:  # bracketed within the bisection's 7% of the theory y / omega_max
        assert r["bound"] == "bracketed" and abs(r["h_stable"] / r["h_theory"] - 1) < 0.08, r
    table = hooke.crosscheck(cloth(**{"time.duration": 0.02}), methods=["rk4", "implicit"])
    assert {r["method"] for r in table} >= {"rk4", "implicit"}
    rk4 = next(r for r in table if r["method"] == "rk4")
    assert rk4["rms_err_final"] < 1e-6


def test_run_with_out_is_hooke_run_and_the_simulation_continues(tmp_path):
    sets = {"integrator.method": "bdf2", "time.dt": 1e-3, "time.duration": 0.01}
    sim = hooke.Simulation(cloth(**sets))
    x = sim.x
    sim.run(out=str(tmp_path))
    for name in ("scene.toml", "log.csv", "final.csv", "status.txt"):
        assert (tmp_path / name).exists(), name
    fx, fv = read_final(tmp_path / "final.csv")
    assert np.array_equal(x, fx) and np.array_equal(sim.v, fv) and sim.t == 0.01
    sim.step()  # continues with BDF2's history from the run
    plain = hooke.Simulation(cloth(**sets))
    plain.run()
    plain.step()
    assert np.array_equal(sim.x, plain.x)
    with pytest.raises(ValueError):
        sim.run(out=str(tmp_path / "again"))


def test_string_overrides_are_quoted_whatever_they_hold():
    with pytest.raises(hooke.InputError) as e:
        hooke.load_scene(CLOTH, {"integrator.method": 'rk"4\n'})
    assert e.value.key == "integrator.method" and 'rk"4' in e.value.reason


def adaptive_cloth(method="dopri5", **overrides):
    sets = {"time.duration": 0.1, "integrator.method": method, "integrator.adaptive": True,
            "integrator.rtol": 1e-6, "integrator.atol": 1e-8}
    sets.update(overrides)
    return hooke.load_scene(CLOTH, sets)


def test_an_adaptive_run_is_hooke_runs_bit_for_bit_and_continues(tmp_path):
    sets = {"integrator.method": "bs32", "integrator.adaptive": True, "integrator.rtol": 1e-5,
            "integrator.atol": 1e-8, "time.duration": 0.1, "output.interval": 0.03}
    sim = hooke.Simulation(hooke.load_scene(CLOTH, sets))
    sim.run()
    assert sim.t == 0.1
    stats = sim.stats()
    assert stats["accepted"] == sim.steps_taken > 0 and stats["rejected"] >= 0
    cmd = [os.environ["HOOKE_BIN"], "run", CLOTH, "--out", str(tmp_path / "cli"), "--no-progress",
           "--set", "output.png=false"]
    for k, val in sets.items():
        cmd += ["--set", f"{k}={str(val).lower() if isinstance(val, bool) else val}"]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    assert f"bs32: steps {sim.steps_taken}, rejected {stats['rejected']}," in out
    x, v = read_final(tmp_path / "cli" / "final.csv")
    assert np.array_equal(sim.x, x) and np.array_equal(sim.v, v)
    # A checkpoint carries the error control: two halves give the whole run's bits.
    half = hooke.Simulation(hooke.load_scene(CLOTH, sets))
    half.advance(0.06)  # a frame time (2 x 0.03), where the whole run lands too
    half.save_checkpoint(str(tmp_path / "half.bin"))
    rest = hooke.Simulation(hooke.load_scene(CLOTH, sets))
    rest.load_checkpoint(str(tmp_path / "half.bin"))
    rest.run()
    assert np.array_equal(rest.x, sim.x) and rest.stats()["accepted"] == stats["accepted"]


def test_an_adaptive_step_count_is_within_5x_of_scipys_for_the_same_pair():
    """The controller against a textbook one of the same order (issue 21, acceptance 1): scipy's
    RK45 and RK23 on the same ODE, the same rtol and atol, and the achieved errors of both
    against a DOP853 reference at rtol 1e-12."""
    integrate = pytest.importorskip("scipy.integrate")
    for method, scipy_method in (("dopri5", "RK45"), ("bs32", "RK23")):
        for rtol in (1e-4, 1e-6):
            scene = adaptive_cloth(method, **{"mesh.nx": 6, "mesh.ny": 6, "time.duration": 0.5,
                                              "integrator.rtol": rtol, "integrator.atol": 1e-3 * rtol})
            sim = hooke.Simulation(scene)
            system = sim.system
            m = np.repeat(system.masses, 3)
            free = np.repeat(~system.pinned, 3)
            x0, v0 = sim.x.ravel().copy(), sim.v.ravel().copy()
            n3 = x0.size

            def rhs(_, y):
                x, v = y[:n3], y[n3:]
                a = np.where(free, system.forces(x.reshape(-1, 3), v.reshape(-1, 3)).ravel() / m, 0.0)
                return np.concatenate([np.where(free, v, 0.0), a])

            y0 = np.concatenate([x0, v0])
            ref = integrate.solve_ivp(rhs, (0, 0.5), y0, method="DOP853", rtol=1e-12, atol=1e-14)
            theirs = integrate.solve_ivp(rhs, (0, 0.5), y0, method=scipy_method, rtol=rtol,
                                         atol=1e-3 * rtol, first_step=scene.dt)
            sim.run()
            x_ref = ref.y[:n3, -1]
            ours_err = np.abs(sim.x.ravel() - x_ref).max()
            theirs_err = np.abs(theirs.y[:n3, -1] - x_ref).max()
            allowed = rtol * np.abs(x_ref).max() + 1e-3 * rtol
            ours_steps, their_steps = sim.steps_taken, theirs.t.size - 1
            print(f"{method} rtol {rtol:g}: {ours_steps} steps (error {ours_err:.2e}), scipy "
                  f"{scipy_method} {their_steps} steps (error {theirs_err:.2e}); allowed {allowed:.2e}")
            assert ours_err <= 10 * allowed
            assert their_steps / 5 <= ours_steps <= 5 * their_steps
