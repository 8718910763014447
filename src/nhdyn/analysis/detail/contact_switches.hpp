// The switches of contacts that slide and lift off (docs/contact-modes.md; derived in
// docs/derivations/contact-modes.md section 6): the mode each contact starts in, the event
// functions each mode watches (its normal force, its friction cone, its slip along the carried
// direction, its gap), located to round-off like any event, and what happens at a crossing: the
// new mode (a stick, a slip, a lift-off, a touchdown with its impact), the row written there, and a
// restart of the integration from that state (with the velocities after an impact). simulate()
// (simulation.hpp) runs through them with integrate_contact_modes.
//
//     simulate -> choose_initial_contact_modes -> integrate_contact_modes
//         -> integrate (one segment per mode set) -> ContactSwitches::on_event -> new modes
// Internal: used by analysis/simulation.cpp, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <array>
#include <cmath>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/integrators/events.hpp"
#include "nhdyn/integrators/ode.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Chooses each contact's mode at (t0, q0, v0) into data.modes: the one its `mode` key gives, else
// free when its gap is open (unilateral), sliding when it slips (or when rolling would need more
// friction than mu_s N: the onset direction of section 5), rolling otherwise. Throws ModelError
// naming the contact when a unilateral contact would pull (N < 0) in its starting mode, with the
// mode to start in instead, or when mode = "sliding" is given with no slip and no friction needed.
void choose_initial_contact_modes(const Model& model, Data& data, const FormulationOptions& formulation, double t0,
                                  const Vector& q0, const Vector& v0);

// The mode events of every contact (3 per contact) after the run's own events (`user`, may be
// null): located on the integrator's dense output; a crossing changes data.modes and ends the
// current segment (Status::stopped), which integrate_contact_modes restarts from the state there.
// The impulse of one touchdown (docs/derivations/contact-modes.md section 7): the velocities
// after it, its normal part Pi_n and its tangential part Pi_t (unit tangent basis) at the contact.
struct Impulse {
  bool ok = false;
  Vector v;
  double normal = 0.0;
  std::array<double, 2> tangential{0.0, 0.0};
  // Another unilateral contact held through the impact whose normal impulse would pull, or -1.
  int pulling = -1;
  std::string failure;  // why not, when !ok
};

class ContactSwitches final : public EventFunctions {
 public:
  // Writes the row of a switch (the mode after it) and records it as an event named NAME_stick,
  // NAME_slip, NAME_liftoff or NAME_touchdown; returns its status.
  using Handler = std::function<Status(const std::string& name, double t, const double* y)>;

  // `state_size`: the size of the integrated state y (q, q' and the works); `run_length`: t_end - t0,
  // the time scale against which switches accumulate (count_switch).
  ContactSwitches(const Model& model, Data& data, const FormulationOptions& formulation, int state_size,
                  EventFunctions* user, Handler handler, double run_length);

  int count() const override;
  CrossingDirection direction(int i) const override;
  Status evaluate(double t, const double* y, double* g) override;
  Status on_event(int i, double t, const double* y) override;
  // A free contact's gap: a body in flight can pass through the ground's edge or a sphere within
  // one long step, the gap positive at both ends.
  bool may_dip(int i) const override;

  // After integrate() returned Status::stopped: whether a switch ended the segment, and where.
  bool switched() const { return switched_; }
  double switch_t() const { return switch_t_; }
  const std::vector<double>& switch_y() const { return switch_y_; }
  void clear() { switched_ = false; }
  // The run's start t0 is the first segment's: its free contacts' gaps start as a switch's do.
  void start(double t0) { start_t_ = t0; }
  // Set when the switches accumulate (Zeno or no consistent mode): the message ending the run.
  const std::string& accumulation() const { return accumulation_; }
  long switches() const { return switch_count_; }
  // Warnings for the run's summary (an impact that gains energy: once per run).
  const std::vector<std::string>& warnings() const { return warnings_; }

  // The row of an output time is held until the next call of the output (or an event, or the
  // end): a switch located within round-off after it, 64 eps max(1, |t|), replaces it, so that the
  // row at that time shows the mode and impact_loss after the switch (one row per time, as
  // simulate() writes them). integrate_contact_modes holds and flushes them through `output`.
  void hold_row(double t, const double* y);
  Status flush_row();
  // The same after a failed step: Data keeps the failure's record (its t, state and reason, which
  // the run's message reads), not the evaluation of the row written.
  Status flush_row_after_failure();
  void set_output(const OutputFn* output) { output_ = output; }

 private:
  // Counts a switch at t; true when the last kMaxSwitches of them accumulate (docs/contact-modes.md).
  bool count_switch(double t);
  // The time from the oldest of the last kMaxSwitches switches (or of all, when fewer) to t.
  double window_span(double t) const;

