#include "hooke/whole_step/ceres/ceres_implicit_stepper.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "hooke/whole_step/spring_potential_forces.hpp"

namespace hooke {

namespace {

/// Ceres' type for each CeresLinearSolver, in the enum's order.
constexpr ceres::LinearSolverType kLinearSolverTypes[] = {ceres::SPARSE_NORMAL_CHOLESKY,
                                                          ceres::DENSE_QR, ceres::CGNR};

/// Ceres' termination type as a lowercase hyphenated word ("no-convergence").
std::string termination_name(ceres::TerminationType t) {
  std::string s = ceres::TerminationTypeToString(t);
  for (char& c : s)
    c = c == '_' ? '-' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// Per-step data of one spring, 4 doubles: d_y = y_a - y_b (3) and c0 = |d_y|^2 - L^2 (1).
constexpr int kSpringData = 4;

/// Geometry of a spring at the unknowns dx = x - y: d = x_a - x_b = d_y + e with e = dx_a - dx_b,
/// l = |d| and the stretch l - L. Levenberg-Marquardt accepts a step by comparing two costs, so
/// near the solution the rounding noise of the residuals limits how far it converges; computing
/// l - L = (l^2 - L^2) / (l + L) with l^2 - L^2 = c0 + e . (2 d_y + e), c0 once per step, gives
/// the stretch to a few eps of itself, where |x_a - x_b| - L is only good to eps * l (and to
/// eps * |x| if d is formed from absolute positions).
struct SpringGeometry {
  Vec3 d;
  double l;
  double stretch;
};

inline SpringGeometry spring_geometry(const double* data, const Vec3& e, double L) {
  const Eigen::Map<const Vec3> dy(data);
  SpringGeometry g;
  g.d = dy + e;
  g.l = g.d.norm();
  g.stretch = g.l + L > 0.0 ? (data[3] + e.dot(2.0 * dy + e)) / (g.l + L) : 0.0;
  return g;
}

/// Energy formulation. Residual block r = diag(w) s (dx + o) of one particle, with constant
/// weights w (3 values), a per-step scale s and a per-step offset o (3 values, or none) read from
/// the stepper's buffers:
///   inertia: w = sqrt(m_i), s = 1/h,       o = 0                   (r = sqrt(m)/h (x - y))
///   drag:    w = sqrt(c),   s = 1/sqrt(h), o = y - x0 - h w_wind   (r = sqrt(c/h) (x - x0 - h w))
/// Jacobian dr/dx = diag(w) s (3 x 3, row-major as Ceres wants).
class WeightedDistanceCost final : public ceres::SizedCostFunction<3, 3> {
 public:
  WeightedDistanceCost(const Vec3& weight, const double* scale, const double* offset)
      : m_w(weight), m_scale(scale), m_offset(offset) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double s = *m_scale;
    const double* dx = parameters[0];
    for (int k = 0; k < 3; ++k)
      residuals[k] = m_w[k] * s * (m_offset ? dx[k] + m_offset[k] : dx[k]);
    if (jacobians && jacobians[0])
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) jacobians[0][3 * r + c] = r == c ? m_w[r] * s : 0.0;
    return true;
  }

 private:
  Vec3 m_w;
  const double* m_scale;
  const double* m_offset;
};

/// Energy formulation. Residual block of one Hooke spring: r = sqrt(k) (l - L), d = x_a - x_b,
/// l = |d|, u = d / l, so that 1/2 r^2 is the spring energy k/2 (l - L)^2. Jacobians
/// dr/dx_a = sqrt(k) u^T and dr/dx_b = -sqrt(k) u^T (1 x 3 each). At l = 0 the direction is
/// undefined: both are zero, matching the zero force of hooke_spring_kernel there.
class SpringCost final : public ceres::SizedCostFunction<1, 3, 3> {
 public:
  SpringCost(double k, double L, const double* data)
      : m_sqrt_k(std::sqrt(k)), m_L(L), m_data(data) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Vec3> dxa(parameters[0]), dxb(parameters[1]);
    const SpringGeometry g = spring_geometry(m_data, dxa - dxb, m_L);
    residuals[0] = m_sqrt_k * g.stretch;
    if (jacobians) {
      const Vec3 J = g.l > 0.0 ? Vec3((m_sqrt_k / g.l) * g.d) : Vec3::Zero();
      for (int c = 0; c < 3; ++c) {
        if (jacobians[0]) jacobians[0][c] = J[c];
        if (jacobians[1]) jacobians[1][c] = -J[c];
      }
    }
    return true;
  }

