// The in-process half of `make bench-check` (scripts/bench-check runs it and the whole-process
// pairs): paired ratios of two jobs measured in one process, A B A B ..., each pair's ratio
// taken from the process's CPU time (every thread's), so that the machine's speed (shared, noisy)
// divides out.
// Prints one line per ratio:
//   NAME median min max A_median_seconds B_median_seconds
// The ratios (the names are those of bench/baselines):
//   bicycle_rhs_compiled_vs_interpreted  one right-hand side of examples/whipple_bicycle.toml
//                                        (compute_dynamics: terms, then sanh with D from QR),
//                                        compiled evaluator over interpreter
//   bicycle_rows_1001_vs_2               simulate() 10 s of the bicycle (dopri5 at rtol 1e-10,
//                                        atol 1e-12, a roll-rate kick of 0.5 rad/s) with every
//                                        row filled and written as CSV (fill_result_row,
//                                        CsvWriter): 1001 rows (output step 0.01 s) over 2 rows,
//                                        interpreted
//   bicycle_rows_1001_vs_2_compiled      the same with the compiled evaluator
//   bicycle_rows_1001_vs_2_in_memory     the same 10 s with the rows kept in memory (Trajectory,
//                                        what nhdyn.simulate returns) instead of written as CSV
//   bicycle_rows_1001_vs_2_in_memory_compiled  the same with the compiled evaluator
//   sled_watch_on_vs_off                 simulate() 200 s of examples/sled.toml (dopri5 at rtol 1e-8,
//                                        atol 1e-10, 2001 rows, nothing written) with the constraint
//                                        watch over the same without it: what the watch costs a
//                                        small model, whose right-hand side is cheapest
//   bicycle_watch_on_vs_off_compiled     the bicycle's 10 s run as above (1001 rows, compiled
//                                        evaluator, nothing written), with the watch over without
//   rattleback_rhs_compiled_vs_hand_written   one right-hand side of examples/rattleback.toml
//                                        (compute_dynamics, compiled) over the same equations written
//                                        by hand (check/rattleback_stacked.hpp: the same coordinates,
//                                        A, b, b0, Q + G by vector mechanics, an analytic D, a fixed-
//                                        size 6 x 6 LU), at the example's start; the two q'' are
//                                        compared first (1e-12)
//   rattleback_rhs_interpreted_vs_hand_written  the same, interpreted
//   sled_dopri5_vs_hand_written          simulate() of examples/sled.toml for its 10 s, 20 times
//                                        (dopri5 at rtol 1e-8, atol 1e-10, first step 1e-3, 2 rows,
//                                        nothing written, the default options otherwise: the
//                                        constraint watch on) over the same integration written by
//                                        hand (check/sled_by_hand.hpp:
//                                        the stacked 3 x 3 system written out, a Dormand-Prince 5(4)
//                                        loop for 6 doubles); the step counts and final states are
//                                        compared first
//   sled_dop853_vs_hand_written          the same with dop853 (Dormand-Prince 8(5,3)) on both sides
//   sled_dopri5_compiled_vs_hand_written the dopri5 pair with the sled's terms compiled
//   sled_dop853_compiled_vs_hand_written the dop853 pair with the sled's terms compiled
//   chain_rhs_sparse_vs_reference        one right-hand side of the 300-body chain (n = 900) on the
//                                        sparse path (compute_dynamics, sparse sanh: KLU refactorizes
//                                        b_dep in place), 100 times, over 20 hand-written sled
//                                        integrations (dopri5): a fixed amount of hand-written work,
//                                        so that a slower sparse path shows
// The compiled object comes from the compiled evaluator's cache ($XDG_CACHE_HOME/nhdyn), so only
// the first run on a machine pays the compiler.
//   nhdyn_bench_check EXAMPLES_DIR [PAIRS [FILTER]]   (PAIRS: pairs per ratio, default 7; FILTER:
//                                                   only the ratios whose name contains it)
// NHDYN_BENCH_CLOCK=wall times the pairs by the elapsed time instead of the CPU time.
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "nhdyn/analysis/batch.hpp"
#include "nhdyn/analysis/constraint_watch.hpp"
#include "nhdyn/analysis/residuals.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/jit/compiled_evaluator.hpp"
#include "nhdyn/model/contact_forces.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/output.hpp"
#include "nhdyn/symbolic/chain.hpp"  // write_chain_toml: declared without GiNaC
#include "rattleback_stacked.hpp"
#include "sled_by_hand.hpp"

