// The compiled evaluator (jit/compiled_evaluator.hpp) against the interpreter it replaces: the
// same terms and the same q'' to round-off on every example model (dense and sparse), after a
// parameter change too; the cache reused by a second build; and the failures it must survive (no
// compiler, a corrupt cache entry) turned into a clear error or, under `auto`, the interpreter.
// The reference of both: the interpreter's prepared terms (constants folded, steps fused and
// reordered, model/tape.hpp) equal their program run instruction by instruction, to the bit.
#include <gtest/gtest.h>
#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "nhdyn/analysis/residuals.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/jit/compiled_evaluator.hpp"
#include "nhdyn/model/contact_forces.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/output.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/model/tape.hpp"

namespace nhdyn::jit {
namespace {

namespace fs = std::filesystem;

std::string example(const std::string& file) { return (fs::path(NHDYN_SOURCE_DIR) / "examples" / file).string(); }

// A cache directory of the test's own, removed afterwards.
class Jit : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / (std::string("nhdyn-jit-") + info->name() + "-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    options_.cache_dir = dir_.string();
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  JitOptions options_;
};

// Every output of the terms of both models at a few states near the initial one.
void expect_same_terms(const Model& interpreted, const Model& compiled, double tolerance) {
  const int n = interpreted.n(), s = interpreted.s();
  std::mt19937 random(7);
  std::uniform_real_distribution<double> d(-0.3, 0.3);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<double> q(static_cast<std::size_t>(n)), v(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      q[static_cast<std::size_t>(i)] = interpreted.q0[i] + d(random);
      v[static_cast<std::size_t>(i)] = interpreted.v0[i] + d(random);
    }
    const double t = 0.3 * trial;
    std::vector<double> out1(static_cast<std::size_t>(n * n + 2 * n + s * n + s)), out2(out1.size(), -7.0);
    std::vector<double> scratch1(interpreted.evaluator->scratch_size()), scratch2(compiled.evaluator->scratch_size());
    const auto out = [&](std::vector<double>& o) {
      double* p = o.data();
      return TermsOut{p, p + n * n, p + n * n + n, p + n * n + 2 * n, p + n * n + 2 * n + s * n};
    };
    interpreted.evaluator->terms(t, q.data(), v.data(), scratch1.data(), out(out1));
    compiled.evaluator->terms(t, q.data(), v.data(), scratch2.data(), out(out2));
    for (std::size_t k = 0; k < out1.size(); ++k)
      ASSERT_NEAR(out2[k], out1[k], tolerance * (1.0 + std::abs(out1[k]))) << "output " << k << ", trial " << trial;
  }
}

// q'' of both models (sanh, D from QR) at their initial state.
void expect_same_acceleration(const Model& interpreted, const Model& compiled, double tolerance) {
  Data a = make_data(interpreted), b = make_data(compiled);
  FormulationOptions options;
  ASSERT_EQ(compute_dynamics(interpreted, a, options, interpreted.t0, interpreted.q0.data(), interpreted.v0.data()),
            Status::ok);
  ASSERT_EQ(compute_dynamics(compiled, b, options, compiled.t0, compiled.q0.data(), compiled.v0.data()), Status::ok);
  for (int i = 0; i < interpreted.n(); ++i)
    EXPECT_NEAR(b.qdd[i], a.qdd[i], tolerance * (1.0 + std::abs(a.qdd[i]))) << interpreted.coordinates[static_cast<std::size_t>(i)];
}

TEST_F(Jit, EveryExampleGivesTheInterpretersTermsAndAccelerations) {
  for (const char* file : {"knife_edge.toml", "chaplygin_sleigh.toml", "double_pendulum.toml", "slider_crank.toml",
                           "rolling_disk.toml", "diff_drive.toml", "rolling_disk_bodies.toml", "whipple_bicycle.toml"}) {
    SCOPED_TRACE(file);
    const Model interpreted = load_model(example(file));
    JitReport report;
    const Model compiled = make_compiled(interpreted, options_, &report);
    EXPECT_TRUE(is_compiled(compiled));
    EXPECT_FALSE(is_compiled(interpreted));
    EXPECT_TRUE(fs::exists(report.object));  // compiled now, or cached: rolling_disk_bodies.toml
                                             // makes the same program as rolling_disk.toml
    // The same operations in the same order without fused multiply-adds: equal to the last bit
    // is expected, round-off is what is asked.
    expect_same_terms(interpreted, compiled, 1e-14);
    expect_same_acceleration(interpreted, compiled, 1e-12);
  }
}

// A model with programs (docs/derivations/program-motion.md): the compiled terms and the
// interpreted program rows together give the interpreter's q'' and actuator forces u.
TEST_F(Jit, ProgramsKeepTheirActuatorForces) {
  for (const char* file : {"sled_heading_program.toml", "arm_circle_program.toml", "cart_pendulum_program.toml"}) {
    SCOPED_TRACE(file);
    const Model interpreted = load_model(example(file));
    ASSERT_GT(interpreted.m(), 0);
    const Model compiled = make_compiled(interpreted, options_);
    expect_same_acceleration(interpreted, compiled, 1e-12);
    Data a = make_data(interpreted), b = make_data(compiled);
    ASSERT_EQ(compute_dynamics(interpreted, a, {}, interpreted.t0, interpreted.q0.data(), interpreted.v0.data()),
              Status::ok);
    ASSERT_EQ(compute_dynamics(compiled, b, {}, compiled.t0, compiled.q0.data(), compiled.v0.data()), Status::ok);
    ASSERT_EQ(b.motion.u.size(), interpreted.m());
    for (int j = 0; j < interpreted.m(); ++j) {
      EXPECT_NE(a.motion.u(j), 0.0) << "an actuator force that is zero proves nothing";
      EXPECT_NEAR(b.motion.u(j), a.motion.u(j), 1e-12 * (1.0 + std::abs(a.motion.u(j))));
    }
  }
}

// The output rows of a compiled model run compiled too (NativeTape, model/tape.hpp): the
// bicycle's contact forces, residuals, energy and derived outputs (the multibody points), and a
// file's [outputs], equal the interpreter's, before and after a parameter change (the stage follows the values).
TEST_F(Jit, OutputRowsGiveTheInterpretersContactForcesAndOutputs) {
  for (const char* file : {"whipple_bicycle.toml", "pendulum_outputs.toml"}) {
    SCOPED_TRACE(file);
    const Model interpreted = load_model(example(file));
    const Model compiled = make_compiled(interpreted, options_);
    ASSERT_GT(compiled.outputs.count(), 0);
    EXPECT_TRUE(compiled.outputs.native != nullptr);
    EXPECT_EQ(compiled.contact_forces != nullptr, interpreted.contact_forces != nullptr);
    if (compiled.contact_forces) {
      EXPECT_TRUE(compiled.contact_forces->native != nullptr);
    }
    for (const bool changed : {false, true}) {
      Model a = interpreted, b = compiled;
      if (changed) {
        const std::string name = a.parameters.front().name;
        const double value = 1.1 * a.parameters.front().value + 0.01;
        set_parameter(a, name, value);
        set_parameter(b, name, value);
      }
      Data da = make_data(a), db = make_data(b);
      ASSERT_EQ(compute_dynamics(a, da, {}, a.t0, a.q0.data(), a.v0.data()), Status::ok);
      ASSERT_EQ(compute_dynamics(b, db, {}, b.t0, b.q0.data(), b.v0.data()), Status::ok);
      compute_contact_forces(a, da);
      compute_contact_forces(b, db);
      compute_outputs(a, da);
      compute_outputs(b, db);
      compute_residuals(a, da);
      compute_residuals(b, db);
      compute_energy(a, da);
      compute_energy(b, db);
      EXPECT_NE(da.energy, 0.0);
      EXPECT_NEAR(db.energy, da.energy, 1e-12 * (1.0 + std::abs(da.energy)));
      for (Eigen::Index i = 0; i < da.f.size(); ++i) EXPECT_NEAR(db.f(i), da.f(i), 1e-12);
      for (Eigen::Index i = 0; i < da.phi.size(); ++i) EXPECT_NEAR(db.phi(i), da.phi(i), 1e-12);
      ASSERT_EQ(db.outputs.values.size(), da.outputs.values.size());
      double largest = 0.0;
      for (Eigen::Index i = 0; i < da.outputs.values.size(); ++i) {
        largest = std::max(largest, std::abs(da.outputs.values(i)));
        EXPECT_NEAR(db.outputs.values(i), da.outputs.values(i), 1e-12 * (1.0 + std::abs(da.outputs.values(i))));
      }
      EXPECT_GT(largest, 0.0) << "outputs that are all zero prove nothing";
      ASSERT_EQ(db.contact.values.size(), da.contact.values.size());
      for (Eigen::Index i = 0; i < da.contact.values.size(); ++i) {
        if (std::isnan(da.contact.values(i))) {
          EXPECT_TRUE(std::isnan(db.contact.values(i)));
          continue;
        }
        EXPECT_NEAR(db.contact.values(i), da.contact.values(i), 1e-10 * (1.0 + std::abs(da.contact.values(i))));
      }
      if (interpreted.contact_forces) {
        // The normal force of the rear wheel carries weight: a contact force that is zero proves nothing.
        EXPECT_GT(std::abs(da.contact.values(3)), 1.0);
      }
    }
  }
}

TEST_F(Jit, ParametersAreDataAfterCompilation) {
  const Model interpreted = load_model(example("double_pendulum.toml"));
  const Model compiled = make_compiled(interpreted, options_);
  Model a = interpreted, b = compiled;
  set_parameter(a, "m2", 1.7);
  set_parameter(b, "m2", 1.7);
  set_parameter(a, "l2", 0.4);
  set_parameter(b, "l2", 0.4);
  EXPECT_TRUE(is_compiled(b));
  expect_same_terms(a, b, 1e-14);
  // And no second compile: the object is the same for every value.
  JitReport report;
  make_compiled(a, options_, &report);
  EXPECT_FALSE(report.compiled);
}

TEST_F(Jit, SparseModelsFillTheSparseAndTheDenseTerms) {
  // A chain of 70 bodies is compiled sparse (symbolic/compile.hpp, kSparseFrom); its model file
  // comes from the CLI, as a user makes it.
  fs::create_directories(dir_);
  const fs::path file = dir_ / "chain.toml";
  const std::string command = "'" NHDYN_CLI_PATH "' example chain --bodies 70 -o '" + file.string() + "' > /dev/null";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const Model interpreted = load_model(file.string());
  ASSERT_NE(interpreted.evaluator->sparsity(), nullptr) << "the chain should be compiled sparse";
  const Model compiled = make_compiled(interpreted, options_);
  ASSERT_NE(compiled.evaluator->sparsity(), nullptr);
  expect_same_terms(interpreted, compiled, 1e-14);
  expect_same_acceleration(interpreted, compiled, 1e-12);
}

TEST_F(Jit, TheSecondBuildLoadsTheCachedObject) {
  const Model model = load_model(example("slider_crank.toml"));
  JitReport first, second;
  make_compiled(model, options_, &first);
  make_compiled(model, options_, &second);
  EXPECT_TRUE(first.compiled);
  EXPECT_FALSE(second.compiled);
  EXPECT_EQ(first.object, second.object);
  EXPECT_TRUE(fs::exists(second.object));
  // Nothing but the object and its check file is left in the cache (no temporaries, sources or logs).
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    ++files;
    EXPECT_TRUE(entry.path().extension() == ".so" || entry.path().extension() == ".check") << entry.path();
  }
  EXPECT_EQ(files, 2);
}