 private:
  double m_sqrt_k, m_L;
  const double* m_data;
};

/// The positions x = y + dx of the K particles of element e of `set` (each block a parameter of
/// Ceres, dx_a = parameters[slot[a]]) written into a per-thread 3n vector, at their ids (the rest
/// of it is never read): the element sets read positions by particle id. Sized on first use.
const Vec& stencil_positions(const ElementSet& set, size_t e, const Vec& y,
                             double const* const* parameters, const int* slot) {
  thread_local Vec x;
  if (x.size() != y.size()) x.setZero(y.size());
  const int* s = set.stencil(e);
  for (int a = 0; a < set.stencil_size(); ++a)
    x.segment<3>(3 * s[a]) = y.segment<3>(3 * s[a]) + Eigen::Map<const Vec3>(parameters[slot[a]]);
  return x;
}

/// Energy formulation. Residual block of one element of the constraint form k/2 C^2
/// (ElementSet::has_constraint): r = sqrt(k) C(x_e), x = y + dx, so 1/2 r^2 is the element's
/// energy; dr/dx_a = sqrt(k) dC_a (1 x 3 each). Parameter block a is the stencil's particle a.
class ElementCost final : public ceres::DynamicCostFunction {
 public:
  ElementCost(const ElementSet& set, size_t e, const Vec& y) : m_set(set), m_e(e), m_y(y) {
    for (int a = 0; a < set.stencil_size(); ++a) AddParameterBlock(3);
    SetNumResiduals(1);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    static constexpr int kSlots[kMaxStencil] = {0, 1, 2, 3, 4, 5};
    const Vec& x = stencil_positions(m_set, m_e, m_y, parameters, kSlots);
    double C = 0.0, k = 0.0;
    std::array<double, kMaxElementDofs> dC;
    m_set.constraint(x, m_e, C, dC.data(), k);
    const double sqrt_k = std::sqrt(k);
    residuals[0] = sqrt_k * C;
    if (jacobians)
      for (int a = 0; a < m_set.stencil_size(); ++a)
        if (jacobians[a])
          for (int c = 0; c < 3; ++c) jacobians[a][c] = sqrt_k * dC[size_t(3 * a + c)];
    return true;
  }

 private:
  const ElementSet& m_set;
  size_t m_e;
  const Vec& m_y;
};

