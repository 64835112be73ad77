"""hooke: stiff mass-spring systems (strings, hair, cloth) from Python.

    import hooke
    scene = hooke.load_scene("problems/scenes/hanging_cloth.toml", {"time.duration": 0.5})
    sim = hooke.Simulation(scene)
    sim.run()                      # the same states as `hooke run`, bit for bit
    print(sim.t, sim.x[:3])        # sim.x, sim.v: (n, 3) views of the solver's state
    K = sim.system.stiffness(sim.x, sim.v)   # df/dx as a scipy.sparse.csr_matrix

The compiled part is hooke._hooke (python/module.cpp); this file adds the exception classes.
"""


class InputError(ValueError):
    """A scene (file, dict, TOML text or override) that hooke refuses: the message of `hooke run`
    (FILE: KEY: reason), with its parts as attributes."""

    def __init__(self, message, file="", key="", reason=""):
        super().__init__(message)
        self.file = file
        self.key = key
        self.reason = reason


class StepError(RuntimeError):
    """A step that failed (diverged, not converged, a linear solver breaking down); the state
    stays at the last accepted step."""


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
    """`hooke crosscheck`: each method at the scene's dt against a CVODE reference; the rows of
    crosscheck.csv. `out` keeps the files (crosscheck.csv, crosscheck.md) there."""
    return _study(lambda d: _hooke._crosscheck(scene, list(methods), reference_rtol, d), out,
                  ["crosscheck.csv"])


def stability(cases=(), methods=(), k=(), full=False, plot=False, out=None):
    """`hooke stability`: the largest stable step per case, method and stiffness; the rows of
    stability.csv."""
    return _study(lambda d: _hooke._stability(list(cases), list(methods), list(k), full, plot, d),
                  out, ["stability.csv"])


def workprecision(cases=(), methods=(), repeat=3, full=False, plot=False, out=None):
    """`hooke workprecision`: error against wall time per case and method; the rows of
    workprecision.csv and of reference.csv (the fluid cases' rows are in fluid.csv, kept in
    `out`)."""
    return _study(lambda d: _hooke._workprecision(list(cases), list(methods), repeat, full, plot,
                                                  d), out, ["workprecision.csv", "reference.csv"])


def step_convergence(scene_path, full=False, out=None):
    """`hooke step-convergence`: iterations and errors of the whole-step methods per k and h; the
    rows of step_convergence.csv."""
    return _study(lambda d: _hooke._step_convergence(scene_path, full, d), out,
                  ["step_convergence.csv"])
