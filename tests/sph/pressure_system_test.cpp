// Claims of solver/sph/pressure_system.*: the assembled pressure Poisson equation is IISPH's
// matrix-free operator (A p = h^2 M^-1 E^T (-M^-1 F R^-2 p) on the active rows, to round-off);
// solved exactly on the active set of relaxed Jacobi's pressures (by sparse LU, and by CHOLMOD
// through the normal equations: the walls make the system nonsymmetric), its predicted densities
// agree with Jacobi's to within Jacobi's stated tolerance. Prints the cost of each solve.
#include "hooke/sph/pressure_system.hpp"

#include <gtest/gtest.h>

#include <Eigen/SparseLU>
#include <cmath>
#include <string>

#include "hooke/config.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/linear/linear_solver.hpp"
#include "hooke/sph/iisph.hpp"
#include "sph/sph_scenes.hpp"

namespace hooke {
namespace {

/// rho* + A p: the densities the pressures p predict at the end of the step.
Vec predicted_density(const IisphStepper& stepper, const NeighbourSearch& search, const State& s,
                      const MassSpringSystem& system, ConstRef p, double h) {
  const FluidModel& fluid = stepper.fluid();
  const Index nf = fluid.num_fluid();
  Vec a = Vec::Zero(3 * system.num_particles()), div(nf);
  fluid.add_pressure_acceleration(search, s.x, system.masses(), stepper.densities(), p, a,
                                  stepper.gradient_scale());
  fluid.density_change(search, s.x, system.masses(), a, div);
  return (fluid.rest_density() - stepper.source().array() + h * h * div.array()).matrix();
}

TEST(PressureSystem, ExactSolutionAgreesWithRelaxedJacobiWithinItsTolerance) {
  for (const double tolerance : {1e-3, 1e-5}) {
    // A column of water collapsing in a 2D tank, 0.1 s in: a moving free surface.
    auto scene = test::tank_2d(0.01, 0.6, 0.5, 0.2, 0.4, FluidOptions{});
    IisphOptions options;
    options.tolerance = tolerance;
    options.max_iterations = 100000;
    IisphStepper stepper(*scene.system, options);
    const double h = 2e-3;
    ASSERT_EQ(test::run_fluid(stepper, scene.state, h, 0.1).status, Status::Converged);
    State next;
    const auto t0 = Clock::now();
    ASSERT_EQ(stepper.step(scene.state, h, next).status, Status::Converged);
    const double jacobi_seconds = seconds_since(t0);
    const FluidModel& fluid = stepper.fluid();
    const Index nf = fluid.num_fluid();
    const Vec pJ = stepper.pressures();
    std::vector<char> active(static_cast<size_t>(nf));
    for (Index i = 0; i < nf; ++i) active[size_t(i)] = pJ[i] > 0.0;
    NeighbourSearch search(fluid.support());
    ASSERT_EQ(search.update(scene.state.x, nf), Status::Converged);
    const auto t1 = Clock::now();
    const PressureSystem sys = assemble_pressure_system(
        fluid, search, scene.state.x, scene.system->masses(), stepper.densities(), stepper.source(),
        h, active, stepper.gradient_scale());
    const double assembly_seconds = seconds_since(t1);
    ASSERT_GT(sys.active.size(), size_t(nf / 2));
    ASSERT_EQ(sys.S.rows(), sys.S.cols());

    const double rho0 = fluid.rest_density();
    for (const char* backend : {"cholmod", "sparse-lu"}) {
      Vec q = Vec::Zero(sys.rhs.size());
      int iterations = 0;
      const auto t2 = Clock::now();
      if (std::string(backend) == "cholmod") {
        // CHOLMOD factors the normal equations S^T S q = S^T b of the nonsymmetric system.
        if (!linear_solver_unknown(backend).empty()) continue;
        auto solver = make_linear_solver(backend, "");
        const SparseMatrix N = SparseMatrix(sys.S.transpose()) * sys.S;
        const Vec b = sys.S.transpose() * sys.rhs;
        LinearSolveOptions solve_options;
        solve_options.tolerance = 1e-12;
        ASSERT_EQ(solver->analyze(N).status, Status::Converged) << backend;
        ASSERT_EQ(solver->factor(N).status, Status::Converged) << backend;
        const LinearSummary r = solver->solve(b, q, solve_options);
        ASSERT_EQ(r.status, Status::Converged) << backend << ": " << r.message;
        iterations = r.iterations;
      } else {
        Eigen::SparseLU<SparseMatrix, Eigen::COLAMDOrdering<int>> lu;
        lu.compute(sys.S);
        ASSERT_EQ(lu.info(), Eigen::Success) << backend << ": " << lu.lastErrorMessage();
        q = lu.solve(sys.rhs);
      }
      const double seconds = seconds_since(t2);
      const Vec pC = sys.pressures(q, stepper.densities());
      // The system's equations are the active rows: there the exact pressures predict rho0 to
      // round-off (the assembly is the matrix-free operator), and Jacobi's predict densities
      // within its tolerance of them (the sum over the active rows, per fluid particle, as the
      // stopping rule counts it).
      const Vec exact = predicted_density(stepper, search, scene.state, *scene.system, pC, h);
      const Vec jacobi = predicted_density(stepper, search, scene.state, *scene.system, pJ, h);
      double worst_active = 0.0, active_difference = 0.0, all_difference = 0.0;
      for (Index i = 0; i < nf; ++i) {
        const double d = std::abs(exact[i] - jacobi[i]) / rho0;
        all_difference += d / double(nf);
        if (!active[size_t(i)]) continue;
        worst_active = std::max(worst_active, std::abs(exact[i] - rho0) / rho0);
        active_difference += d / double(nf);
      }
      std::printf(
          "[ ppe      ] tolerance %.0e, %zu of %lld particles active; %s %.2e s (analyze, factor, "
          "solve; %d iterations), assembly %.2e s; relaxed Jacobi's whole step %.2e s (%d "
          "iterations); the exact pressures meet the operator to %.1e; predicted densities "
          "differ by %.2e rho0 on the active rows, %.2e over all; max |p_J - p_exact| / max p = "
          "%.3f\n",
          tolerance, sys.active.size(), static_cast<long long>(nf), backend, seconds, iterations,
          assembly_seconds, jacobi_seconds, stepper.last_fluid_stats().pressure_iterations,
          worst_active, active_difference, all_difference,
          (pJ - pC).lpNorm<Eigen::Infinity>() / pC.maxCoeff());
      EXPECT_LT(worst_active, 1e-9) << backend;
      EXPECT_LE(active_difference, tolerance) << backend;
    }
  }
}

}  // namespace
}  // namespace hooke