/// Residual formulation. One residual block per free particle i: its backward Euler residual
///   G_i = m_i / h^2 (x_i - y_i) + c_i / h (x_i - x0_i - h w) - sum_springs f_i(x)      (N)
/// i.e. M (v1 - v0) / h - f(x1, v1) with v1 = (x1 - x0) / h, over the parameter blocks of i and of
/// its spring neighbours (parameter slot 0 is i itself). Jacobians: dG_i/dx_i = m_i/h^2 I + c_i/h I
/// - sum B_s and dG_i/dx_j = sum over springs (i, j) of B_s, with B_s = df_a/dx_a of the spring as
/// in hooke_spring_kernel::dfdx, unclamped, its factor 1 - L/l computed as (l - L) / l.
class ParticleResidualCost final : public ceres::DynamicCostFunction {
 public:
  struct Incident {
    double k, L;
    const double* data;  ///< the spring's per-step data
    int slot;            ///< parameter slot of the other end
    double sign;         ///< +1 if i is the spring's first end (a), -1 if it is b
  };
  /// An element that holds i: G_i += dE_e/dx_i, dG_i/dx_a += the Hessian's block (i, a).
  struct IncidentElement {
    const ElementSet* set;
    size_t e;
    int self;                             ///< i's place in the stencil
    std::array<int, kMaxStencil> slot{};  ///< parameter slot of each stencil particle
  };
  ParticleResidualCost(double mass, const Vec3& drag_c, const double* inv_h,
                       const double* drag_offset, std::vector<Incident> incident,
                       std::vector<IncidentElement> elements, const Vec& y, int num_slots)
      : m_mass(mass),
        m_c(drag_c),
        m_inv_h(inv_h),
        m_offset(drag_offset),
        m_incident(std::move(incident)),
        m_elements(std::move(elements)),
        m_y(y) {
    for (int s = 0; s < num_slots; ++s) AddParameterBlock(3);
    SetNumResiduals(3);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double inv_h = *m_inv_h;
    const Eigen::Map<const Vec3> dxi(parameters[0]), off(m_offset);
    const Vec3 c_h = m_c * inv_h;
    Eigen::Map<Vec3> G(residuals);
    G = (m_mass * inv_h * inv_h) * dxi + c_h.cwiseProduct(dxi + off);
    const int slots = static_cast<int>(parameter_block_sizes().size());
    if (jacobians)
      for (int s = 0; s < slots; ++s)
        if (jacobians[s]) Eigen::Map<Mat3R>(jacobians[s]).setZero();
    if (jacobians && jacobians[0])
      Eigen::Map<Mat3R>(jacobians[0]).diagonal() = Vec3::Constant(m_mass * inv_h * inv_h) + c_h;
    for (const Incident& s : m_incident) {
      const Eigen::Map<const Vec3> dxj(parameters[s.slot]);
      const SpringGeometry g = spring_geometry(s.data, s.sign * (dxi - dxj), s.L);
      // Force on the first end f_a = -k (l - L) u; on i it is sign * f_a.
      if (g.l > 0.0) G += (s.sign * s.k * g.stretch / g.l) * g.d;
      if (!jacobians) continue;
      Mat3 B = -s.k * Mat3::Identity();  // l = 0: hooke_spring_kernel's finite surrogate
      if (g.l > 0.0) {
        const Vec3 u = g.d / g.l;
        const Mat3 uu = u * u.transpose();
        B = -s.k * (uu + (g.stretch / g.l) * (Mat3::Identity() - uu));
      }
      if (jacobians[0]) Eigen::Map<Mat3R>(jacobians[0]) -= B;
      if (jacobians[s.slot]) Eigen::Map<Mat3R>(jacobians[s.slot]) += B;
    }
    std::array<double, kMaxElementDofs> g;
    std::array<double, kMaxElementDofs * kMaxElementDofs> H;
    for (const IncidentElement& in : m_elements) {
      const Vec& x = stencil_positions(*in.set, in.e, m_y, parameters, in.slot.data());
      in.set->gradient_hessian(x, in.e, in.e + 1, PsdProjection::None, g.data(),
                               jacobians ? H.data() : nullptr);
      G += Eigen::Map<const Vec3>(g.data() + 3 * in.self);
      if (!jacobians) continue;
      const int dofs = 3 * in.set->stencil_size();
      for (int a = 0; a < in.set->stencil_size(); ++a) {
        double* J = jacobians[in.slot[size_t(a)]];
        if (!J) continue;
        for (int r = 0; r < 3; ++r)  // row-major: J[3 r + c] = d G_r / d dx_a,c
          for (int c = 0; c < 3; ++c)
            J[3 * r + c] += H[size_t((3 * a + c) * dofs + 3 * in.self + r)];
      }
    }
    return true;
  }

 private:
  using Mat3R = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
  double m_mass;
  Vec3 m_c;
  const double* m_inv_h;
  const double* m_offset;
  std::vector<Incident> m_incident;
  std::vector<IncidentElement> m_elements;
  const Vec& m_y;
};

}  // namespace

OptionError CeresImplicitOptions::validate() const {
  std::ostringstream os;
  std::string field;
  auto bad_tolerance = [](double t) { return !(t >= 0.0) || !std::isfinite(t); };
  const std::pair<const char*, double> tolerances[] = {{"function_tolerance", function_tolerance},
                                                       {"gradient_tolerance", gradient_tolerance},
                                                       {"parameter_tolerance", parameter_tolerance},
                                                       {"residual_tolerance", residual_tolerance}};
  if (max_iterations < 1) {
    field = "max_iterations";
    os << "max_iterations = " << max_iterations << ": must be >= 1";
  } else if (threads < 1) {
    field = "threads";
    os << "threads = " << threads << ": must be >= 1";
  } else {
    for (const auto& [name, value] : tolerances)
      if (field.empty() && bad_tolerance(value)) {
        field = name;
        os << name << " = " << value << ": must be finite and >= 0";
      }
  }
  return {field, os.str()};
}

