#pragma once
#include <vector>

#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

// Kept in bench/, not in the library: measured against the assembled CSR product of the same
// operator (hooke_bench_roofline at 1M springs: 21.1 / 14.3 ms matrix-free against 13.4 / 7.9 ms
// CSR on 1 / 2 threads), the matrix-free product is slower on this hardware, and every backend
// needs the assembled matrix anyway (preconditioners, factorizations). Force::add_jacobian_product,
// which it is built on, stays in the Force interface and is checked for every force by
// tests/forces/force_conformance_test.cpp, for a later matrix-free Krylov path (e.g. a PETSc
// MatShell).

/// The implicit-step operator p -> A p with A = M - a D - b K on the free DOFs (the ordering of
/// ReducedMatrix: free DOFs in particle order), matrix-free: each force applies its Jacobians to p
/// from the positions and velocities (Force::add_jacobian_product) instead of reading stored 3x3
/// blocks. A spring then costs its two positions and p values (about 100 bytes) instead of four
/// stored blocks (about 430 bytes of CSR values and indices), so the product is compute-bound and
/// scales with threads where the CSR product is limited by memory bandwidth (bench/README.md). The
/// per-spring loops run in parallel through SpringSet::for_each: results are the same bits for
/// any thread count. No allocation after construction.
class ImplicitOperator {
 public:
  explicit ImplicitOperator(const MassSpringSystem& system);
  /// False if some force of the system has no matrix-free Jacobian product.
  bool supported() const { return m_supported; }
  /// The linearisation point (x, v: 3n vectors, kept by reference until the next call), the
  /// coefficients a of D and b of K, and the Jacobian options.
  void set(ConstRef x, ConstRef v, double a, double b, const JacobianOptions& options);
  /// y = A p on the free DOFs (both of length free_dofs()).
  void apply(ConstRef p, VecRef y);
  Index free_dofs() const { return Index(m_free.size()); }

 private:
  const MassSpringSystem& m_sys;
  std::vector<int> m_free;    // full DOF index of each free DOF
  std::vector<int> m_pinned;  // full DOF index of each pinned DOF
  Vec m_mass;                 // mass per full DOF
  Vec m_P, m_Y;               // full-length scratch
  const double* m_x = nullptr;
  const double* m_v = nullptr;
  double m_a = 0.0, m_b = 0.0;
  JacobianOptions m_options;
  bool m_supported = true;
};

}  // namespace hooke