TEST_F(Jit, ConcurrentBuildsOfOneModelBothGetAWholeObject) {
  // Each compiles under a name of its own and renames into place: neither loads a partial file.
  const Model model = load_model(example("rolling_disk.toml"));
  Model first, second;
  std::string error;
  std::thread other([&] {
    try {
      second = make_compiled(model, options_);
    } catch (const std::exception& e) {
      error = e.what();
    }
  });
  first = make_compiled(model, options_);
  other.join();
  EXPECT_TRUE(error.empty()) << error;
  expect_same_terms(model, first, 1e-14);
  expect_same_terms(model, second, 1e-14);
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_TRUE(entry.path().extension() == ".so" || entry.path().extension() == ".check")
        << "left behind: " << entry.path();
}

TEST_F(Jit, ACorruptCacheEntryIsCompiledAgain) {
  const Model model = load_model(example("knife_edge.toml"));
  JitReport first;
  make_compiled(model, options_, &first);
  std::ofstream(first.object, std::ios::binary | std::ios::trunc) << "not an object";
  JitReport second;
  const Model compiled = make_compiled(model, options_, &second);
  EXPECT_TRUE(second.compiled);
  expect_same_terms(model, compiled, 1e-14);
}

TEST_F(Jit, AMissingCompilerIsAnErrorOfMakeCompiledAndTheInterpreterWithANoticeForARun) {
  options_.compiler = "/nonexistent/c++";
  const Model model = load_model(example("whipple_bicycle.toml"));
  try {
    make_compiled(model, options_);
    FAIL() << "no error";
  } catch (const JitError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/c++"), std::string::npos) << e.what();
  }
  for (const EvaluatorChoice choice : {EvaluatorChoice::automatic, EvaluatorChoice::compiled}) {
    std::string notice;
    const Model fallback = with_evaluator(model, choice, &notice, options_);
    EXPECT_FALSE(is_compiled(fallback));
    EXPECT_NE(notice.find("interpreter"), std::string::npos) << notice;
    EXPECT_NE(notice.find("/nonexistent/c++"), std::string::npos) << notice;
    EXPECT_EQ(notice.find('\n'), std::string::npos) << "one line";
  }
}