std::string ceres_implicit_unsupported(const MassSpringSystem& system) {
  const auto& forces = system.forces();
  for (size_t n = 0; n < forces.size(); ++n) {
    const Force* f = forces[n].get();
    std::ostringstream os;
    os << "ceres-implicit: force '" << f->name() << "' (force " << n << " of the system) ";
    const ForceTerms t = f->terms();
    if (t.form == ForceForm::ElementDampers) continue;  // named after every other obstacle
    if (t.form == ForceForm::Elements) {
      if (t.elements->has_constraint()) continue;  // a sum of squares: sqrt(k) C per element
      os << "has '" << t.elements->name()
         << "' elements without the constraint form k/2 C^2, which ceres-implicit needs for its "
            "least squares; "
         << element_set_takers(*t.elements);
      return os.str();
    }
    if (t.form == ForceForm::Springs) {
      const auto& c = t.springs->coeff;
      const auto it = std::find_if(c.begin(), c.end(), [](double k) { return !(k >= 0.0); });
      if (it != c.end()) {
        os << "has a spring with stiffness k = " << *it
           << ": k/2 (l - L)^2 is a sum of squares only for k >= 0";
        return os.str();
      }
    } else if (t.form == ForceForm::Gravity) {
      // Constant: folds into y.
    } else if (t.form == ForceForm::Drag) {
      if (!(t.drag >= 0.0)) {
        os << "has drag coefficient c = " << t.drag
           << ": c/(2h) |x - x0 - h w|^2 is a sum of squares only for c >= 0";
        return os.str();
      }
    } else if (t.form == ForceForm::Dampers) {
      os << "(axial spring damping) is not supported: its force -c (u . (v_a - v_b)) u is not "
            "the gradient of any function of x1, so the backward Euler step is not a "
            "minimisation; set the damping to 0 (air-drag is supported) or use method "
            "'implicit' with beta = 1 and newton_iterations > 1 for the same step";
      return os.str();
    } else {
      os << "is not known to the ceres-implicit backend, which supports hooke-spring, gravity, "
            "air-drag and element sets of the constraint form only; use method 'implicit' with "
            "beta = 1 and newton_iterations > 1";
      return os.str();
    }
  }
  // The element sets' damping last: then dropping it is enough.
  for (size_t n = 0; n < forces.size(); ++n) {
    const ForceTerms t = forces[n]->terms();
    if (t.form != ForceForm::ElementDampers) continue;
    std::ostringstream os;
    os << "ceres-implicit: force '" << forces[n]->name() << "' (force " << n
       << " of the system) damps the '" << t.elements->name()
       << "' elements (bending.damping): a dissipation on their rates is not the gradient of any "
          "function of x1, so the backward Euler step is not a minimisation; set it to 0 "
          "(air-drag is supported), or use vbd, or method 'implicit' with beta = 1 and "
          "newton_iterations > 1 for the same step";
    return os.str();
  }
  return "";
}

struct CeresImplicitStepper::Impl {
  const MassSpringSystem& system;
  CeresImplicitOptions options;
  StepperStats totals;  // over all steps; solve_seconds = time in ceres::Solve
  ceres::Solver::Options solver_options;
  // The unknowns are dx = x - y, the deviation from the inertial prediction y, rather than x:
  // residuals then lose digits relative to themselves, never to |x| (see spring_geometry).
  // The cost functions read the per-step data from these buffers (3n vectors unless noted), which
  // are never resized after construction; the parameter blocks are the 3-vectors of dx.
  Vec dx;           // parameter values: initial guess 0 (x = y) in, x1 - y out
  Vec dy;           // y - x0 = h v0 + h^2 M^-1 f_ext (0 for pinned particles: they stay at x0)
  Vec y;            // x0 + dy: the element costs form positions y + dx
  Vec drag_off;     // y - x0 - h w, per DOF with drag
  Vec spring_data;  // kSpringData per spring (see spring_geometry)
  double inv_h = 1.0, inv_sqrt_h = 1.0;
  // Constant data read from the forces at construction.
  Vec f_ext;   // sum of the constant (gravity) forces, N
  Vec drag_c;  // summed linear drag coefficient per DOF (-diag of df/dv), kg/s
  Vec drag_b;  // summed drag force at v = 0 (c w), N
  std::vector<int> free_particles;
  std::vector<int> spring_a, spring_b;  // springs with k > 0 and a free end
  std::vector<double> spring_k, spring_L;
  std::vector<const ElementSet*> elements;  // every element force's set, in force order
  Index num_residuals = 0;
  Vec f;  // scratch for the backward Euler residual of the result
  ceres::Problem problem;
  ceres::Solver::Summary summary;
  CeresReport report;

