// Claims of solver/integrators/step_matrix.*: the Newton matrix formed in place over K's values,
// A = M - a D - b K with pinned DOFs as Dirichlet rows, is
//  - on the free DOFs, entry for entry the reduced matrix ReducedMatrix builds independently (its
//    own pattern and index map, from a separate K and D);
//  - zero in every pinned row and column except the diagonal, which holds the particle's mass;
//  - correct with and without a stored D (a system with no velocity-dependent force stores none);
// and jacobians() before form() is the system's own assembly, zero_pinned() zeroes exactly the
// pinned DOFs.
#include "hooke/integrators/step_matrix.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/integrators/reduced_matrix.hpp"
#include "support/systems.hpp"

namespace {

using hooke::Index;
using hooke::MassSpringSystem;
using hooke::SparseMatrix;
using hooke::Vec;

// Dense copy, for entry-by-entry comparison of small matrices.
Eigen::MatrixXd dense(const SparseMatrix& A) { return Eigen::MatrixXd(A); }

void check_against_reduced(const MassSpringSystem& sys, const Vec& x, const Vec& v, double a,
                           double b) {
  hooke::JacobianOptions jo;
  jo.clamp_compressed = true;
  jo.damping_position_terms = false;

  hooke::Jacobians J = sys.make_jacobians();
  sys.assemble_jacobians(x, v, J, jo);
  hooke::ReducedMatrix R(sys);
  R.assemble(J, a, b);
  const Eigen::MatrixXd Ar = dense(R.matrix());

  hooke::StepMatrix S(sys);
  S.assemble_jacobians(x, v, jo);
  EXPECT_EQ(dense(S.jacobians().K), dense(J.K));
  EXPECT_EQ(S.jacobians().D.nonZeros(), J.D.nonZeros());
  if (J.D.nonZeros() > 0) {
    EXPECT_EQ(dense(S.jacobians().D), dense(J.D));
  }
  S.form(a, b);
  const Eigen::MatrixXd A = dense(S.matrix());
  ASSERT_EQ(A.rows(), sys.dofs());

  std::vector<Index> free;
  for (Index i = 0; i < sys.dofs(); ++i)
    if (!sys.pinned()[size_t(i / 3)]) free.push_back(i);
  ASSERT_EQ(Index(free.size()), R.free_dofs());
  for (Index r = 0; r < sys.dofs(); ++r)
    for (Index c = 0; c < sys.dofs(); ++c) {
      const bool pr = sys.pinned()[size_t(r / 3)] != 0, pc = sys.pinned()[size_t(c / 3)] != 0;
      if (!pr && !pc) continue;
      const double expected = r == c ? sys.mass_diagonal()[r] : 0.0;
      EXPECT_EQ(A(r, c), expected) << "pinned entry (" << r << ", " << c << ")";
    }
  for (size_t i = 0; i < free.size(); ++i)
    for (size_t j = 0; j < free.size(); ++j)
      EXPECT_EQ(A(free[i], free[j]), Ar(Index(i), Index(j)))
          << "free entry (" << free[i] << ", " << free[j] << ")";

  Vec r = Vec::Ones(sys.dofs());
  S.zero_pinned(r);
  for (Index i = 0; i < sys.dofs(); ++i)
    EXPECT_EQ(r[i], sys.pinned()[size_t(i / 3)] ? 0.0 : 1.0) << "dof " << i;
}

TEST(StepMatrix, EqualsTheReducedMatrixOnFreeDofsWithDampers) {
  hooke::test::ClothSpec spec;
  spec.n = 6;
  spec.spacing = 0.2;
  spec.jitter = 0.3;
  spec.speed = 0.5;
  const hooke::test::Cloth cloth = hooke::test::make_cloth(spec);
  ASSERT_TRUE(cloth.system->has_velocity_jacobian());
  ASSERT_GT(cloth.system->num_pinned(), 0);
  check_against_reduced(*cloth.system, cloth.state.x, cloth.state.v, 0.01, 1e-4);
}

TEST(StepMatrix, EqualsTheReducedMatrixOnFreeDofsWithoutD) {
  // A chain pinned at both ends (springs and gravity: no df/dv, so D is not stored).
  const int n = 7;
  std::vector<char> pinned(size_t(n), 0);
  pinned[0] = pinned[size_t(n - 1)] = 1;
  Vec masses(n);
  for (int i = 0; i < n; ++i) masses[i] = 0.1 + 0.05 * i;
  MassSpringSystem sys(masses, pinned);
  auto springs = std::make_unique<hooke::HookeSpring>();
  for (int i = 0; i + 1 < n; ++i) springs->add(i, i + 1, 100.0 * (i + 1), 0.3);
  springs->add(1, 4, 50.0, 0.8);
  sys.add_force(std::move(springs));
  sys.add_force(std::make_unique<hooke::Gravity>(masses, hooke::Vec3(0.0, -9.81, 0.0)));
  sys.finalize();
  ASSERT_FALSE(sys.has_velocity_jacobian());
  Vec x(3 * n), v = Vec::Zero(3 * n);
  for (int i = 0; i < n; ++i) x.segment<3>(3 * i) = hooke::Vec3(0.25 * i, 0.05 * (i % 2), 0.01 * i);
  check_against_reduced(sys, x, v, 0.02, 4e-4);
}

}  // namespace
