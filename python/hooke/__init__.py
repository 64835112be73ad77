"""hooke: stiff mass-spring systems (strings, hair, cloth) from Python.

    import hooke
    scene = hooke.load_scene("problems/scenes/hanging_cloth.toml", {"time.duration": 0.5})
    sim = hooke.Simulation(scene)
    sim.run()                      # the same states as `hooke run`, bit for bit
    print(sim.t, sim.x[:3])        # sim.x, sim.v: (n, 3) views of the solver's state
    K = sim.system.stiffness(sim.x, sim.v)   # df/dx as a scipy.sparse.csr_matrix

Positions, velocities and forces are (n, 3) numpy float64 arrays, n the number of particles;
units are SI (m, m/s, s, kg, N, J). help(hooke.NAME) documents each name with its parameters,
shapes, units and what it raises.

API
---
load_scene(path, overrides)          a Scene from a file, or a shipped scene by name
Scene                                a loaded, validated scene; Scene.from_toml, Scene.from_dict
Simulation(scene)                    the scene's run stepped from Python; x and v as numpy views
System                               the model as maths: forces, energy, K = df/dx, D = df/dv
system(scene)                        the scene's System (also Simulation.system)
methods()                            the time-stepping methods of this build, as dicts
linear_solvers()                     the linear solver backends of this build, as dicts
crosscheck(scene, methods)           `hooke crosscheck`: each method against a CVODE reference
stability(cases, methods, k)         `hooke stability`: the largest stable step per k
workprecision(cases, methods)        `hooke workprecision`: error against wall time
step_convergence(scene_path)         `hooke step-convergence`: one backward-Euler step's solvers
InputError                           a scene or argument that hooke refuses (a ValueError)
StepError                            a step or study that failed (a RuntimeError)

The compiled part is hooke._hooke (python/module.cpp); this file adds the exception classes and
the studies' wrappers, which read their CSV tables back.
"""


class InputError(ValueError):
    """A scene (file, dict, TOML text or override) that hooke refuses: the message of `hooke run`
    (FILE: KEY: reason), with its parts as attributes.

    Attributes
    ----------
    file : str
        The scene file (or '<dict>', '<overrides>', the checkpoint file, ...).
    key : str
        The dotted key at fault ('mesh.nx', 'integrator.method', ...).
    reason : str
        What is wrong with it.
    """

    def __init__(self, message, file="", key="", reason=""):
        super().__init__(message)
        self.file = file
        self.key = key
        self.reason = reason


class StepError(RuntimeError):
    """A step that failed (diverged, not converged, a linear solver breaking down); the state
    stays at the last accepted step. The studies (crosscheck, stability, workprecision,
    step_convergence) raise it too when they exit with a non-zero code."""


# The standard modules under private names: the package's namespace is its API (dir(hooke)).
import csv as _csv  # noqa: E402
import os as _os  # noqa: E402
import tempfile as _tempfile  # noqa: E402

# hooke's wait policies for libgomp's and OpenBLAS's idle threads (solver/parallel/thread_policy.hpp),
# which the libraries read when they are loaded: set here, before the compiled module loads them,
# unless the user chose them (or another module already loaded the library, when this has no
# effect).
if "GOMP_SPINCOUNT" not in _os.environ and "OMP_WAIT_POLICY" not in _os.environ:
    _os.environ["GOMP_SPINCOUNT"] = "10000"
_os.environ.setdefault("OPENBLAS_THREAD_TIMEOUT", "20")

from . import _hooke  # noqa: E402
from ._hooke import (Scene, Simulation, System, linear_solvers, load_scene,  # noqa: E402,F401
                     methods, system)

__all__ = ["InputError", "StepError", "Scene", "Simulation", "System", "load_scene", "methods",
           "linear_solvers", "system", "crosscheck", "stability", "workprecision",
           "step_convergence"]


def _value(text):
    """A CSV field as a float where it is a number ('inf', 'nan' included), else the text."""
    try:
        return float(text)
    except ValueError:
        return text