  Impl(const MassSpringSystem& s, CeresImplicitOptions o);
  void add_energy_blocks();
  void add_residual_blocks();
  void set_step_data(const State& s0, double h);
};

CeresImplicitStepper::Impl::Impl(const MassSpringSystem& s, CeresImplicitOptions o)
    : system(s), options(std::move(o)) {
  const Index n = system.num_particles(), N = system.dofs();
  for (Vec* v : {&dx, &dy, &y, &drag_off, &f_ext, &drag_c, &drag_b, &f}) v->setZero(N);
  for (const auto& force : system.forces())
    if (const ForceTerms t = force->terms(); t.form == ForceForm::Elements)
      elements.push_back(t.elements);
  const std::vector<char>& pinned = system.pinned();

  // Constant forces and linear drag from the forces' terms: gravity's force and drag's c w as
  // their forces at x = v = 0, drag's c summed per DOF.
  const Vec zero = Vec::Zero(N);
  for (const auto& force : system.forces()) {
    const ForceTerms t = force->terms();
    if (t.form == ForceForm::Gravity) force->add_forces(zero, zero, f_ext);
    if (t.form == ForceForm::Drag) {
      force->add_forces(zero, zero, drag_b);
      drag_c.array() += t.drag;
    }
  }

  for (Index i = 0; i < n; ++i)
    if (!pinned[size_t(i)]) free_particles.push_back(int(i));
  for (const auto& force : system.forces())
    if (const ForceTerms t = force->terms(); t.form == ForceForm::Springs) {
      const SpringSet& set = *t.springs;
      for (size_t k = 0; k < set.size(); ++k)
        if (set.coeff[k] != 0.0 && !(pinned[size_t(set.i[k])] && pinned[size_t(set.j[k])])) {
          spring_a.push_back(set.i[k]);
          spring_b.push_back(set.j[k]);
          spring_k.push_back(set.coeff[k]);
          spring_L.push_back(set.rest_length[k]);
        }
    }
  spring_data.setZero(kSpringData * Index(spring_a.size()));

  if (options.formulation == CeresFormulation::Energy)
    add_energy_blocks();
  else
    add_residual_blocks();
  // Pinned particles: y = x0 and dx = 0, held constant.
  for (Index i = 0; i < n; ++i)
    if (pinned[size_t(i)] && problem.HasParameterBlock(dx.data() + 3 * i))
      problem.SetParameterBlockConstant(dx.data() + 3 * i);

  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver_options.linear_solver_type = kLinearSolverTypes[size_t(options.linear_solver)];
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.gradient_tolerance = options.gradient_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  solver_options.num_threads = options.threads;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  // Start as (almost) undamped Gauss-Newton: in the residual formulation that is Newton's method,
  // and Ceres' default (1e4, i.e. damping 1e-4 of the scaled diagonal) costs about 6 extra
  // iterations per step on stiff cloths until the damping has decayed. Failed steps still shrink
  // the trust region as usual.
  solver_options.initial_trust_region_radius = 1e12;
  std::string error;
  if (!solver_options.IsValid(&error))
    throw std::invalid_argument("ceres-implicit: Ceres rejects the options (linear_solver = '" +
                                std::string(to_string(options.linear_solver)) + "'): " + error);
}