namespace {

namespace fs = std::filesystem;
using namespace nhdyn;

// The process's CPU time, every thread's: a CSV's rows are formatted on a thread of their own
// (io/csv.hpp), and that work counts. With NHDYN_BENCH_CLOCK=wall, the elapsed time instead
// (CLOCK_MONOTONIC): what a user waits for when the second thread has a core of its own; the
// guard itself reads the CPU clock, which a busy machine disturbs less.
double clock_seconds() {
  static const clockid_t clock = [] {
    const char* which = std::getenv("NHDYN_BENCH_CLOCK");
    return which != nullptr && std::string(which) == "wall" ? CLOCK_MONOTONIC : CLOCK_PROCESS_CPUTIME_ID;
  }();
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double timed(const std::function<void()>& job) {
  const double t0 = clock_seconds();
  job();
  return clock_seconds() - t0;
}

double median(std::vector<double> x) {
  std::sort(x.begin(), x.end());
  const std::size_t k = x.size() / 2;
  return x.size() % 2 ? x[k] : 0.5 * (x[k - 1] + x[k]);
}

// One warm-up pair, then `pairs` pairs A B (the order alternates, so neither side always runs
// second, after the other has warmed the caches).
std::string filter;

void pair(const std::string& name, int pairs, const std::function<void()>& a, const std::function<void()>& b) {
  if (name.find(filter) == std::string::npos) return;
  a();
  b();
  std::vector<double> ta, tb, ratio;
  for (int i = 0; i < pairs; ++i) {
    double x = 0, y = 0;
    if (i % 2 == 0) {
      x = timed(a);
      y = timed(b);
    } else {
      y = timed(b);
      x = timed(a);
    }
    ta.push_back(x);
    tb.push_back(y);
    ratio.push_back(x / y);
  }
  std::printf("%s %.4g %.4g %.4g %.4g %.4g\n", name.c_str(), median(ratio),
              *std::min_element(ratio.begin(), ratio.end()), *std::max_element(ratio.begin(), ratio.end()),
              median(ta), median(tb));
  std::fflush(stdout);
}

void rhs_loop(const Model& model, Data& data, long calls) {
  const FormulationOptions options{Formulation::sanh, Complement::qr};
  for (long i = 0; i < calls; ++i) {
    if (compute_dynamics(model, data, options, 0.0, model.q0.data(), model.v0.data()) != Status::ok) {
      std::fprintf(stderr, "bench-check: compute_dynamics failed on %s\n", model.name.c_str());
      std::exit(1);
    }
  }
}

// The bicycle's 10 s of the rows ratios: dopri5 at rtol 1e-10, atol 1e-12, rows every output_step.
SimulationOptions bicycle_row_options(double output_step) {
  SimulationOptions options;
  options.t_end = 10.0;
  options.output_step = output_step;
  options.formulation = {Formulation::sanh, Complement::qr};
  options.integrator.kind = IntegratorKind::dopri5;
  options.integrator.rtol = 1e-10;
  options.integrator.atol = 1e-12;
  return options;
}

// The run with its rows filled and written as CSV, as `nhdyn simulate` writes them.
void run_with_rows(const Model& model, double output_step, const fs::path& csv) {
  const SimulationOptions options = bicycle_row_options(output_step);
  const ResultColumns columns = make_result_columns(model);
  CsvWriter writer(csv, columns.all);
  std::vector<double> row(columns.all.size());
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    writer.write_row(row);
  });
  if (summary.status != Status::ok) {
    std::fprintf(stderr, "bench-check: the bicycle run failed: %s\n", summary.message.c_str());
    std::exit(1);
  }
  writer.commit();
}

// The same run with its rows kept in memory as a Trajectory (analysis/batch.hpp): every row's
// calculations (q'', R, residuals, energy balance, contact forces, outputs) without the CSV text,
// what nhdyn.simulate in Python and the C++ batches return.
void run_with_rows_in_memory(const Model& model, double output_step) {
  const SimulationOptions options = bicycle_row_options(output_step);
  Trajectory trajectory;
  trajectory.reset(model, static_cast<long>(options.t_end / output_step) + 1);
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) { trajectory.append(data); });
  if (summary.status != Status::ok || trajectory.rows() != static_cast<long>(options.t_end / output_step + 0.5) + 1) {
    std::fprintf(stderr, "bench-check: the bicycle run in memory failed: %s\n", summary.message.c_str());
    std::exit(1);
  }
}

