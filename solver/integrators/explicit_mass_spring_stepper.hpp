#pragma once
#include <memory>
#include <vector>

#include "hooke/integrators/explicit_stepper.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_ode.hpp"

namespace hooke {

/// Runs any ExplicitStepper on a mass-spring system through MassSpringOde, packing (x, v) into the
/// first-order state [x; v] in preallocated buffers. Symplectic Euler (without scripted pins)
/// takes a fused path instead: the forces, then v1 = v0 + h (f / m) and x1 = x0 + h v1 in one
/// parallel pass over the particles, the same arithmetic per entry as SymplecticEuler on
/// MassSpringOde (the same bits, tested) without its six passes of packing and unpacking, which
/// at a million particles cost a third of the step and keep a second thread from paying off.
class ExplicitMassSpringStepper final : public Stepper {
 public:
  ExplicitMassSpringStepper(const MassSpringSystem& system,
                            std::unique_ptr<ExplicitStepper> method);
  const char* name() const override { return m_method->name(); }
  StepSummary step(const State& s0, double h, State& s1) override;
  int error_estimate_order() const override { return m_method->error_estimate_order(); }
  double error_norm(double rtol, double atol) override;

 private:
  const MassSpringSystem& m_system;
  MassSpringOde m_ode;
  std::unique_ptr<ExplicitStepper> m_method;
  bool m_symplectic = false;  // the fused symplectic Euler path (unless pins are scripted)
  Vec m_f;                    // its forces (sized once)
  // Its inverse masses and moving mask per particle (the per-DOF arrays' entries, which repeat
  // for a particle's three DOFs): 9 bytes a particle instead of 48.
  Vec m_inv_mass;
  std::vector<char> m_moving;
  Vec m_X0, m_X1;
  Vec m_err;  // the embedded pair's error estimate (sized once, for methods that have one)
};

}  // namespace hooke