void CeresImplicitStepper::Impl::add_energy_blocks() {
  // Rows: inertia (3 per free particle), springs (1 each), drag (3 per free particle with c > 0).
  const Vec& mass = system.masses();
  for (int i : free_particles) {
    problem.AddResidualBlock(
        new WeightedDistanceCost(Vec3::Constant(std::sqrt(mass[i])), &inv_h, nullptr), nullptr,
        dx.data() + 3 * i);
    num_residuals += 3;
  }
  for (size_t s = 0; s < spring_a.size(); ++s) {
    problem.AddResidualBlock(
        new SpringCost(spring_k[s], spring_L[s], spring_data.data() + kSpringData * s), nullptr,
        dx.data() + 3 * spring_a[s], dx.data() + 3 * spring_b[s]);
    num_residuals += 1;
  }
  const std::vector<char>& pinned = system.pinned();
  for (const ElementSet* set : elements)
    for (size_t e = 0; e < set->size(); ++e) {
      const int* s = set->stencil(e);
      std::vector<double*> blocks;
      bool moves = false;
      for (int a = 0; a < set->stencil_size(); ++a) {
        blocks.push_back(dx.data() + 3 * s[a]);
        moves = moves || !pinned[size_t(s[a])];
      }
      if (!moves) continue;  // a constant
      problem.AddResidualBlock(new ElementCost(*set, e, y), nullptr, blocks);
      num_residuals += 1;
    }
  for (int i : free_particles) {
    const Vec3 c = drag_c.segment<3>(3 * i);
    if (c.maxCoeff() == 0.0) continue;
    problem.AddResidualBlock(
        new WeightedDistanceCost(c.cwiseSqrt(), &inv_sqrt_h, drag_off.data() + 3 * i), nullptr,
        dx.data() + 3 * i);
    num_residuals += 3;
  }
}

void CeresImplicitStepper::Impl::add_residual_blocks() {
  // Rows: 3 per free particle (its backward Euler residual), in increasing particle id.
  std::vector<std::vector<std::pair<size_t, double>>> incident(size_t(system.num_particles()));
  for (size_t s = 0; s < spring_a.size(); ++s) {
    incident[size_t(spring_a[s])].push_back({s, 1.0});
    incident[size_t(spring_b[s])].push_back({s, -1.0});
  }
  struct Held {  // element e of set holds the particle as its stencil's particle `self`
    const ElementSet* set;
    size_t e;
    int self;
  };
  std::vector<std::vector<Held>> holds(size_t(system.num_particles()));
  for (const ElementSet* set : elements)
    for (size_t e = 0; e < set->size(); ++e)
      for (int a = 0; a < set->stencil_size(); ++a)
        holds[size_t(set->stencil(e)[a])].push_back({set, e, a});
  for (int i : free_particles) {
    std::vector<double*> blocks = {dx.data() + 3 * i};
    auto slot_of = [&](double* block) {  // blocks shared by several springs or elements once
      const auto it = std::find(blocks.begin(), blocks.end(), block);
      if (it != blocks.end()) return int(it - blocks.begin());
      blocks.push_back(block);
      return int(blocks.size()) - 1;
    };
    std::vector<ParticleResidualCost::Incident> springs;
    for (const auto& [s, sign] : incident[size_t(i)]) {
      const int slot = slot_of(dx.data() + 3 * (sign > 0.0 ? spring_b[s] : spring_a[s]));
      springs.push_back(
          {spring_k[s], spring_L[s], spring_data.data() + kSpringData * s, slot, sign});
    }
    std::vector<ParticleResidualCost::IncidentElement> held;
    for (const Held& hd : holds[size_t(i)]) {
      ParticleResidualCost::IncidentElement in{hd.set, hd.e, hd.self, {}};
      for (int a = 0; a < hd.set->stencil_size(); ++a)
        in.slot[size_t(a)] = slot_of(dx.data() + 3 * hd.set->stencil(hd.e)[a]);
      held.push_back(in);
    }
    problem.AddResidualBlock(
        new ParticleResidualCost(system.masses()[i], drag_c.segment<3>(3 * i), &inv_h,
                                 drag_off.data() + 3 * i, std::move(springs), std::move(held), y,
                                 int(blocks.size())),
        nullptr, blocks);
    num_residuals += 3;
  }
}

