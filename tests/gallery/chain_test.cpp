// The N-trailer chain (docs/gallery/chain.md) against model files: with N = 1 it is the Chaplygin
// sleigh of examples/chaplygin_sleigh.toml (J = m (rho^2 - a^2)), at random states on the blade and
// along the file's whole run; the model file written for N = 5 loads back to the accelerations of
// the Spec built in C++; examples/chain.toml is the generator's output for N = 3, byte for byte.
// The sparse path (model/data.hpp) against the dense one on the chain compiled sparse: the same
// q'', R, multipliers and residuals at random states, the same motion through simulate (plain,
// projected, from a fixed initial state), the same linearization of another model compiled
// sparse; and `nhdyn simulate` takes the sparse path for a chain file of 30 bodies.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>

#include "gallery/gallery.hpp"
#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/analysis/residuals.hpp"
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
  const FormulationOptions options{Formulation::sanh, Complement::qr};
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

Model chain_model(int bodies, symbolic::TermsLayout layout) {
  symbolic::ChainParameters p;
  p.bodies = bodies;
  return symbolic::compile_model(symbolic::make_chain_spec(p), symbolic::CompileOptions{layout});
}

double relative(const Vector& x, const Vector& reference) {
  return (x - reference).norm() / std::max(reference.norm(), 1e-300);
}

DataOptions on_path(Path path) {
  DataOptions o;
  o.path = path;
  return o;
}

TEST(ChainSparsePath, SparseAndDenseKernelsAgreeAtRandomStates) {
  for (const int bodies : {2, 6}) {
    SCOPED_TRACE(bodies);
    const Model model = chain_model(bodies, symbolic::TermsLayout::sparse);  // forced sparse below 64 coordinates
    Data sparse = make_data(model), dense = make_data(model, on_path(Path::dense));
    ASSERT_TRUE(sparse.sparse);
    ASSERT_FALSE(dense.sparse);
    std::mt19937 rng(13);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 5; ++trial)
      for (Formulation m : {Formulation::sanh, Formulation::lagrange}) {
        Vector q = model.q0, v = model.v0;
        for (int i = 0; i < model.n(); ++i) {
          q(i) += 0.3 * u(rng);
          v(i) += u(rng);
        }
        const FormulationOptions options(m, Complement::qr);
        ASSERT_EQ(compute_dynamics(model, dense, options, 0.0, q.data(), v.data()), Status::ok);
        ASSERT_EQ(compute_dynamics(model, sparse, options, 0.0, q.data(), v.data()), Status::ok)
            << sparse.failed_quantity;
        EXPECT_LT(relative(sparse.qdd, dense.qdd), 1e-11) << formulation_name(m);
        EXPECT_LT(relative(sparse.R, dense.R), 1e-10) << formulation_name(m);
        if (m == Formulation::lagrange) {
          EXPECT_LT(relative(sparse.lambda, dense.lambda), 1e-10);
        }
        compute_residuals(model, dense);
        compute_residuals(model, sparse);
        EXPECT_LT((sparse.e - dense.e).norm(), 1e-11 * (1.0 + dense.b.norm() * dense.qdd.norm())) << formulation_name(m);
        EXPECT_EQ(sparse.phi, dense.phi);
        EXPECT_EQ(sparse.f, dense.f);
      }
  }
}

TEST(ChainSparsePath, SimulationsOnBothPathsFollowTheSameMotion) {
  const Model model = chain_model(5, symbolic::TermsLayout::sparse);
  for (Stabilization stabilization : {Stabilization::none, Stabilization::projection, Stabilization::baumgarte})
    for (Formulation m : {Formulation::sanh, Formulation::lagrange}) {
      SCOPED_TRACE(std::string(stabilization_name(stabilization)) + " " + std::string(formulation_name(m)));
      SimulationOptions options = tight_options(1.0, 0.25, m);
      options.stabilization = stabilization;
      options.fix_initial = stabilization == Stabilization::projection;
      SimulationSummary sparse_summary, dense_summary;
      options.path = Path::automatic;
      const std::vector<Row> sparse = run_rows(model, options, &sparse_summary);
      options.path = Path::dense;
      const std::vector<Row> dense = run_rows(model, options, &dense_summary);
      EXPECT_TRUE(sparse_summary.sparse);
      EXPECT_FALSE(dense_summary.sparse);
      ASSERT_EQ(sparse.size(), dense.size());
      for (std::size_t i = 0; i < sparse.size(); ++i) {
        // Two runs at rtol 1e-10 whose right-hand sides differ by round-off.
        EXPECT_LT((sparse[i].q - dense[i].q).cwiseAbs().maxCoeff(), 1e-8) << "t = " << sparse[i].t;
        EXPECT_LT((sparse[i].v - dense[i].v).cwiseAbs().maxCoeff(), 1e-8) << "t = " << sparse[i].t;
      }
      EXPECT_LT(std::abs(sparse_summary.residuals.position - dense_summary.residuals.position), 1e-8);
      // Without Baumgarte's terms b q'' + b0 is round-off; with them it is the stabilization itself.
      if (stabilization == Stabilization::baumgarte) {
        EXPECT_LT(std::abs(sparse_summary.residuals.acceleration - dense_summary.residuals.acceleration), 1e-9);
      } else {
        EXPECT_LT(sparse_summary.residuals.acceleration, 1e-10);
      }
    }
}