// The processors this process may run on.
int processors() {
  cpu_set_t cpus;
  return sched_getaffinity(0, sizeof cpus, &cpus) == 0 ? CPU_COUNT(&cpus) : 1;
}

// `auto` on a cold cache: the model runs on the interpreter while the compile goes on, and switches
// to the compiled code once it is loaded. The run below waits at its 20th row until then, so the
// switch falls mid-run; every row (q, q', q'', R, residuals, energy, contact forces) equals the
// interpreter's run to the bit, before and after it. The object is then in the cache for the
// next `auto`, which loads it at once.
TEST_F(Jit, AutoOnAColdCacheStartsInterpretedAndSwitchesMidRunToTheSameNumbers) {
  const Model model = load_model(example("whipple_bicycle.toml"));
  const Model automatic = with_evaluator(model, EvaluatorChoice::automatic, nullptr, options_);
  if (processors() < 2) {  // the compile would take the run's processor: the interpreter stays
    EXPECT_EQ(background_state(automatic), BackgroundState::none);
    GTEST_SKIP() << "one processor available: auto keeps the interpreter";
  }
  ASSERT_EQ(background_state(automatic), BackgroundState::compiling);  // the compile takes seconds
  EXPECT_FALSE(is_compiled(automatic));
  SimulationOptions run;
  run.t_end = 2.0;
  run.output_step = 0.01;
  const auto rows_of = [&](const Model& m, bool wait_at_row_20) {
    std::vector<std::vector<double>> rows;
    std::vector<double> row;
    simulate(m, run, [&](const Data& data) {
      if (wait_at_row_20 && rows.size() == 20) {
        EXPECT_EQ(background_state(m), BackgroundState::compiling) << "switched before the wait";
        for (int i = 0; i < 6000 && background_state(m) == BackgroundState::compiling; ++i)
          std::this_thread::sleep_for(std::chrono::milliseconds(20));
        EXPECT_EQ(background_state(m), BackgroundState::switched);
      }
      fill_result_row(m, data, row);
      rows.push_back(row);
    });
    return rows;
  };
  const std::vector<std::vector<double>> interpreted = rows_of(model, false), switched = rows_of(automatic, true);
  ASSERT_EQ(switched.size(), interpreted.size());
  ASSERT_EQ(interpreted.size(), 201u);
  for (std::size_t r = 0; r < interpreted.size(); ++r)
    for (std::size_t c = 0; c < interpreted[r].size(); ++c)
      ASSERT_EQ(std::memcmp(&switched[r][c], &interpreted[r][c], sizeof(double)), 0)
          << "row " << r << ", column " << c << ": " << switched[r][c] << " against " << interpreted[r][c];
  JitReport again;
  EXPECT_TRUE(is_compiled(with_evaluator(model, EvaluatorChoice::automatic, nullptr, options_, &again)));
  EXPECT_FALSE(again.compiled) << "loaded from the cache";
}