void CeresImplicitStepper::Impl::set_step_data(const State& s0, double h) {
  const std::vector<char>& pinned = system.pinned();
  const Vec& mass = system.masses();
  inv_h = 1.0 / h;
  inv_sqrt_h = 1.0 / std::sqrt(h);
  for (Index i = 0; i < system.num_particles(); ++i) {
    if (pinned[size_t(i)]) {
      dy.segment<3>(3 * i).setZero();
      dx.segment<3>(3 * i).setZero();
      y.segment<3>(3 * i) = s0.x.segment<3>(3 * i);
      continue;
    }
    dy.segment<3>(3 * i) = h * s0.v.segment<3>(3 * i) + (h * h / mass[i]) * f_ext.segment<3>(3 * i);
    y.segment<3>(3 * i) = s0.x.segment<3>(3 * i) + dy.segment<3>(3 * i);
    for (Index j = 3 * i; j < 3 * i + 3; ++j)
      drag_off[j] = drag_c[j] > 0.0 ? dy[j] - h * drag_b[j] / drag_c[j] : 0.0;
  }
  for (size_t s = 0; s < spring_a.size(); ++s) {
    const Index a = 3 * spring_a[s], b = 3 * spring_b[s];
    const Vec3 d =
        (s0.x.segment<3>(a) - s0.x.segment<3>(b)) + (dy.segment<3>(a) - dy.segment<3>(b));
    spring_data.segment<3>(kSpringData * Index(s)) = d;
    spring_data[kSpringData * Index(s) + 3] = d.squaredNorm() - spring_L[s] * spring_L[s];
  }
}

CeresImplicitStepper::CeresImplicitStepper(const MassSpringSystem& system,
                                           CeresImplicitOptions options) {
  HOOKE_ASSERT(system.pattern().finalized(), "ceres-implicit: the system must be finalize()d");
  if (const OptionError err = options.validate(); !err.ok())
    throw std::invalid_argument("ceres-implicit: " + err.message);
  const std::string unsupported = ceres_implicit_unsupported(system);
  if (!unsupported.empty()) throw std::invalid_argument(unsupported);
  m_impl = std::make_unique<Impl>(system, std::move(options));
}

CeresImplicitStepper::~CeresImplicitStepper() = default;

const CeresImplicitOptions& CeresImplicitStepper::options() const { return m_impl->options; }
const CeresReport& CeresImplicitStepper::last_report() const { return m_impl->report; }
Index CeresImplicitStepper::num_free_particles() const {
  return static_cast<Index>(m_impl->free_particles.size());
}
Index CeresImplicitStepper::num_residuals() const { return m_impl->num_residuals; }

StepperStats CeresImplicitStepper::stats() const { return m_impl->totals; }

