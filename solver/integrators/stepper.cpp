#include "hooke/integrators/stepper.hpp"

#include <sstream>

namespace hooke {

double Stepper::error_norm(double, double) {
  HOOKE_ASSERT(false, name() << " makes no local error estimate");
  return 0.0;
}

void add_work(StepperStats& to, const StepperStats& from) {
  for (auto m :
       {&StepperStats::internal_steps, &StepperStats::iterations, &StepperStats::linear_iterations,
        &StepperStats::factorizations, &StepperStats::contact_pattern_builds})
    to.*m += from.*m;
  for (auto m :
       {&StepperStats::assembly_seconds, &StepperStats::analyze_seconds,
        &StepperStats::factor_seconds, &StepperStats::solve_seconds, &StepperStats::local_seconds,
        &StepperStats::global_seconds, &StepperStats::contact_seconds, &StepperStats::ccd_seconds,
        &StepperStats::broad_phase_seconds, &StepperStats::total_seconds,
        &StepperStats::factor_nonzeros})
    to.*m += from.*m;
}

void add_substep(StepSummary& total, const StepSummary& s) {
  total.iterations += s.iterations;
  total.newton_iterations += s.newton_iterations;
  total.residual = s.residual;
  if (s.status != Status::Converged && total.status == Status::Converged) {
    total.status = s.status;
    total.message = s.message;
  }
}

std::string format_stats(const StepperStats& s) {
  std::ostringstream os;
  os << s.steps << " steps";
  auto count = [&](long long v, const char* what) {
    if (v) os << ", " << v << " " << what;
  };
  count(s.internal_steps, "internal steps");
  count(s.iterations, "iterations");
  count(s.linear_iterations, "linear iterations");
  count(s.factorizations, "factorizations");
  count(s.contact_pattern_builds, "contact pattern builds");
  const char* sep = "; ";
  auto time = [&](double v, const char* what) {
    if (v == 0.0) return;
    os << sep << what << " " << v << " s";
    sep = ", ";
  };
  time(s.assembly_seconds, "assembly");
  time(s.analyze_seconds, "analyze");
  time(s.factor_seconds, "factor");
  time(s.solve_seconds, "solve");
  time(s.local_seconds, "local");
  time(s.global_seconds, "global");
  time(s.contact_seconds, "contact");
  time(s.ccd_seconds, "of which CCD");
  time(s.broad_phase_seconds, "of which broad phase");
  time(s.total_seconds, "total");
  return os.str();
}

}  // namespace hooke