TEST(ChainSparsePath, UdwadiaKalabaAndNullspaceOfASparseModelRunDense) {
  const Model model = chain_model(3, symbolic::TermsLayout::sparse);
  for (Formulation m : {Formulation::udwadia_kalaba, Formulation::nullspace}) {
    SimulationSummary summary;
    const std::vector<Row> rows = run_rows(model, tight_options(0.5, 0.25, m), &summary);
    EXPECT_FALSE(summary.sparse) << formulation_name(m);
    SimulationSummary reference;
    const std::vector<Row> sanh = run_rows(model, tight_options(0.5, 0.25), &reference);
    EXPECT_TRUE(reference.sparse);
    EXPECT_LT((rows.back().q - sanh.back().q).cwiseAbs().maxCoeff(), 1e-8) << formulation_name(m);
  }
}

TEST(LinearizationSparsePath, AModelCompiledSparseLinearizesLikeTheDenseOne) {
  // The upright rolling disk: its terms tape compiled sparse gives its tangents in the
  // compressed layout (analysis/linearization.cpp scatters them).
  const symbolic::Spec spec = load_model_file(example_path("rolling_disk_upright.toml"));
  const Model dense = symbolic::compile_model(spec, symbolic::CompileOptions{symbolic::TermsLayout::dense});
  const Model sparse = symbolic::compile_model(spec, symbolic::CompileOptions{symbolic::TermsLayout::sparse});
  ASSERT_NE(sparse.evaluator->sparsity(), nullptr);
  const Linearization ld = calc_linearization(dense), ls = calc_linearization(sparse);
  EXPECT_EQ(ls.derivatives, DerivativeMethod::tangent);
  EXPECT_EQ(ls.state, ld.state);
  ASSERT_EQ(ls.state_matrix.rows(), ld.state_matrix.rows());
  EXPECT_LT((ls.state_matrix - ld.state_matrix).norm(), 1e-12 * (1.0 + ld.state_matrix.norm()));
  EXPECT_LT((ls.Fq - ld.Fq).norm(), 1e-12 * (1.0 + ld.Fq.norm()));
  EXPECT_LT((ls.Fv - ld.Fv).norm(), 1e-12 * (1.0 + ld.Fv.norm()));
}

TEST(ChainSparsePath, CommandLineSimulatesA30BodyChainOnTheSparsePath) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("nhdyn-chain-sparse-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path toml = dir / "c.toml", csv = dir / "c.csv", out = dir / "stdout.txt";
  const std::string cli = std::string("'") + NHDYN_CLI_PATH + "'";
  ASSERT_EQ(std::system((cli + " example chain --bodies 30 -o '" + toml.string() + "' > /dev/null").c_str()), 0);
  const std::string command = cli + " simulate '" + toml.string() + "' --t-end 0.5 --output-step 0.25 -o '" +
                              csv.string() + "' > '" + out.string() + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  std::ifstream said(out);
  std::stringstream text;
  text << said.rdbuf();
  EXPECT_NE(text.str().find("sparse path"), std::string::npos) << text.str();
  // The last row against the library's dense path on the same file and options.
  const Model model = symbolic::compile_model(load_model_file(toml));
  ASSERT_NE(model.evaluator->sparsity(), nullptr);  // 90 coordinates: compiled sparse
  std::ifstream in(csv);
  std::string line, last;
  while (std::getline(in, line) && line.starts_with('#')) {
  }  // the provenance header (io/provenance.hpp), then the column names
  int rows = 0;
  while (std::getline(in, line)) {
    last = line;
    ++rows;
  }
  EXPECT_EQ(rows, 3);
  std::vector<double> values;
  std::stringstream fields(last);
  for (std::string field; std::getline(fields, field, ',');) values.push_back(std::stod(field));
  ASSERT_GT(values.size(), static_cast<std::size_t>(model.n()));
  EXPECT_DOUBLE_EQ(values[0], 0.5);
  // The file's tolerances (rtol 1e-10, atol 1e-12) are tight_options'.
  SimulationOptions options = tight_options(0.5, 0.25);
  options.path = Path::dense;
  SimulationSummary summary;
  const std::vector<Row> dense = run_rows(model, options, &summary);
  EXPECT_FALSE(summary.sparse);
  for (int i = 0; i < model.n(); ++i)
    EXPECT_NEAR(values[static_cast<std::size_t>(1 + i)], dense.back().q(i), 1e-8) << model.coordinates[static_cast<std::size_t>(i)];
  fs::remove_all(dir);
}

}  // namespace
}  // namespace nhdyn::gallery