StepSummary CeresImplicitStepper::step(const State& s0, double h, State& s1) {
  Impl& d = *m_impl;
  const Index N = d.system.dofs();
  HOOKE_ASSERT(s0.x.size() == N && s0.v.size() == N, "ceres-implicit: state size mismatch");
  StepSummary out;
  CeresReport& rep = d.report;
  rep = CeresReport{};
  if (!(h > 0.0) || !std::isfinite(h)) {
    std::ostringstream os;
    os << "ceres-implicit: step size h = " << h << " must be finite and > 0";
    out.status = Status::Fatal;
    out.message = os.str();
    return out;
  }

  d.set_step_data(s0, h);
  for (int i : d.free_particles) d.dx.segment<3>(3 * i).setZero();  // initial guess x = y
  if (!d.free_particles.empty()) {
    const auto t0 = Clock::now();
    ceres::Solve(d.solver_options, &d.problem, &d.summary);
    rep.seconds = seconds_since(t0);
    // Ceres counts the initial evaluation as iteration 0 (and as a successful step).
    rep.iterations = std::max(int(d.summary.iterations.size()) - 1, 0);
    rep.successful_steps = std::max(d.summary.num_successful_steps - 1, 0);
    rep.unsuccessful_steps = std::max(d.summary.num_unsuccessful_steps, 0);
    rep.initial_cost = d.summary.initial_cost;
    rep.final_cost = d.summary.final_cost;
    rep.gradient_max_norm = d.summary.iterations.empty()
                                ? std::numeric_limits<double>::quiet_NaN()
                                : d.summary.iterations.back().gradient_max_norm;
    rep.termination = termination_name(d.summary.termination_type);
    rep.message = d.summary.message;
  } else {
    rep = CeresReport{};
    rep.termination = "convergence";
    rep.message = "no free particles";
  }

  // x1 - x0 = (y - x0) + dx and v1 = (x1 - x0) / h; pinned particles have both parts zero, so
  // they keep x0 and v1 = 0 (as in ImplicitStepper).
  s1.v = d.dy + d.dx;
  s1.x = s0.x + s1.v;
  s1.v /= h;
  s1.t = s0.t + h;

  // The backward Euler residual of the result, with the system's own forces, and its scale.
  d.system.compute_forces(s1.x, s1.v, d.f);
  const Vec& M = d.system.mass_diagonal();
  double residual = 0.0, inertia = 0.0, force = 0.0;
  for (int i : d.free_particles)
    for (Index j = 3 * i; j < 3 * i + 3; ++j) {
      const double ma = M[j] * (s1.v[j] - s0.v[j]) / h;
      residual = std::max(residual, std::abs(ma - d.f[j]));
      inertia = std::max(inertia, std::abs(ma));
      force = std::max(force, std::abs(d.f[j]));
    }
  rep.residual = residual;
  const double residual_bound = d.options.residual_tolerance * (inertia + force);

  out.iterations = out.newton_iterations = rep.iterations;
  out.residual = residual;
  ++d.totals.steps;
  d.totals.iterations += rep.iterations;
  d.totals.last_residual = residual;
  d.totals.solve_seconds += rep.seconds;
  const bool usable = rep.termination == "convergence" || rep.termination == "user-success" ||
                      rep.termination == "no-convergence";
  if (!usable || !s1.is_finite())
    out.status = Status::Fatal;
  else if (rep.termination == "no-convergence" || !(residual <= residual_bound))
    out.status = Status::NotConverged;
  if (out.status != Status::Converged) {
    std::ostringstream os;
    os << "ceres-implicit: Ceres terminated with " << rep.termination
       << (s1.is_finite() ? "" : " and a non-finite x1") << " after " << rep.iterations
       << " iterations (max_iterations " << d.options.max_iterations
       << "), final gradient max-norm " << rep.gradient_max_norm << ", backward Euler residual "
       << residual << " N (bound " << residual_bound << " from residual_tolerance "
       << d.options.residual_tolerance << "): " << rep.message;
    out.message = os.str();
  }
  return out;
}

void CeresImplicitStepper::evaluate(const State& s0, double h, ConstRef x, Vec& residuals,
                                    Eigen::MatrixXd& jacobian) {
  Impl& d = *m_impl;
  HOOKE_ASSERT(s0.x.size() == d.system.dofs() && x.size() == d.system.dofs() && h > 0.0,
               "ceres-implicit: evaluate: size mismatch or h <= 0");
  d.set_step_data(s0, h);
  if (d.free_particles.empty()) {  // empty parameter_blocks would mean "all blocks" to Ceres
    residuals.resize(0);
    jacobian.resize(0, 0);
    return;
  }
  ceres::Problem::EvaluateOptions eo;
  for (int i : d.free_particles) {
    d.dx.segment<3>(3 * i) =
        (x.segment<3>(3 * i) - s0.x.segment<3>(3 * i)) - d.dy.segment<3>(3 * i);
    eo.parameter_blocks.push_back(d.dx.data() + 3 * i);
  }
  std::vector<double> r;
  ceres::CRSMatrix J;
  double cost = 0.0;
  const bool ok = d.problem.Evaluate(eo, &cost, &r, nullptr, &J);
  HOOKE_ASSERT(ok, "ceres-implicit: Problem::Evaluate failed");
  residuals = Eigen::Map<const Vec>(r.data(), Index(r.size()));
  jacobian.setZero(J.num_rows, J.num_cols);
  for (int row = 0; row < J.num_rows; ++row)
    for (int p = J.rows[size_t(row)]; p < J.rows[size_t(row) + 1]; ++p)
      jacobian(row, J.cols[size_t(p)]) = J.values[size_t(p)];
}

}  // namespace hooke
