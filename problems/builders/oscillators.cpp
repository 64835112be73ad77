// Small oscillator scenes with known behaviour: the two-particle stiff spring on a line (exact
// solution) and a row of pendulum-free damped oscillators with increasing damping.
#include <cmath>

#include "problems/builders/mesh_build.hpp"

namespace hooke {

void build_two_particle(TableReader& mesh, TableReader& springs, MeshBuild& out) {
  const double m = mesh.positive("mass", 1.0);
  const double L = mesh.positive("rest_length", 1.0);
  const double s = mesh.number("stretch", 0.1 * L);
  if (L + s <= 0.0)
    mesh.fail("stretch", "rest_length + stretch must be > 0 (particles would cross)");
  const double k = springs.non_negative("stiffness", 1e4);
  const double c = springs.non_negative("damping", 0.0);
  out.resize(2);
  out.masses.setConstant(m);
  out.x.segment<3>(3) = Vec3(L + s, 0.0, 0.0);
  out.springs.push_back({0, 1, k, L, c, true});
  // Relative coordinate r = x1 - x0 obeys (m/2) r'' = -k (r - L) - c r' around a fixed centre:
  // underdamped solution with omega0 = sqrt(2k/m), zeta = c / sqrt(2 k m) (c = 0: cosine).
  if (k > 0.0) {
    const double w0 = std::sqrt(2.0 * k / m);
    const double zeta = c / std::sqrt(2.0 * k * m);
    if (zeta < 1.0) {
      const double wd = w0 * std::sqrt(1.0 - zeta * zeta);
      const double centre = 0.5 * (L + s);
      out.exact = [=](double t, State& st) {
        const double e = std::exp(-zeta * w0 * t);
        const double q = s * e * (std::cos(wd * t) + zeta * w0 / wd * std::sin(wd * t));
        const double dq = -s * e * (w0 * w0 / wd) * std::sin(wd * t);
        st.x.setZero(6);
        st.v.setZero(6);
        st.x[0] = centre - 0.5 * (L + q);
        st.x[3] = centre + 0.5 * (L + q);
        st.v[0] = -0.5 * dq;
        st.v[3] = 0.5 * dq;
        st.t = t;
      };
    }
  }
}

void build_damped_springs(TableReader& mesh, TableReader& springs, MeshBuild& out) {
  const long long count = mesh.integer("count", 5, 1, 10000000LL);
  check_size(mesh, "count", 2.0 * double(count), double(count));
  const double m = mesh.positive("mass", 1.0);
  const double L = mesh.positive("rest_length", 1.0);
  const double spacing = mesh.positive("spacing", 0.5);
  const double disp = mesh.number("displacement", 0.2);
  if (L + disp <= 0.0) mesh.fail("displacement", "rest_length + displacement must be > 0");
  const double k = springs.non_negative("stiffness", 100.0);
  const double cmax = springs.non_negative("max_damping", 2.0 * std::sqrt(k * m));
  // Oscillator p hangs below its pinned anchor; its damping grows linearly from 0 to max_damping
  // (the default max_damping is critical damping 2 sqrt(k m)).
  out.resize(2 * count);
  for (long long p = 0; p < count; ++p) {
    const int a = int(2 * p), b = int(2 * p + 1);
    out.masses[a] = out.masses[b] = m;
    out.pinned[size_t(a)] = 1;
    out.x.segment<3>(3 * a) = Vec3(spacing * double(p), 0.0, 0.0);
    out.x.segment<3>(3 * b) = Vec3(spacing * double(p), -(L + disp), 0.0);
    const double c = count == 1 ? cmax : cmax * double(p) / double(count - 1);
    out.springs.push_back({a, b, k, L, c, true});
  }
}

}  // namespace hooke
