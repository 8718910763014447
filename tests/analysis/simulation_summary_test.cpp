// The summary's groups in words (analysis/simulation_summary.hpp): what `nhdyn simulate` prints,
// line for line, for a model with and without each kind of constraint, and the cases a short run
// of the examples does not reach (more than ten crossings, a plural of warnings, the sparse path).
#include "nhdyn/analysis/simulation_summary.hpp"

#include <gtest/gtest.h>

#include <string>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/model/sled.hpp"

namespace nhdyn {
namespace {

TEST(SimulationSummaryText, ResidualsSayDashForALevelWithoutConstraints) {
  const Model sled = make_sled_model();  // one velocity constraint, no position constraint, no program
  EXPECT_EQ(format_residuals(sled, {1e-3, 2.5e-10, 4e-16}),
            "  max residual: position -, velocity 2.5e-10, acceleration 4e-16\n");
  EXPECT_EQ(format_program(sled, {1.0, 1.0, 1.0}, {true, 10.0, 10.0}), "");
}

TEST(SimulationSummaryText, EventsListTenCrossingsAndCountTheRest) {
  EventSummary events;
  EXPECT_EQ(format_events(events, "r-events.csv"), "");  // a run without events says nothing
  events.names = {"bottom"};
  for (int i = 0; i < 12; ++i) events.crossings.push_back({0, "bottom", 0.5 * i, {}, {}});
  const std::string text = format_events(events, "r-events.csv");
  EXPECT_EQ(text.substr(0, text.find('\n') + 1), "  events: 12 located -> r-events.csv\n");
  EXPECT_NE(text.find("    bottom at t = 4.5\n    ... and 2 more\n"), std::string::npos);
  EXPECT_EQ(text.find("at t = 5\n"), std::string::npos);  // the eleventh is not listed
  EXPECT_EQ(format_events(events, "").substr(0, 22), "  events: 12 located\n ");
}

TEST(SimulationSummaryText, ConstraintWatchCountsWarningsAndLeavesTheConditioningToTheDensePath) {
  const Model sled = make_sled_model();
  ConstraintWatchSummary watch;
  watch.largest_condition_factor = 2.5;
  EXPECT_EQ(format_constraint_watch(sled, watch, 0, false),
            "  constraint watch: no warning; largest change of a row of b x1, of the conditioning x2.5\n");
  EXPECT_EQ(format_constraint_watch(sled, watch, 1, true),
            "  constraint watch: 1 warning on stderr; largest change of a row of b x1\n");
  EXPECT_EQ(format_constraint_watch(sled, watch, 2, true),
            "  constraint watch: 2 warnings on stderr; largest change of a row of b x1\n");
}

TEST(SimulationSummaryText, EnergyIsDriftOrBalanceOrNothing) {
  const Model sled = make_sled_model();
  EnergySummary energy;
  EXPECT_EQ(format_energy(sled, energy), "");
  energy.has_energy = true;
  energy.initial = 0.5;
  energy.drift = 1e-12;
  EXPECT_EQ(format_energy(sled, energy), "  energy drift: 1e-12 (E0 = 0.5)\n");
  energy.has_balance = true;
  energy.balance_error = 3e-11;
  energy.work_forces = 1.0;
  energy.work_reactions = 0.25;
  energy.change = 1.25;
  energy.function_differs = true;
  energy.function_initial = 0.75;
  energy.function_change = 1.5;
  EXPECT_EQ(format_energy(sled, energy),
            "  energy balance error: 3e-11 (max |h - h0 - W|)\n"
            "  work W: 1.25 (forces 1, reactions 0.25, explicit time 0)\n"
            "  energy change: E - E0 = 1.25 (E0 = 0.5)\n"
            "  energy function change: h - h0 = 1.5 (h0 = 0.75)\n");
}

TEST(SimulationSummaryText, StabilizationAndTheInitialFix) {
  const Model sled = make_sled_model();
  SimulationOptions options;
  ProjectionSummary projection{3, 7, 1e-9, 2e-8};
  EXPECT_EQ(format_stabilization(options, projection), "");
  options.stabilization = Stabilization::projection;
  EXPECT_EQ(format_stabilization(options, projection),
            "  stabilization: projection, 3 projections (7 Newton iterations), largest correction 1e-09 in a "
            "coordinate, 2e-08 in a velocity\n");
  InitialFix fix;
  fix.q = Vector::Zero(3);
  fix.dq = Vector::Zero(3);
  fix.v = Vector::Zero(3);
  fix.dv = Vector::Zero(3);
  fix.v(1) = 0.5;
  fix.dv(1) = 0.25;
  EXPECT_EQ(format_initial_fix(sled, fix), "  initial state moved onto the constraints (--fix-initial):\n"
                                           "    y' = 0.5 (changed by +0.25), was 0.25\n");
  EXPECT_EQ(format_contact_force_notes(sled), "");
}

TEST(SimulationSummaryText, OutcomeInATableRow) {
  SimulationSummary summary;
  EXPECT_EQ(format_status(summary), "ok");
  EXPECT_EQ(format_failure_note(summary), "");
  summary.status = Status::non_finite;
  summary.t_reached = 1.23456;
  summary.message = "non-finite value in A";
  EXPECT_EQ(format_status(summary), describe(Status::non_finite));
  EXPECT_EQ(format_failure_note(summary), "  FAILED at t = 1.235: non-finite value in A");
}

}  // namespace
}  // namespace nhdyn
