// Appell's particle built from C++ with the model-building API (no file), derived and compiled
// by the symbolic front end, then simulated. Built and run by the tests (ctest -R example_appell).
#include <fmt/format.h>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

int main() {
  using namespace nhdyn;
  symbolic::SpecBuilder b("appell");
  b.description("Appell's particle, built in C++");
  b.coordinate("x").coordinate("y").coordinate("z");  // z points down
  b.parameter("m", 1.0, "kg").parameter("g", 9.81, "m/s^2").parameter("a", 0.5);
  b.kinetic_energy("m/2*(x'^2 + y'^2 + z'^2)");
  b.potential_energy("-m*g*z");
  b.constraint("appell", ConstraintLevel::velocity, "z'^2 - a^2*(x'^2 + y'^2)");
  b.independent({"x", "y"});
  b.initial("x", "0", "1").initial("y", "0", "0.5").initial("z", "0", "a*sqrt(1 + 0.25)");
  const Model model = symbolic::compile_model(b.build());

  SimulationOptions options;
  options.t_end = 10.0;
  options.output_step = 1.0;
  double speed = 0.0;
  const SimulationSummary s = simulate(model, options, [&](const Data& d) { speed = std::hypot(d.v(0), d.v(1)); });
  if (s.status != Status::ok) {
    fmt::print(stderr, "simulation failed: {}\n", s.message);
    return 1;
  }
  // The horizontal speed grows linearly: u(10) = u0 + 10 g a / (1 + a^2) (docs/derivations/appell.md).
  const double expected = std::sqrt(1.25) + 10.0 * 9.81 * 0.5 / 1.25;
  fmt::print("horizontal speed at t = 10 s: {:.12f} (closed form {:.12f}); energy drift {:.2e}\n", speed, expected,
             s.energy.drift);
  return std::abs(speed - expected) < 1e-8 * expected ? 0 : 1;
}