def _table(path):
    with open(path, newline="") as f:
        return [{k: _value(v) for k, v in row.items()} for row in _csv.DictReader(f)]


def _study(run, out, tables):
    """Runs a study driver into `out` (a temporary folder if None) and returns its CSV tables as
    lists of dicts (numbers as floats); raises StepError if the study reports a failed run."""
    with _tempfile.TemporaryDirectory() as tmp:
        folder = out if out is not None else tmp
        code = run(folder)
        if code != 0:
            raise StepError(f"the study stopped with exit code {code} (see its messages above)")
        result = [_table(_os.path.join(folder, t)) for t in tables]
    return result[0] if len(result) == 1 else tuple(result)


def crosscheck(scene, methods=(), reference_rtol=1e-10, out=None):
    """`hooke crosscheck`: each method at the scene's dt against a CVODE reference.

    Position errors against CVODE (BDF) at tight tolerance, at the final time and over the
    trajectory's samples, and the final energy error.

    Parameters
    ----------
    scene : Scene
        A mass-spring scene with time.duration > 0.
    methods : sequence of str, optional
        Registry names (hooke.methods()); empty: every method of this build but the fluid ones.
    reference_rtol : float, optional
        The CVODE reference's relative tolerance.
    out : str, optional
        A folder that keeps the files (crosscheck.csv, crosscheck.md); None: a temporary one.

    Returns
    -------
    list of dict
        The rows of crosscheck.csv, one per method, numbers as float: 'method', 'dt' (s),
        'wall_s' (s), 'rms_err_final' and 'max_err_final' (RMS over particles and largest
        |x_i - x_ref_i| at the final time, m), 'rms_err_traj' and 'max_err_traj' (their
        maxima over the samples, m), 'energy_err_final' (E(T) - E_ref(T), J) and 'status'
        ('ok', 'not-converged in N steps', or why the run stopped; its errors are then nan).

    Raises
    ------
    InputError
        For an [ode] scene, a duration of 0 or an unknown method.
    StepError
        If the study exits with a non-zero code (e.g. the CVODE reference did not complete).
    """
    return _study(lambda d: _hooke._crosscheck(scene, list(methods), reference_rtol, d), out,
                  ["crosscheck.csv"])


def stability(cases=(), methods=(), k=(), full=False, plot=False, out=None):
    """`hooke stability`: the largest stable step per case, method and stiffness.

    For each case, method and k, h is scanned down from 0.1 s and the stable-unstable bracket
    bisected; a run is unstable if a step fails, the state becomes non-finite, the energy grows
    past `hooke run`'s divergence limit or a spring's strain exceeds the case's bound.

    Parameters
    ----------
    cases : sequence of str, optional
        'two_particle', 'hanging_cloth', 'stiff_flexion', 'dam_break_2d', 'bending_strand_41',
        'bending_strand_81' ('bending_strand_161' with full); empty: all.
    methods : sequence of str, optional
        Study method labels or registry names; empty: the stability map's methods.
    k : sequence of float, optional
        The cases' stiffness parameter: k (N/m) for the spring cases, the speed of sound c0
        (m/s) for dam_break_2d, EI (N m^2) for the strands. Empty: each case's own values, else
        1e1 .. 1e7, one per decade (half decades with full).
    full : bool, optional
        The paper's size (16 x 16 cloths, more values of k).
    plot : bool, optional
        Also draw stability_<case>.png and .md into the folder (useful with out).
    out : str, optional
        A folder that keeps the files (stability.csv); None: a temporary one.

    Returns
    -------
    list of dict
        The rows of stability.csv, one per case, method and k, numbers as float: 'case',
        'label' (the study's method label), 'method' (registry name), 'k', 'omega_max' (the
        largest natural frequency at the initial state, rad/s; nan for the fluid case),
        'h_theory' (s: y / omega_max for explicit methods, the CFL step for the fluid case,
        else nan), 'h_stable' (the largest stable step found, s; 0 if none), 'h_unstable' (the
        smallest unstable step above it, s; inf if none), 'bound' ('bracketed', 'below' or
        'above' the range of h tried), 'runs', 'wall_s' (s), 'reason' (why the run at
        h_unstable was unstable) and 'parameter' (what k is, with its unit: 'k (N/m)', ...).

    Raises
    ------
    InputError
        For an unknown case or method.
    StepError
        If the study exits with a non-zero code.
    """
    return _study(lambda d: _hooke._stability(list(cases), list(methods), list(k), full, plot, d),
                  out, ["stability.csv"])