  std::string switch_contact(int contact, int slot, double t, const double* y);
  // The impact of a touchdown (section 7): the velocities of switch_y_ after it, and the mode.
  std::string touchdown(int contact, double t);
  // Its impulse (touchdown's first half); false with the message in accumulation_.
  bool impact_impulse(int contact, double t, const double* v, const std::array<double, 2>& slip_before,
                      Impulse& impulse);
  // Whether a free contact's gap crossing 0 at (t, y) is no impact: it meets the ground with no
  // approach speed (the gap's rate within the integration error) while accelerating away from it.
  // Just after a lift-off the gap sits at the integration error, and an integrator whose first
  // steps are shorter than the time it needs to rise above that (CVODE) sees it cross 0 there.
  bool grazes(int contact, double t, const double* y);
  // After `contact`'s impact at (t, q, v): every other sliding contact slides along its slip after
  // the impulse (which may have turned or reversed it), or sticks where the impulse stopped it
  // (sliding on in its onset direction if sticking needs more than mu_s N). False (with the message
  // in accumulation_) when that fails.
  bool settle_others(int contact, double t, const double* q, const double* v);
  // Whether contact i has friction = 0 (mu_s = mu_k = 0, the values of the last solve): it slides
  // with no friction force, so no direction of sliding matters.
  bool frictionless(std::size_t i) const {
    return model_.contact_modes->contacts[i].friction && data_.modes.mu_s[i] == 0.0 && data_.modes.mu_k[i] == 0.0;
  }
  // A free contact that touches its ground at (t, switch_y_) moving into it, or -1: two gaps that
  // close at one instant, or one that this switch's impulse closed. The event that finds a
  // touchdown needs the gap positive where the segment starts; such a contact's gap is not.
  int closing_contact(double t);
  // (I1)-(I2) for `contact` with the velocities v before, after compute_dynamics there: sticking
  // (its no-slip rows target 0), or sliding along `direction` (unit tangent basis) with mu_k.
  Impulse solve_impulse(int contact, double t, const double* v, bool sliding,
                        const std::array<double, 2>& direction);
  // Where a sliding mode starts, after compute_dynamics in it: false (with the message in
  // accumulation_) when the contact is in Painleve's paradox (w_eff <= 0, section 3.8).
  bool check_sliding(int contact, double t);
  // Starts `contact` sliding at (t, q, v) in its onset direction (section 5, (O3)), then
  // check_sliding: false (with the message in accumulation_) when no single direction is
  // consistent or the sliding is in Painleve's paradox.
  bool start_sliding(int contact, double t, const double* q, const double* v);

  const Model& model_;
  Data& data_;
  const FormulationOptions& formulation_;
  EventFunctions* user_;
  Handler handler_;
  int user_count_ = 0;
  int size_ = 0;  // the state's size (y holds q, q' and the works)
  bool switched_ = false;
  double switch_t_ = 0.0;
  std::vector<double> switch_y_;
  std::string accumulation_;
  long switch_count_ = 0;
  // The times of the last kMaxSwitches switches, a ring: where they all fall within a small part of
  // the run, switches accumulate; spread over it, they are regular.
  std::vector<double> switch_times_;
  double run_length_ = 0.0;
  int same_time_ = 0;       // successive switches without progress in t
  double last_switch_t_ = 0.0;
  double start_t_ = -HUGE_VAL;  // the time the current segment started at (the last switch)
  int grazed_ = -1;  // the contact whose graze (grazes) restarted the current segment, or -1
  double last_graze_t_ = -HUGE_VAL;
  int same_graze_ = 0;  // grazes at last_graze_t_ before the last
  std::vector<std::string> settled_;  // NAME_stick of the contacts another's impact stopped (settle_others)
  std::vector<double> user_before_, user_after_;  // the run's own events across a switch
  std::vector<double> last_touchdown_;  // per contact: the times of its last two touchdowns
  std::vector<double> previous_touchdown_;
  std::vector<long> touchdowns_;
  bool gained_energy_ = false;
  std::vector<std::string> warnings_;
  const OutputFn* output_ = nullptr;
  bool held_ = false;  // a row of an output time not yet written
  double held_t_ = 0.0;
  std::vector<double> held_y_;
  std::vector<std::array<double, 2>> held_direction_;  // the carried slip directions then
};

// Integrates as integrate() does, through any number of switches: each switch ends a segment,
// whose state (after the row of the switch) starts the next one with the outputs still due. An
// accumulation of switches ends the run with Status::integrator_failure and the message of
// ContactSwitches::accumulation(), with the rows up to there written.
IntegrationResult integrate_contact_modes(OdeSystem& ode, const IntegratorOptions& options, double t0,
                                          const double* y0, std::span<const double> output_times,
                                          const OutputFn& output, ContactSwitches& switches);

}  // namespace nhdyn
