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


from ._hooke import (Scene, Simulation, System, linear_solvers, load_scene,  # noqa: E402,F401
                     methods, system)

__all__ = ["InputError", "StepError", "Scene", "Simulation", "System", "load_scene", "methods",
           "linear_solvers", "system"]