def workprecision(cases=(), methods=(), repeat=3, full=False, plot=False, out=None):
    """`hooke workprecision`: error against wall time per case and method.

    Each method over each case's step sizes (tolerances for adaptive methods), against a CVODE
    reference whose own error is estimated too.

    Parameters
    ----------
    cases : sequence of str, optional
        'chain', 'hanging_cloth', 'stiff_cloth', and the fluid case 'dam_break_2d'
        ('dam_break_2d_fine' with full); empty: all.
    methods : sequence of str, optional
        Study method labels or registry names; empty: all.
    repeat : int, optional
        Runs per point; the wall time is their median.
    full : bool, optional
        The paper's size (more step sizes and tolerances, 16 x 16 cloths, longer runs of the
        chain and the stiff cloth).
    plot : bool, optional
        Also draw the figures into the folder (useful with out).
    out : str, optional
        A folder that keeps the files (workprecision.csv, reference.csv, fluid.csv,
        fronts.csv); None: a temporary one.

    Returns
    -------
    tuple of (list of dict, list of dict)
        The rows of workprecision.csv, one per case, method and h (or rtol), numbers as float:
        'case', 'label', 'method', 'h' (s), 'rtol', 'wall_s' (s, the median), 'steps',
        'rms_err_final', 'max_err_final', 'rms_err_traj', 'max_err_traj' (position errors, m),
        'status', 'repeats', 'resolved_final' and 'resolved_traj' (1 if the error is above the
        reference's own error estimate, else 0); and the rows of reference.csv, one per case:
        'case', 'rtol', 'wall_s' (s), 'err_rms_final', 'err_rms_traj', 'err_max_traj' (the
        reference's own error estimate, m) and 'how'. The fluid case's rows are in fluid.csv,
        kept in out.

    Raises
    ------
    InputError
        For an unknown case or method.
    StepError
        If the study exits with a non-zero code (e.g. a reference did not complete).
    """
    return _study(lambda d: _hooke._workprecision(list(cases), list(methods), repeat, full, plot,
                                                  d), out, ["workprecision.csv", "reference.csv"])


def step_convergence(scene_path, full=False, out=None):
    """`hooke step-convergence`: how fast each backward-Euler solver reaches the exact step.

    One backward-Euler step of the cloth at scene_path with structural stiffness k (shear k/5,
    flexion k/50), for k = 1e2, 1e4, 1e6 N/m at h = 1e-2 s: the iterates of the local/global
    methods, vertex block descent, Newton and XPBD against the exact step.

    Parameters
    ----------
    scene_path : str
        A cloth scene file (a path, e.g. problems/scenes/hanging_cloth_16.toml).
    full : bool, optional
        The paper's size: k = 1e2 .. 1e6 N/m at h = 1e-3, 1e-2 and 1/30 s.
    out : str, optional
        A folder that keeps the files (step_convergence.csv, .md, .png); None: a temporary one.

    Returns
    -------
    list of dict
        The rows of step_convergence.csv, one per sample of each method's convergence curve,
        numbers as float:
        'k' (N/m), 'h' (s), 'method', 'iterations', 'wall_seconds' (s), 'objective_error'
        (the fraction of the initial objective gap left, (g(x) - g(x*)) / (g(y) - g(x*))) and
        'position_error' (max |x - x*| / max |x* - x0|).

    Raises
    ------
    InputError
        For a scene that does not load.
    StepError
        If the study exits with a non-zero code (also in a build without CHOLMOD, or when its
        plot script fails).
    """
    return _study(lambda d: _hooke._step_convergence(scene_path, full, d), out,
                  ["step_convergence.csv"])
