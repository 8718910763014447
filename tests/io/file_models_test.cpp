// The model files against the hand-written models of the foundation: the same q'' and R for
// every formulation at random states, and the closed-form Appell exam run from the file.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn {
namespace {

Model load(const std::string& name) {
  return symbolic::compile_model(load_model_file(std::string(NHDYN_SOURCE_DIR) + "/examples/" + name));
}

TEST(FileModels, SameAccelerationsAndReactionsAsTheHandWrittenModels) {
  const std::pair<std::string, Model> cases[] = {{"appell.toml", make_appell_model()},
                                                 {"sled.toml", make_sled_model(SledVariant::centre_of_mass)},
                                                 {"sled_paper.toml", make_sled_model(SledVariant::paper)}};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (const auto& [file, hand] : cases) {
    const Model model = load(file);
    Data data_file = make_data(model), data_hand = make_data(hand);
    for (int trial = 0; trial < 20; ++trial) {
      Vector q(3), v(3);
      q << U(rng), U(rng), U(rng);
      v << U(rng), U(rng), 0.5 + std::abs(U(rng));  // Appell's paper form needs z' != 0
      for (Formulation m : {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace}) {
        ASSERT_EQ(compute_dynamics(model, data_file, {m, Complement::qr}, 0.0, q.data(), v.data()), Status::ok);
        ASSERT_EQ(compute_dynamics(hand, data_hand, {m, Complement::qr}, 0.0, q.data(), v.data()), Status::ok);
        EXPECT_LT((data_file.qdd - data_hand.qdd).norm(), 1e-12 * (1.0 + data_hand.qdd.norm()))
            << file << " " << formulation_name(m);
        EXPECT_LT((data_file.R - data_hand.R).norm(), 1e-12 * (1.0 + data_hand.R.norm()))
            << file << " " << formulation_name(m);
      }
    }
  }
}

TEST(FileModels, AppellFromTheFileMatchesTheClosedFormAtTenSeconds) {
  const Model model = load("appell.toml");
  AppellParameters p;  // the file's values (checked against the built-in model above)
  SimulationOptions options;
  options.t_end = 10.0;
  options.output_step = 1.0;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-12;
  Vector q_end, v_end;
  const SimulationSummary s = simulate(model, options, [&](const Data& d) {
    q_end = d.q;
    v_end = d.v;
  });
  ASSERT_EQ(s.status, Status::ok) << s.message;
  const double u0 = std::hypot(model.v0(0), model.v0(1));
  const double c = p.g * p.a / (1.0 + p.a * p.a);
  const double dist = u0 * 10.0 + 0.5 * c * 100.0, u = u0 + c * 10.0;
  Vector q(3), v(3);
  q << dist * model.v0(0) / u0, dist * model.v0(1) / u0, dist * p.a;
  v << u * model.v0(0) / u0, u * model.v0(1) / u0, u * p.a;
  EXPECT_LT((q_end - q).norm(), 1e-9 * q.norm());
  EXPECT_LT((v_end - v).norm(), 1e-9 * v.norm());
}

}  // namespace
}  // namespace nhdyn
