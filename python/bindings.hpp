#pragma once
// What the binding files of the Python module share (python/bind_*.cpp, module.cpp): the
// conversions between Python and hooke values, the error of a failed step, the model as maths,
// and one bind_* function per area, each a thin translation to the library.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "problems/scene.hpp"

namespace hooke::python {

namespace py = pybind11;

/// A float64 array argument, converted (and made contiguous) as needed.
using ArrayArg = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// A step that failed (not accepted): raised in Python as hooke.StepError.
struct StepFailed : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// TOML text of a Python dict with a scene file's sections and keys, for Scene.from_dict.
std::string toml_text(const py::dict& d);
/// "section.key=value" override items of a dict {'section.key': value}, as hooke run --set takes
/// them.
std::vector<std::string> override_items(const py::dict& overrides);
/// (n, 3) float64 numpy array viewing the 3n vector `data` without copying. Its base keeps
/// `owner` alive and counts the view in *live_views while it exists.
py::array_t<double> view(double* data, Index n, py::handle owner, long long* live_views);
/// A 3n vector from an (n, 3) or 3n array-like.
Vec vector_of(const ArrayArg& a, Index n3, const char* what);
/// A scipy.sparse.csr_matrix of an Eigen column-major sparse matrix.
py::object to_scipy(const SparseMatrix& m);

/// The mass-spring model of a scene as maths: forces, potential and Jacobians at any (x, v).
class System {
 public:
  explicit System(std::shared_ptr<Scene> scene) : m_scene(std::move(scene)) {
    if (!m_scene->system) throw py::value_error("an [ode] scene has no mass-spring system");
  }
  const MassSpringSystem& sys() const { return *m_scene->system; }
  Index n() const { return sys().num_particles(); }

  py::array_t<double> forces(const ArrayArg& x, const ArrayArg& v) const {
    const Index n3 = sys().dofs();
    const Vec xv = vector_of(x, n3, "x"), vv = vector_of(v, n3, "v");
    py::array_t<double> out({n(), Index(3)});
    Eigen::Map<Vec> f(out.mutable_data(), n3);
    sys().compute_forces(xv, vv, f);
    return out;
  }
  double energy(const ArrayArg& x) const {
    return sys().potential_energy(vector_of(x, sys().dofs(), "x"));
  }
  /// (K, D) at (x, v).
  std::pair<py::object, py::object> jacobians(const ArrayArg& x, const ArrayArg& v,
                                              bool clamp) const {
    const Index n3 = sys().dofs();
    Jacobians J = sys().make_jacobians();
    JacobianOptions o;
    o.clamp_compressed = clamp;
    o.damping_position_terms = true;
    sys().assemble_jacobians(vector_of(x, n3, "x"), vector_of(v, n3, "v"), J, o);
    if (J.D.nonZeros() == 0) J.D = SparseMatrix(n3, n3);
    return {to_scipy(J.K), to_scipy(J.D)};
  }
  py::array_t<double> masses() const {
    const Vec& m = sys().masses();
    py::array_t<double> out(m.size());
    std::copy(m.data(), m.data() + m.size(), out.mutable_data());
    return out;
  }
  py::array_t<bool> pinned() const {
    const auto& p = sys().pinned();
    py::array_t<bool> out(Index(p.size()));
    for (size_t i = 0; i < p.size(); ++i) out.mutable_data()[i] = p[i] != 0;
    return out;
  }

 private:
  std::shared_ptr<Scene> m_scene;
};

void bind_scene(py::module_& m);       // Scene, load_scene
void bind_system(py::module_& m);      // System, system
void bind_simulation(py::module_& m);  // Simulation
void bind_studies(py::module_& m);     // _crosscheck, _stability, _workprecision, ...
void bind_registry(py::module_& m);    // methods, linear_solvers

}  // namespace hooke::python
