// Two particles on a spring, stepped with RK4 through the installed library: exits 0 if the
// relative coordinate matches the exact cosine after one period.
#include <cmath>
#include <cstdio>
#include <hooke/config.hpp>
#include <hooke/forces/hooke_spring.hpp>
#include <hooke/registry.hpp>
#include <hooke/simulation.hpp>
#include <memory>

int main() {
  hooke::Vec masses = hooke::Vec::Ones(2);
  hooke::MassSpringSystem system(masses, {0, 0});
  auto spring = std::make_unique<hooke::HookeSpring>();
  spring->add(0, 1, 100.0, 1.0);
  system.add_force(std::move(spring));
  system.finalize();
  hooke::State s0(2);
  s0.x[3] = 1.1;
  hooke::Simulation sim(system, hooke::make_stepper("rk4", system), s0);
  const double omega = std::sqrt(2.0 * 100.0 / 1.0), period = 2.0 * M_PI / omega;
  const int steps = 1000;
  for (int k = 0; k < steps; ++k) sim.advance(period / steps);
  const double r = sim.state().x[3] - sim.state().x[0];
  std::printf("hooke %s: relative coordinate after one period: %.12f (exact 1.1)\n", HOOKE_VERSION,
              r);
  return std::abs(r - 1.1) < 1e-9 ? 0 : 1;
}
