// The N-trailer chain (docs/gallery/chain.md) against model files: with N = 1 it is the Chaplygin
// sleigh of examples/chaplygin_sleigh.toml (J = m (rho^2 - a^2)), at random states on the blade and
// along the file's whole run; the model file written for N = 5 loads back to the accelerations of
// the Spec built in C++; examples/chain.toml is the generator's output for N = 3, byte for byte.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include "gallery/gallery.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/symbolic/chain.hpp"

namespace nhdyn::gallery {
namespace {

// The sleigh file's values: m = 2, a = 0.3, rho = 0.5, v0 = -1, w0 = 1.
symbolic::ChainParameters sleigh_parameters() {
  symbolic::ChainParameters p;
  p.bodies = 1;
  p.mass = 2.0;
  p.com_offset = 0.3;
  p.inertia = 2.0 * (0.5 * 0.5 - 0.3 * 0.3);
  p.speed = -1.0;
  p.turn_rate = 1.0;
  p.t_end = 8.0;
  return p;
}

// max over random states of |q''_1 - q''_2| / max|q''_2|; `on_blade` puts the velocity of body 1's
// blade along it (other bodies get random states: the models must agree everywhere).
double acceleration_difference(const Model& m1, const Model& m2, bool on_blade) {
  Data d1 = make_data(m1), d2 = make_data(m2);
  const FormulationOptions options{Method::sanh, Complement::qr};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  double worst = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    Vector q(m1.n()), v(m1.n());
    for (int i = 0; i < m1.n(); ++i) {
      q(i) = u(rng);
      v(i) = u(rng);
    }
    if (on_blade) {
      const double speed = u(rng);
      v(0) = speed * std::cos(q(2));
      v(1) = speed * std::sin(q(2));
    }
    EXPECT_EQ(compute_dynamics(m1, d1, options, 0.0, q.data(), v.data()), Status::ok);
    EXPECT_EQ(compute_dynamics(m2, d2, options, 0.0, q.data(), v.data()), Status::ok);
    worst = std::max(worst, (d1.qdd - d2.qdd).cwiseAbs().maxCoeff() / d2.qdd.cwiseAbs().maxCoeff());
  }
  return worst;
}

TEST(ChainGallery, OneBodyIsTheChaplyginSleigh) {
  const Model chain = symbolic::compile_model(symbolic::make_chain_spec(sleigh_parameters()));
  const Model sleigh = load_example("chaplygin_sleigh.toml");
  ASSERT_EQ(chain.n(), 3);
  const double difference = acceleration_difference(chain, sleigh, true);
  EXPECT_LT(difference, 1e-13);
  EXPECT_EQ(chain.q0, sleigh.q0);
  EXPECT_EQ(chain.v0, sleigh.v0);
  const std::vector<Row> a = run_rows(chain, tight_options(8.0, 0.01));
  const std::vector<Row> b = run_rows(sleigh, tight_options(8.0, 0.01));
  ASSERT_EQ(a.size(), b.size());
  double dq = 0.0, dv = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    dq = std::max(dq, (a[i].q - b[i].q).cwiseAbs().maxCoeff());
    dv = std::max(dv, (a[i].v - b[i].v).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(dq, 1e-9);
  EXPECT_LT(dv, 1e-9);
  std::printf("chain N = 1 vs sleigh: q'' %.2e relative, run max |dq| %.2e, max |dv| %.2e\n", difference, dq, dv);
  // Negative control: the inertia about the contact point instead of the centre of mass.
  symbolic::ChainParameters wrong = sleigh_parameters();
  wrong.inertia = 2.0 * 0.5 * 0.5;
  const double wrong_difference =
      acceleration_difference(symbolic::compile_model(symbolic::make_chain_spec(wrong)), sleigh, true);
  EXPECT_GT(wrong_difference, 1e-3);
  std::printf("negative control (J about the blade): q'' %.2e relative\n", wrong_difference);
}

TEST(ChainGallery, ModelFileLoadsBackToTheSameModel) {
  symbolic::ChainParameters p;
  p.bodies = 5;
  p.rear_hitch = 0.45;
  const symbolic::Spec built = symbolic::make_chain_spec(p);
  const symbolic::Spec loaded = load_model_string(symbolic::write_chain_toml(p), "chain5.toml");
  EXPECT_EQ(loaded.name, built.name);
  EXPECT_EQ(loaded.coordinates, built.coordinates);
  ASSERT_EQ(loaded.s(), built.s());
  for (int i = 0; i < built.s(); ++i) {
    EXPECT_EQ(loaded.constraints[i].name, built.constraints[i].name);
    EXPECT_EQ(loaded.constraints[i].level, built.constraints[i].level);
  }
  const Model a = symbolic::compile_model(loaded), b = symbolic::compile_model(built);
  EXPECT_EQ(a.q0, b.q0);
  EXPECT_EQ(a.v0, b.v0);
  const double difference = acceleration_difference(a, b, false);
  EXPECT_LT(difference, 1e-14);
  std::printf("chain N = 5, file against C++: q'' %.2e relative\n", difference);
  EXPECT_EQ(a.defaults.t_end, b.defaults.t_end);
}

TEST(ChainGallery, ExampleFileIsTheGeneratorsOutput) {
  std::ifstream in(example_path("chain.toml"));
  std::stringstream text;
  text << in.rdbuf();
  symbolic::ChainParameters p;
  p.bodies = 3;
  EXPECT_EQ(text.str(), symbolic::write_chain_toml(p))
      << "regenerate it: nhdyn example chain --bodies 3 -o examples/chain.toml";
}

}  // namespace
}  // namespace nhdyn::gallery
