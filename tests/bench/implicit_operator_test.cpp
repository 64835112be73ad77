// Claims of bench/implicit_operator.*: the matrix-free product equals the assembled
// reduced matrix A = M - a D - b K (ReducedMatrix from the forces' own Jacobian blocks) applied to
// the same vector, for stretched and compressed springs, with and without the clamp and the
// dampers' position terms; and it gives the same bits on one or two threads.
#include "bench/implicit_operator.hpp"

#include <gtest/gtest.h>

#include "hooke/integrators/reduced_matrix.hpp"
#include "hooke/parallel/loops.hpp"
#include "support/random.hpp"
#include "support/systems.hpp"

namespace hooke {
namespace {

using test::random_vector;

TEST(ImplicitOperator, EqualsTheAssembledReducedMatrix) {
  int checked = 0;
  for (const double rest_scale : {1.0, 1.3})  // 1.3: many compressed springs
    for (const bool clamp : {true, false})
      for (const bool position_terms : {true, false}) {
        test::ClothSpec spec;
        spec.n = 12;
        spec.jitter = 0.3;
        spec.speed = 0.5;
        spec.rest_scale = rest_scale;
        const test::Cloth cloth = test::make_cloth(spec);
        const MassSpringSystem& sys = *cloth.system;
        JacobianOptions opt;
        opt.clamp_compressed = clamp;
        opt.damping_position_terms = position_terms;
        const double a = 0.01, b = 1e-4;
        Jacobians J = sys.make_jacobians();
        sys.assemble_jacobians(cloth.state.x, cloth.state.v, J, opt);
        ReducedMatrix R(sys);
        R.assemble(J, a, b);
        ImplicitOperator op(sys);
        ASSERT_TRUE(op.supported());
        op.set(cloth.state.x, cloth.state.v, a, b, opt);
        ASSERT_EQ(op.free_dofs(), R.free_dofs());
        for (unsigned seed : {1u, 2u}) {
          const Vec p = random_vector(R.free_dofs(), seed);
          const Vec want = R.matrix() * p;
          Vec got(R.free_dofs());
          op.apply(p, got);
          EXPECT_LT((got - want).norm(), 1e-13 * want.norm())
              << "rest_scale " << rest_scale << " clamp " << clamp << " position terms "
              << position_terms;
          ++checked;
        }
      }
  EXPECT_EQ(checked, 16);
}

TEST(ImplicitOperator, SameBitsOnOneOrTwoThreads) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  test::ClothSpec spec;
  spec.n = 160;  // 25600 particles: several particle ranges, so the spring loops run in parallel
  spec.spacing = 1.0 / 159.0;
  spec.jitter = 0.2;
  spec.speed = 0.5;
  const test::Cloth cloth = test::make_cloth(spec);
  ImplicitOperator op(*cloth.system);
  op.set(cloth.state.x, cloth.state.v, 0.01, 1e-4, {});
  const Vec p = random_vector(op.free_dofs(), 3);
  Vec y1(op.free_dofs()), y2(op.free_dofs());
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  op.apply(p, y1);
  omp_set_num_threads(2);
  op.apply(p, y2);
  omp_set_num_threads(threads);
  EXPECT_EQ((y1 - y2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(y1.norm(), 0.0);
#endif
}

}  // namespace
}  // namespace hooke