// A run whose rows are not written: what the integration and the watch cost alone.
void run_watched(const Model& model, double t_end, double output_step, double rtol, double atol, bool watch) {
  SimulationOptions options;
  options.t_end = t_end;
  options.output_step = output_step;
  options.formulation = {Formulation::sanh, Complement::qr};
  options.integrator.kind = IntegratorKind::dopri5;
  options.integrator.rtol = rtol;
  options.integrator.atol = atol;
  options.watch_constraints = watch;
  const SimulationSummary summary = simulate(model, options, [](const Data&) {});
  if (summary.status != Status::ok) {
    std::fprintf(stderr, "bench-check: the run of %s failed: %s\n", model.name.c_str(), summary.message.c_str());
    std::exit(1);
  }
}

// The hand-written rattleback at the model's start, `calls` times; first (check) its q'' against
// nhdyn's, so that the yardstick cannot drift from the model.
void hand_written_loop(const Model& model, long calls, bool check) {
  const bench::RattlebackParameters p;
  bench::Vector6 qdd, reaction;
  for (long i = 0; i < calls; ++i)
    if (!bench::rattleback_stacked(p, model.q0.data(), model.v0.data(), qdd, reaction)) {
      std::fprintf(stderr, "bench-check: the hand-written rattleback is singular at the start\n");
      std::exit(1);
    }
  if (!check) return;
  Data data = make_data(model);
  if (compute_dynamics(model, data, {Formulation::sanh, Complement::qr}, 0.0, model.q0.data(), model.v0.data()) !=
          Status::ok ||
      !((data.qdd - qdd).norm() <= 1e-12 * (1.0 + qdd.norm()))) {
    std::fprintf(stderr, "bench-check: the hand-written rattleback's q'' differs from nhdyn's by %g\n",
                 (data.qdd - qdd).norm());
    std::exit(1);
  }
}

// The sled's run by simulate() (the user's path, 2 rows) and by hand, with the same first step.
constexpr double kSledEnd = 10.0, kSledRtol = 1e-8, kSledAtol = 1e-10, kSledFirstStep = 1e-3;
// Runs per timing: the example's 10 s is about a millisecond.
constexpr int kSledRuns = 20;

SimulationSummary run_sled(const Model& sled, IntegratorKind kind, Eigen::VectorXd* last_state = nullptr) {
  SimulationOptions options;
  options.t_end = kSledEnd;
  options.output_step = kSledEnd;
  options.formulation = {Formulation::sanh, Complement::qr};
  options.integrator.kind = kind;
  options.integrator.rtol = kSledRtol;
  options.integrator.atol = kSledAtol;
  options.integrator.step = kSledFirstStep;
  const SimulationSummary summary = simulate(sled, options, [&](const Data& data) {
    if (last_state != nullptr) {
      last_state->resize(data.q.size() + data.v.size());
      *last_state << data.q, data.v;
    }
  });
  if (summary.status != Status::ok) {
    std::fprintf(stderr, "bench-check: the sled's run failed: %s\n", summary.message.c_str());
    std::exit(1);
  }
  return summary;
}

template <class Tableau>
bench::ByHandRun run_sled_by_hand(const Model& sled) {
  bench::SledState y0{};
  for (int i = 0; i < 3; ++i) {
    y0[static_cast<std::size_t>(i)] = sled.q0[i];
    y0[static_cast<std::size_t>(i + 3)] = sled.v0[i];
  }
  return bench::integrate_sled_by_hand<Tableau>(bench::SledByHand{}, y0, kSledEnd, kSledFirstStep, kSledRtol,
                                                 kSledAtol);
}

