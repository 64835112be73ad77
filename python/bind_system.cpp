// Python bindings: System, the mass-spring model of a scene as maths.

#include <memory>
#include <utility>

#include "python/bindings.hpp"

namespace hooke::python {

// The docstrings (numpydoc: shapes and units), in the order the bindings use them.
constexpr const char* kSystemDoc = R"doc(The mass-spring model of a scene as maths.

The scene's forces, potential energy and Jacobians K = df/dx and D = df/dv at any state
(x, v), computed by the library the steppers use. Get one from hooke.system(scene) or
Simulation.system. x and v are (n, 3) float64 arrays, n the number of particles (any
array-like of 3n numbers is converted), row i particle i; the matrices are 3n x 3n with
particle i's x, y, z at rows and columns 3i, 3i + 1, 3i + 2. Forces on pinned particles are
computed too, and their rows and columns appear in K and D (implicit solvers remove them).
The scene's constraints (colliders, strain limiting), which act after each step, are not
part of it. SI units: m, m/s, N, J, kg.)doc";

constexpr const char* kForcesDoc =
    R"doc(The total force on each particle at (x, v): the sum of the scene's forces.

For a [fluid] scene these are its external forces (gravity, drag); the pressure forces
belong to the SPH methods.

Parameters
----------
x : array_like, shape (n, 3)
    Positions (m).
v : array_like, shape (n, 3)
    Velocities (m/s).

Returns
-------
ndarray, shape (n, 3), float64
    Forces (N).

Raises
------
ValueError
    If x or v does not have 3n entries.)doc";

constexpr const char* kEnergyDoc =
    R"doc(The potential energy at x: the sum of the forces' potential energies.

Parameters
----------
x : array_like, shape (n, 3)
    Positions (m).

Returns
-------
float
    Potential energy (J).

Raises
------
ValueError
    If x does not have 3n entries.)doc";

constexpr const char* kStiffnessDoc = R"doc(The stiffness matrix K = df/dx at (x, v).

The exact derivative, including that of spring damping with respect to positions (so K
need not be symmetric when springs are damped and v is not zero).

Parameters
----------
x : array_like, shape (n, 3)
    Positions (m).
v : array_like, shape (n, 3)
    Velocities (m/s).
clamp_compressed : bool, optional
    Drop the indefinite transverse term of compressed springs (a clamp of max(0, 1 - L/l),
    in the style of Choi and Ko 2002), making the springs' -K positive semi-definite; False
    gives the exact df/dx.

Returns
-------
scipy.sparse.csr_matrix, shape (3n, 3n), float64
    K (N/m), with the rows and columns of pinned particles.

Raises
------
ValueError
    If x or v does not have 3n entries.)doc";

constexpr const char* kDampingDoc = R"doc(The damping matrix D = df/dv at (x, v).

Parameters
----------
x : array_like, shape (n, 3)
    Positions (m).
v : array_like, shape (n, 3)
    Velocities (m/s).

Returns
-------
scipy.sparse.csr_matrix, shape (3n, 3n), float64
    D (N s/m), with the rows and columns of pinned particles; no stored entries when no
    force depends on v.

Raises
------
ValueError
    If x or v does not have 3n entries.)doc";

constexpr const char* kSystemFunctionDoc =
    R"doc(The mass-spring model of a scene as maths: its forces, energy, K and D.

Parameters
----------
scene : Scene

Returns
-------
System

Raises
------
ValueError
    For an [ode] scene, which has no mass-spring system.)doc";

void bind_system(py::module_& m) {
  py::class_<System>(m, "System", kSystemDoc)
      .def("forces", &System::forces, py::arg("x"), py::arg("v"), kForcesDoc)
      .def("energy", &System::energy, py::arg("x"), kEnergyDoc)
      .def(
          "stiffness",
          [](const System& s,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& v,
             bool clamp) { return s.jacobians(x, v, clamp).first; },
          py::arg("x"), py::arg("v"), py::arg("clamp_compressed") = false, kStiffnessDoc)
      .def(
          "damping",
          [](const System& s,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& v) {
            return s.jacobians(x, v, false).second;
          },
          py::arg("x"), py::arg("v"), kDampingDoc)
      .def_property_readonly("masses", &System::masses,
                             "The particle masses (kg), an (n,) float64 array (a copy).")
      .def_property_readonly(
          "pinned", &System::pinned,
          "Which particles are pinned, an (n,) bool array (a copy): fixed, or moved by "
          "[pin_motion].");

  m.def(
      "system", [](std::shared_ptr<Scene> s) { return System(std::move(s)); }, py::arg("scene"),
      kSystemFunctionDoc);
}

}  // namespace hooke::python
