#include "experiments/info_command.hpp"

#include <cmath>
#include <iomanip>

#include "experiments/natural_frequency.hpp"
#include "hooke/integrators/stability.hpp"
#include "hooke/registry.hpp"

namespace hooke {

void print_scene_info(const Scene& scene, std::ostream& out) {
  out << std::setprecision(6);
  out << "scene:      " << scene.file << "\n";
  if (scene.is_ode()) {
    out << "kind:       first-order ODE test problem, dimension " << scene.ode->dimension() << "\n";
    out << "method:     " << scene.integrator.method << ", dt = " << scene.time.dt
        << " s, duration = " << scene.time.duration << " s (" << scene.time.steps() << " steps)\n";
    return;
  }
  const MassSpringSystem& sys = *scene.system;
  const Index n = sys.num_particles();
  const Index free_dofs = 3 * (n - sys.num_pinned());
  out << "particles:  " << n << " (" << sys.num_pinned() << " pinned)\n";
  out << "springs:    " << scene.edges.size() << "\n";
  out << "DOFs:       " << free_dofs << " free of " << sys.dofs() << "\n";
  out << "forces:    ";
  for (const auto& f : sys.forces()) out << " " << f->name();
  out << "\nconstraints:";
  for (const auto& c : sys.constraints()) out << " " << c->name();
  if (sys.constraints().empty()) out << " none";
  // Memory of a run: state, scratch and force buffers (~12 vectors of 3n doubles), the Jacobian
  // pattern (two matrices of 9 scalars per block, 12 bytes each with indices) and spring arrays.
  const double nnz = 9.0 * double(sys.pattern().num_blocks());
  const double bytes = 12.0 * 8 * double(sys.dofs()) + 2 * 12.0 * nnz + 60.0 * double(scene.edges.size());
  out << "\nmemory:     about " << bytes / (1 << 20) << " MiB (state, scratch, K and D with "
      << std::size_t(nnz) << " stored entries each)\n";
  const double w = largest_natural_frequency(sys, scene.initial);
  out << "omega_max:  " << w << " rad/s at the initial state (period " << 2 * M_PI / w
      << " s), undamped linearisation\n";
  out << "explicit step-size limits on undamped oscillation (h < y / omega_max):\n";
  for (const auto& m : methods()) {
    if (m.kind != MethodKind::Explicit) continue;
    auto stepper = make_explicit_stepper(m.name);
    const double y = imaginary_axis_limit(*stepper);
    out << "  " << std::left << std::setw(18) << m.name << std::right;
    if (y == 0.0)
      out << "none: |R(i y)| > 1 for every h > 0 (needs damping to be stable)\n";
    else
      out << "h < " << y / w << " s (y = " << y << ")\n";
  }
  out << "scene dt:   " << scene.time.dt << " s (" << scene.integrator.method << ")\n";
}

}  // namespace hooke
