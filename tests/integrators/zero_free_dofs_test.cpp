// Claim: a system whose particles are all pinned (zero free degrees of freedom) runs with every
// registered method, and with every variant that puts a linear solve in the step (implicit methods
// on each registered linear backend, pcg-<preconditioner> included; CVODE and IDA with SPGMR
// preconditioned by each backend; Ceres with each formulation and linear solver; fast-mass-spring
// with each global solver and acceleration): every step is Converged and the state stays where
// the pins hold it. The Newton matrix of such a system is 0 x 0, which a linear backend must
// solve trivially (solver/linear/linear_solver.hpp); CHOLMOD itself rejects it, so before
// CholmodSolver skipped it, cholmod, pcg-cholmod and pcg-nodal (and the default of implicit,
// implicit-midpoint and bdf2) failed in analyze. New methods and backends join the sweep without
// a test edit.
#include <gtest/gtest.h>

#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "hooke/forces/air_drag.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/registry.hpp"
#include "support/registry.hpp"
#include "support/systems.hpp"

namespace hooke {
namespace {

/// One method with one set of options; variant names the options ("" = the method's defaults).
struct Case {
  std::string method, variant;
  MethodOptions options;
};

/// "method / variant" in gtest's messages instead of the object's bytes.
void PrintTo(const Case& c, std::ostream* os) {
  *os << c.method << (c.variant.empty() ? "" : " / " + c.variant);
}

/// The values of an enum with an EnumNames table, in table order.
template <class E>
std::vector<E> enum_values() {
  std::vector<E> out;
  for (size_t i = 0; i < EnumNames<E>::names.size(); ++i) out.push_back(static_cast<E>(i));
  return out;
}

/// Options of every method that takes options, one per variant with a linear solve of its own.
/// Each is offered to every method; options_for() keeps those of the method's own type.
std::vector<std::pair<std::string, MethodOptions>> option_variants() {
  std::vector<std::pair<std::string, MethodOptions>> out;
  for (const auto& ls : linear_solvers()) {
    ImplicitOptions o;
    o.linear_solver = ls.name;
    out.emplace_back(ls.name, o);
  }
  std::vector<std::string> preconditioners = {"none"};
  for (const auto& ls : linear_solvers()) preconditioners.push_back(ls.name);
  for (const std::string& p : preconditioners) {
    CvodeOptions c;
    c.linear_solver = SundialsLinearSolver::Spgmr;
    c.preconditioner = p;
    out.emplace_back("spgmr-" + p, c);
    IdaOptions i;
    i.linear_solver = SundialsLinearSolver::Spgmr;
    i.preconditioner = p;
    out.emplace_back("spgmr-" + p, i);
  }
  for (const CeresFormulation f : enum_values<CeresFormulation>())
    for (const CeresLinearSolver l : enum_values<CeresLinearSolver>()) {
      CeresImplicitOptions o;
      o.formulation = f;
      o.linear_solver = l;
      out.emplace_back(std::string(to_string(f)) + "-" + to_string(l), o);
    }
  for (const GlobalSolver g : enum_values<GlobalSolver>())
    for (const Acceleration a : enum_values<Acceleration>()) {
      FastMassSpringOptions o;
      o.global_solver = g;
      o.acceleration = a;
      if (o.validate().ok()) out.emplace_back(std::string(to_string(g)) + "-" + to_string(a), o);
    }
  return out;
}

std::vector<Case> cases() {
  std::vector<Case> out;
  const auto variants = option_variants();
  for (const auto& m : methods()) {
    // The fluid methods step fluids, whose fluid particles always move (tests/sph/).
    if (m.kind == MethodKind::Fluid) continue;
    out.push_back({m.name, "", {}});
    for (const auto& [variant, options] : variants) {
      const MethodOptions taken = options_for(m.name, options);
      if (!taken.empty()) out.push_back({m.name, variant, taken});
    }
  }
  return out;
}

std::string case_name(const testing::TestParamInfo<Case>& info) {
  return test::pascal_case(info.param.method) +
         (info.param.variant.empty() ? "" : "On" + test::pascal_case(info.param.variant));
}

/// A 3 x 3 net, every particle pinned, off its rest shape (springs stretched and compressed, out
/// of plane) and at rest, as the scene reader leaves pinned particles (problems/scene.cpp zeroes
/// their velocities); structural and shear Hooke springs, air drag and gravity, and with
/// `dampers` a SpringDamper on every spring (which ceres-implicit, fast-mass-spring and xpbd
/// refuse).
test::Cloth pinned_net(bool dampers) {
  const int n = 3, np = n * n;
  const double s = 0.5, m = 0.1;
  test::Cloth c;
  c.system = std::make_unique<MassSpringSystem>(Vec::Constant(np, m), std::vector<char>(np, 1));
  c.state = State(np);
  for (int i = 0; i < np; ++i)
    c.state.x.segment<3>(3 * i) =
        Vec3((i % n) * s + 0.03 * (i % 2), (i / n) * s, 0.05 * ((i * 7) % 3));
  auto springs = std::make_unique<HookeSpring>();
  auto damper = std::make_unique<SpringDamper>();
  auto add = [&](int a, int b, double L) {
    springs->add(a, b, 1e3, L);
    damper->add(a, b, 0.5);
  };
  for (int i = 0; i < np; ++i) {
    if (i % n + 1 < n) add(i, i + 1, 0.8 * s);              // stretched
    if (i + n < np) add(i, i + n, 1.3 * s);                 // compressed
    if (i % n + 1 < n && i + n < np) add(i, i + n + 1, s);  // shear
  }
  c.system->add_force(std::move(springs));
  if (dampers) c.system->add_force(std::move(damper));
  c.system->add_force(std::make_unique<AirDrag>(np, 0.01));
  c.system->add_force(std::make_unique<Gravity>(Vec::Constant(np, m), Vec3(0.0, -9.81, 0.0)));
  c.system->finalize();
  return c;
}

class ZeroFreeDofs : public testing::TestWithParam<Case> {};

TEST_P(ZeroFreeDofs, StateStaysAtThePins) {
  const Case& k = GetParam();
  const test::Cloth plain = pinned_net(false), damped = pinned_net(true);
  ASSERT_EQ(plain.system->num_pinned(), plain.system->num_particles());
  // Every method runs the undamped net; those that take dampers run the damped one.
  ASSERT_EQ(method_unsupported(k.method, *plain.system), "") << k.method;
  const bool with_dampers = method_unsupported(k.method, *damped.system).empty();
  const test::Cloth& c = with_dampers ? damped : plain;

  std::unique_ptr<Stepper> stepper;
  ASSERT_NO_THROW(stepper = make_stepper(k.method, *c.system, k.options)) << k.method;
  const double h = 1e-3;
  State s0 = c.state, s1;
  int steps = 0;
  for (; steps < 4; ++steps) {
    const StepSummary sum = stepper->step(s0, h, s1);
    ASSERT_EQ(sum.status, Status::Converged)
        << k.method << " " << k.variant << ", step " << steps + 1 << ": " << sum.message;
    ASSERT_TRUE(s1.is_finite()) << k.method << " " << k.variant << ", step " << steps + 1;
    ASSERT_EQ(s1.x.size(), c.state.x.size());
    ASSERT_EQ(s1.v.size(), c.state.v.size());
    // Exact for most methods; BDF2's 4/3 x0 - 1/3 x_prev and adaptive integrators may round.
    EXPECT_LE((s1.x - c.state.x).lpNorm<Eigen::Infinity>(), 1e-12)
        << k.method << " " << k.variant << ", step " << steps + 1;
    EXPECT_LE(s1.v.lpNorm<Eigen::Infinity>(), 1e-12)
        << k.method << " " << k.variant << ", step " << steps + 1;
    EXPECT_DOUBLE_EQ(s1.t, s0.t + h);
    s0 = s1;
  }
  EXPECT_EQ(steps, 4);
  EXPECT_NO_THROW(stepper->report()) << k.method;
}

INSTANTIATE_TEST_SUITE_P(Registry, ZeroFreeDofs, testing::ValuesIn(cases()), case_name);

// The sweep covers what it claims: every method, and every linear backend under each implicit
// method.
TEST(ZeroFreeDofsSweep, CoversEveryMethodAndEveryLinearBackend) {
  const std::vector<Case> all = cases();
  for (const auto& m : methods()) {
    if (m.kind == MethodKind::Fluid) continue;  // see cases()
    int with_method = 0;
    for (const Case& k : all) with_method += k.method == m.name;
    EXPECT_GE(with_method, 1) << m.name;
    if (m.kind != MethodKind::Implicit) continue;
    for (const auto& ls : linear_solvers()) {
      int with_backend = 0;
      for (const Case& k : all) with_backend += k.method == m.name && k.variant == ls.name;
      EXPECT_EQ(with_backend, 1) << m.name << " on " << ls.name;
    }
  }
}

}  // namespace
}  // namespace hooke