// The yardstick must be the same run: the same steps, the same final state (to the tolerances'
// level: the two evaluate the same equations in a different order).
template <class Tableau>
void check_sled_by_hand(const Model& sled, IntegratorKind kind, const char* name) {
  Eigen::VectorXd last;
  const SimulationSummary summary = run_sled(sled, kind, &last);
  const bench::ByHandRun by_hand = run_sled_by_hand<Tableau>(sled);
  double difference = 0.0;
  for (int i = 0; i < 3; ++i)
    difference = std::max({difference, std::abs(last[i] - by_hand.y[static_cast<std::size_t>(i)]),
                           std::abs(last[i + 3] - by_hand.y[static_cast<std::size_t>(i + 3)])});
  // A step whose error estimate is within round-off of 1 may be taken on one side and rejected on
  // the other (the two sum the same terms in another order): the counts agree to 1 %.
  const auto near = [](long x, long y) { return std::abs(x - y) <= 2 + std::max(x, y) / 100; };
  if (!near(summary.stats.steps, by_hand.steps) || !near(summary.stats.rejected_steps, by_hand.rejected) ||
      !(difference <= 1e-6)) {
    std::fprintf(stderr,
                 "bench-check: %s: simulate() took %ld steps (%ld rejected), the hand-written run %ld (%ld); "
                 "final states differ by %g\n",
                 name, summary.stats.steps, summary.stats.rejected_steps, by_hand.steps, by_hand.rejected,
                 difference);
    std::exit(1);
  }
}

