// The C++ API in one page: build the sled, make its Data, evaluate the accelerations and
// reactions with every formulation at the initial state, then simulate ten seconds and print
// the summary. Built and run by the tests (ctest -R example_sled_api).
#include <fmt/format.h>

#include <cstdio>

#include "nhdyn/model/sled.hpp"
#include "nhdyn/nhdyn.hpp"

int main() {
  using namespace nhdyn;
  const Model model = make_sled_model(SledVariant::centre_of_mass);
  Data data = make_data(model);

  for (Formulation method : {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace}) {
    const Status status = compute_dynamics(model, data, {method, Complement::qr}, model.t0, model.q0.data(),
                                           model.v0.data());
    if (status != Status::ok) {
      fmt::print(stderr, "{}: {}\n", formulation_name(method), describe(status));
      return 1;
    }
    fmt::print("{:<15} q'' = ({:+.12f}, {:+.12f}, {:+.12f})   R = ({:+.12f}, {:+.12f}, {:+.12f})\n",
               formulation_name(method), data.qdd(0), data.qdd(1), data.qdd(2), data.R(0), data.R(1), data.R(2));
  }

  SimulationOptions options;
  options.t_end = 10.0;
  options.output_step = 0.1;
  double x_end = 0.0;
  const SimulationSummary summary = simulate(model, options, [&](const Data& d) { x_end = d.q(0); });
  if (summary.status != Status::ok) {
    fmt::print(stderr, "simulation failed: {}\n", summary.message);
    return 1;
  }
  fmt::print("10 s: x = {:.6f} m, {} steps, max velocity residual {:.2e}, energy drift {:.2e}\n", x_end,
             summary.stats.steps, summary.residuals.velocity, summary.energy.drift);
  return 0;
}