// A run that ends before the background compile does not wait for it: the compile is stopped when
// the model goes, and leaves no temporary (source, log, partial object) in the cache.
TEST_F(Jit, AutoStopsAnUnfinishedCompileAndLeavesNothingBehind) {
  const Model model = load_model(example("whipple_bicycle.toml"));
  {
    const Model automatic = with_evaluator(model, EvaluatorChoice::automatic, nullptr, options_);
    if (processors() < 2) GTEST_SKIP() << "one processor available: auto keeps the interpreter";
    ASSERT_EQ(background_state(automatic), BackgroundState::compiling);
    // Until the compiler has written its source, there is nothing to remove: wait for it.
    bool source = false;
    for (int i = 0; i < 500 && !source; ++i) {
      for (const auto& entry : fs::directory_iterator(dir_)) source = source || entry.path().extension() == ".cpp";
      if (!source) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_TRUE(source) << "the compile did not start";
  }
  for (const auto& entry : fs::directory_iterator(dir_))
    ADD_FAILURE() << "left behind: " << entry.path();
}

// The files a compile of a process gone left behind (a run ended by a signal) are removed by the
// next compile in the cache; those of a live process (this one) and the entries are kept.
TEST_F(Jit, ACompileRemovesTheFilesOfCompilesWhoseProcessIsGone) {
  pid_t gone = 4'000'000;  // above Linux's largest pid (4194304 is the limit; take one not running)
  while (::kill(gone, 0) == 0 || errno != ESRCH) --gone;
  fs::create_directories(dir_);
  const std::string g = std::to_string(gone), me = std::to_string(::getpid());
  const std::vector<std::string> orphans = {"0123abcd-" + g + "-1.cpp", "0123abcd-" + g + "-1.log",
                                            "0123abcd.so.tmp-" + g + "-1", "0123abcd.so.check.tmp-" + g + "-1",
                                            "version-" + g + "-7.log"};
  const std::vector<std::string> kept = {"0123abcd-" + me + "-99.cpp", "0123abcd.so", "0123abcd.so.check"};
  for (const std::string& name : orphans) std::ofstream(dir_ / name) << "x";
  for (const std::string& name : kept) std::ofstream(dir_ / name) << "x";
  make_compiled(load_model(example("knife_edge.toml")), options_);
  for (const std::string& name : orphans) EXPECT_FALSE(fs::exists(dir_ / name)) << name;
  for (const std::string& name : kept) EXPECT_TRUE(fs::exists(dir_ / name)) << name;
}

TEST_F(Jit, AutoLeavesSmallModelsToTheInterpreter) {
  const Model model = load_model(example("knife_edge.toml"));
  std::string notice;
  EXPECT_FALSE(is_compiled(with_evaluator(model, EvaluatorChoice::automatic, &notice, options_)));
  EXPECT_TRUE(notice.empty());
  EXPECT_FALSE(fs::exists(dir_)) << "nothing compiled";
}

TEST_F(Jit, HandWrittenModelsHaveNothingToCompile) {
  const Model model = load_model("sled");
  EXPECT_THROW(make_compiled(model, options_), JitError);
  std::string notice;
  EXPECT_FALSE(is_compiled(with_evaluator(model, EvaluatorChoice::automatic, &notice, options_)));
  EXPECT_TRUE(notice.empty()) << notice;
  EXPECT_FALSE(is_compiled(with_evaluator(model, EvaluatorChoice::compiled, &notice, options_)));
  EXPECT_NE(notice.find("nothing to compile"), std::string::npos) << notice;
}

TEST(Interpreter, PreparedTermsOfEveryExampleAreItsProgramToTheBit) {
  for (const char* file : {"knife_edge.toml", "chaplygin_sleigh.toml", "double_pendulum.toml", "slider_crank.toml",
                           "rolling_disk.toml", "diff_drive.toml", "whipple_bicycle.toml"}) {
    SCOPED_TRACE(file);
    const Model model = load_model(example(file));
    const auto& evaluator = dynamic_cast<const TapeEvaluator&>(*model.evaluator);
    const Tape& program = evaluator.tapes().terms;  // bound to the parameters
    ASSERT_FALSE(evaluator.tapes().sparsity.has_value());
    const int n = model.n(), s = model.s();
    std::mt19937 random(11);
    std::uniform_real_distribution<double> d(-0.5, 0.5);
    for (int trial = 0; trial < 3; ++trial) {
      std::vector<double> q(static_cast<std::size_t>(n)), v(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) {
        q[static_cast<std::size_t>(i)] = model.q0[i] + d(random);
        v[static_cast<std::size_t>(i)] = model.v0[i] + d(random);
      }
      const double t = 0.7 * trial;
      std::vector<double> registers(static_cast<std::size_t>(program.registers()));
      std::vector<double> expected(static_cast<std::size_t>(program.outputs()));
      program.run(t, q.data(), v.data(), registers.data(), expected.data());
      std::vector<double> got(expected.size(), -7.0), scratch(evaluator.scratch_size());
      double* p = got.data();
      evaluator.terms(t, q.data(), v.data(), scratch.data(),
                      TermsOut{p, p + n * n, p + n * n + n, p + n * n + 2 * n, p + n * n + 2 * n + s * n});
      for (std::size_t k = 0; k < got.size(); ++k)
        ASSERT_EQ(std::memcmp(&got[k], &expected[k], sizeof(double)), 0)
            << "output " << k << ", trial " << trial << ": " << got[k] << " != " << expected[k];
    }
  }
}

TEST(EvaluatorChoice, Parses) {
  EXPECT_EQ(parse_evaluator_choice("interpreted"), EvaluatorChoice::interpreted);
  EXPECT_EQ(parse_evaluator_choice("compiled"), EvaluatorChoice::compiled);
  EXPECT_EQ(parse_evaluator_choice("auto"), EvaluatorChoice::automatic);
  EXPECT_THROW(parse_evaluator_choice("jit"), InputError);
}

}  // namespace
}  // namespace nhdyn::jit