// FILTER "breakdown": what one output row of the bicycle costs, kernel by kernel (CPU time per
// call, microseconds), the way simulate() computes a row: for finding where the time goes. The
// kernels run at the model's start; the CSV formats the 1001 rows of the 10 s run in turn (one
// row formatted again and again reads about half as long: its digits are the same every time).
void breakdown(const Model& model, const char* label) {
  Data data = make_data(model);
  const FormulationOptions options{Formulation::sanh, Complement::qr};
  ConstraintWatch watch = make_constraint_watch(model, data, options.method, kConstraintWatchFactor);
  const ResultColumns columns = make_result_columns(model);
  std::vector<double> row(columns.all.size());
  std::vector<std::vector<double>> rows;
  {
    SimulationOptions run;
    run.t_end = 10.0;
    run.output_step = 0.01;
    run.integrator.rtol = 1e-10;
    run.integrator.atol = 1e-12;
    simulate(model, run, [&](const Data& at) {
      fill_result_row(model, at, row);
      rows.push_back(row);
    });
  }
  std::size_t next_row = 0;
  const fs::path csv = fs::temp_directory_path() / ("nhdyn-bench-check-" + std::to_string(::getpid()) + ".csv");
  CsvWriter writer(csv, columns.all, {}, false);  // formatted here: what a row's text costs
  const long calls = 2000;
  auto per_call = [&](const char* what, const std::function<void()>& job) {
    job();
    const double t = timed([&] {
      for (long i = 0; i < calls; ++i) job();
    });
    std::printf("%s %-22s %8.2f us\n", label, what, 1e6 * t / calls);
  };
  per_call("compute_dynamics", [&] { compute_dynamics(model, data, options, 0.0, model.q0.data(), model.v0.data()); });
  per_call("constraint_watch", [&] { compute_constraint_watch(model, data, watch); });
  per_call("residuals", [&] { compute_residuals(model, data); });
  per_call("energy", [&] { compute_energy(model, data); });
  per_call("power", [&] { compute_power(model, data); });
  per_call("contact_forces", [&] { compute_contact_forces(model, data); });
  per_call("outputs", [&] { compute_outputs(model, data); });
  per_call("fill_result_row", [&] { fill_result_row(model, data, row); });
  per_call("csv write_row", [&] { writer.write_row(rows[next_row++ % rows.size()]); });
  fs::remove(csv);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: nhdyn_bench_check EXAMPLES_DIR [PAIRS]\n");
    return 2;
  }
  const fs::path examples = argv[1];
  const int pairs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 7;
  if (argc > 3) filter = argv[3];
  try {
    Model interpreted = load_model((examples / "whipple_bicycle.toml").string());
    const auto phi = std::find(interpreted.coordinates.begin(), interpreted.coordinates.end(), "phi") -
                     interpreted.coordinates.begin();
    interpreted.v0[phi] = 0.5;
    const Model compiled = jit::make_compiled(interpreted);

    if (filter == "breakdown") {
      breakdown(interpreted, "interpreted");
      breakdown(compiled, "compiled");
      return 0;
    }
    Data di = make_data(interpreted), dc = make_data(compiled);
    pair("bicycle_rhs_compiled_vs_interpreted", pairs, [&] { rhs_loop(compiled, dc, 20000); },
         [&] { rhs_loop(interpreted, di, 20000); });

    const fs::path dir = fs::temp_directory_path() / ("nhdyn-bench-check-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const fs::path csv = dir / "rows.csv";
    pair("bicycle_rows_1001_vs_2", pairs, [&] { run_with_rows(interpreted, 0.01, csv); },
         [&] { run_with_rows(interpreted, 10.0, csv); });
    pair("bicycle_rows_1001_vs_2_compiled", pairs, [&] { run_with_rows(compiled, 0.01, csv); },
         [&] { run_with_rows(compiled, 10.0, csv); });
    fs::remove_all(dir);
    pair("bicycle_rows_1001_vs_2_in_memory", pairs, [&] { run_with_rows_in_memory(interpreted, 0.01); },
         [&] { run_with_rows_in_memory(interpreted, 10.0); });
    pair("bicycle_rows_1001_vs_2_in_memory_compiled", pairs, [&] { run_with_rows_in_memory(compiled, 0.01); },
         [&] { run_with_rows_in_memory(compiled, 10.0); });

    const Model sled = load_model((examples / "sled.toml").string());
    pair("sled_watch_on_vs_off", pairs, [&] { run_watched(sled, 200.0, 0.1, 1e-8, 1e-10, true); },
         [&] { run_watched(sled, 200.0, 0.1, 1e-8, 1e-10, false); });
    pair("bicycle_watch_on_vs_off_compiled", pairs, [&] { run_watched(compiled, 10.0, 0.01, 1e-10, 1e-12, true); },
         [&] { run_watched(compiled, 10.0, 0.01, 1e-10, 1e-12, false); });

    const Model rattleback = load_model((examples / "rattleback.toml").string());
    const Model rattleback_compiled = jit::make_compiled(rattleback);
    hand_written_loop(rattleback, 1, true);
    Data dr = make_data(rattleback), drc = make_data(rattleback_compiled);
    pair("rattleback_rhs_compiled_vs_hand_written", pairs, [&] { rhs_loop(rattleback_compiled, drc, 50000); },
         [&] { hand_written_loop(rattleback, 50000, false); });
    pair("rattleback_rhs_interpreted_vs_hand_written", pairs, [&] { rhs_loop(rattleback, dr, 50000); },
         [&] { hand_written_loop(rattleback, 50000, false); });

    const auto sled_pair = [&](const char* name, const Model& model, IntegratorKind kind, auto tableau) {
      using Tableau = decltype(tableau);
      if (std::string(name).find(filter) == std::string::npos) return;
      check_sled_by_hand<Tableau>(model, kind, name);
      pair(
          name, pairs,
          [&] {
            for (int i = 0; i < kSledRuns; ++i) run_sled(model, kind);
          },
          [&] {
            for (int i = 0; i < kSledRuns; ++i) run_sled_by_hand<Tableau>(sled);
          });
    };
    sled_pair("sled_dopri5_vs_hand_written", sled, IntegratorKind::dopri5, rk::DormandPrince54{});
    sled_pair("sled_dop853_vs_hand_written", sled, IntegratorKind::dop853, rk::DormandPrince853{});
    if (std::string("sled_dopri5_compiled_vs_hand_written").find(filter) != std::string::npos)
      sled_pair("sled_dopri5_compiled_vs_hand_written", jit::make_compiled(sled), IntegratorKind::dopri5,
                rk::DormandPrince54{});
    if (std::string("sled_dop853_compiled_vs_hand_written").find(filter) != std::string::npos)
      sled_pair("sled_dop853_compiled_vs_hand_written", jit::make_compiled(sled), IntegratorKind::dop853,
                rk::DormandPrince853{});

    // The sparse path: one right-hand side of the 300-body chain (n = 900, sparse sanh, KLU's LU of
    // b_dep refactorized in place) against a fixed amount of hand-written work, as the loads are.
    if (std::string("chain_rhs_sparse_vs_reference").find(filter) != std::string::npos) {
      symbolic::ChainParameters chain_parameters;
      chain_parameters.bodies = 300;
      const Model chain = load_model_text(symbolic::write_chain_toml(chain_parameters), "chain.toml");
      Data dchain = make_data(chain);
      if (!dchain.sparse) {
        std::fprintf(stderr, "bench-check: the chain did not take the sparse path\n");
        return 1;
      }
      pair("chain_rhs_sparse_vs_reference", pairs, [&] { rhs_loop(chain, dchain, 100); },
           [&] {
             for (int i = 0; i < kSledRuns; ++i) run_sled_by_hand<rk::DormandPrince54>(sled);
           });
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench-check: %s\n", e.what());
    return 1;
  }
  return 0;
}
