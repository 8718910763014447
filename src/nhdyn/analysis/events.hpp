// A model's events as the integrators see them (integrators/events.hpp): the tapes g(t, q, q')
// (or of q'', R and the contact forces, solved at each evaluation) of model/event.hpp bound to the model's parameter values, evaluated on y = [q; q'], and the
// check that refuses a run whose events cannot mean anything at its start (an event already at
// zero, a stop condition already true). simulate() (simulation.hpp) uses them; the located
// crossings come back in SimulationSummary::events.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "nhdyn/integrators/events.hpp"
#include "nhdyn/model/event.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// One located crossing: which event, when, and the state there (as written to the results).
struct EventRecord {
  int index = 0;             // in the run's list of events (SimulationOptions::events)
  std::string name;
  double t = 0.0;
  std::vector<double> q, v;  // n values each
};

class ModelEventFunctions final : public EventFunctions {
 public:
  // What happens at a crossing of event i: the caller writes the row and returns Status::ok (or
  // the status of a failure); ModelEventFunctions adds Status::stopped for a stop event.
  using Handler = std::function<Status(int i, double t, const double* y)>;
  // Solves the dynamics at (t, y = [q; q']) and points qdd and R at its q'' and R (n each), for
  // the events that read them (Event::dynamics: through an output, model/output.hpp); when F is
  // not null, also computes the contact forces there and points F at their values (6 per wheel
  // and knife edge, ContactForceData::values), for the events that read them
  // (Event::contact_forces). simulate() passes compute_dynamics (and compute_contact_forces) with
  // the run's formulation: such an event costs one more solve per evaluation of the events (once
  // for all of them), at each step and in the root finding.
  using Dynamics =
      std::function<Status(double t, const double* y, const double** qdd, const double** R, const double** F)>;

  // Binds every event's tape to the model's current parameter values (allocates; not in the
  // time loop). `events` must outlive this object. Throws InputError when an event reads q'' or R
  // and no `dynamics` is given, or reads contact forces that `model` does not have.
  ModelEventFunctions(const Model& model, const std::vector<const Event*>& events, Handler handler,
                      Dynamics dynamics = {});

  int count() const override { return static_cast<int>(events_.size()); }
  CrossingDirection direction(int i) const override;
  // Non-finite g: Status::non_finite, and non_finite() records which event, where. Allocates
  // nothing (the record's state has its size from the constructor).
  Status evaluate(double t, const double* y, double* g) override;
  Status on_event(int i, double t, const double* y) override;

  const Event& event(int i) const { return *events_[static_cast<std::size_t>(i)]; }
  // The index of the stop event that ended the run, or -1.
  int stopped_by() const { return stopped_by_; }
  // The first event whose value was not finite at the latest evaluate (index -1 when all were),
  // with t, the value and the state y = [q; q'] (2n) there: for the message of a run it ends.
  struct NonFinite {
    int index = -1;
    double t = 0.0;
    double g = 0.0;
    std::vector<double> y;
  };
  const NonFinite& non_finite() const { return non_finite_; }

  // Throws InputError when an event is exactly zero (or not finite) at (t0, q0, q'0), or a stop
  // condition (Event::condition) already holds there, naming the event, where it was written and
  // its value.
  void require_valid_start(double t0, const double* y0);

 private:
  int n_;
  std::vector<const Event*> events_;
  std::vector<Tape> tapes_;   // bound to the parameter values
  std::vector<double> registers_;
  std::vector<double> g_;
  NonFinite non_finite_;
  Handler handler_;
  Dynamics dynamics_;
  bool needs_dynamics_ = false;
  bool needs_contact_forces_ = false;
  int contact_columns_ = 0;     // 6 per wheel and knife edge of the model
  // 2n (+ contact_columns_) each: the inputs [q; q''; F], [q'; R; 0] of the dynamics layout (and
  // of the contact layout, whose tapes read the forces after them).
  std::vector<double> x_, xd_;
  // Runs every tape at (t, y) into g; solves the dynamics first when an event needs it.
  Status run_all(double t, const double* y, double* g);
  int stopped_by_ = -1;
};

}  // namespace nhdyn
