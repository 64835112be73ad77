// A scene loaded through the installed scene loader (hooke::problems) and run with the installed
// solver: the two-particle spring by RK4 for one period; exits 0 if the particles are back where
// they started (the exact motion is periodic).
#include <cmath>
#include <cstdio>
#include <hooke/registry.hpp>
#include <hooke/simulation.hpp>
#include <problems/scene.hpp>

int main() {
  const hooke::Scene scene = hooke::load_scene_from_string(
      "[mesh]\ntype = 'two-particle'\nmass = 1.0\nrest_length = 1.0\nstretch = 0.1\n"
      "[springs]\nstiffness = 100.0\n[integrator]\nmethod = 'rk4'\n",
      "consumer.toml");
  hooke::Simulation sim(*scene.system, hooke::make_stepper(scene.integrator.method, *scene.system),
                        scene.initial);
  const double period = 2.0 * M_PI / std::sqrt(2.0 * 100.0 / 1.0);
  const int steps = 1000;
  for (int k = 0; k < steps; ++k) sim.advance(period / steps);
  const double r = sim.state().x[3] - sim.state().x[0];
  std::printf(
      "scene loaded by hooke::problems: relative coordinate after one period %.12f "
      "(exact 1.1)\n",
      r);
  return std::abs(r - 1.1) < 1e-9 ? 0 : 1;
}
