#pragma once
#include <memory>

#include "hooke/integrators/explicit_stepper.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_ode.hpp"

namespace hooke {

/// Runs any ExplicitStepper on a mass-spring system through MassSpringOde, packing (x, v) into the
/// first-order state [x; v] in preallocated buffers.
class ExplicitMassSpringStepper final : public Stepper {
 public:
  ExplicitMassSpringStepper(const MassSpringSystem& system,
                            std::unique_ptr<ExplicitStepper> method);
  const char* name() const override { return m_method->name(); }
  StepSummary step(const State& s0, double h, State& s1) override;
  int error_estimate_order() const override { return m_method->error_estimate_order(); }
  double error_norm(double rtol, double atol) override;

 private:
  MassSpringOde m_ode;
  std::unique_ptr<ExplicitStepper> m_method;
  Vec m_X0, m_X1;
  Vec m_err;  // the embedded pair's error estimate (sized once, for methods that have one)
};

}  // namespace hooke
