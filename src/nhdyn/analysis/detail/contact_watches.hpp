// The contact watches of a run (model.hpp, ContactWatch): the measures that say where a contact's
// closed-form point stops being defined (a disk lying flat, a surface whose tangents vanish), the
// message of a run that reaches one, and WatchedEvents, which checks them at every step's end and
// locates their crossings as events where the integrator can.
// Internal: used by analysis/simulation.cpp, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <string>
#include <vector>

#include "nhdyn/integrators/events.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"
#include "nhdyn/model/tape.hpp"

namespace nhdyn {

// Watch `w`'s measure at (t, q, v), bound to the model's parameter values. Cold path: allocates.
double calc_watch_measure(const Model& model, const ContactWatch& w, double t, const double* q, const double* v);

// The message of a run that reached watch `w` (its measure `value` at (t, q, v)), ending with
// `ending`.
std::string watch_message(const Model& model, const ContactWatch& w, double value, double t, const double* q,
                          const double* v, const char* ending = "the run stops there");

// The contact whose closed-form point is singular at (t, q, v) (a disk lying flat), as the
// message of the run that failed there; "" when none is. A measure that is not a number counts
// as singular.
std::string singular_contact_message(const Model& model, const Data& data, double t, const double* q,
                                     const double* v, const char* ending = "the run stops there");

// The contact watches checked along the run (ContactWatch::every_step), bound to the parameter
// values: at every accepted step's end (after_step: every integrator), and, for an integrator that
// locates events, as events falling through their thresholds, so that the run stops where a
// measure reaches its limit and not at the end of the step past it. Forwards the run's own events
// (`user`, may be null) as its first ones.
class WatchedEvents final : public EventFunctions {
 public:
  WatchedEvents(const Model& model, Data& data);

  bool empty() const { return watches_.empty(); }
  void set_user(EventFunctions* user) {
    user_ = user;
    user_count_ = user ? user->count() : 0;
  }
  int count() const override { return user_count_ + static_cast<int>(watches_.size()); }
  CrossingDirection direction(int i) const override {
    return i < user_count_ ? user_->direction(i) : CrossingDirection::falling;
  }
  bool may_dip(int i) const override { return i < user_count_ && user_->may_dip(i); }
  // A watch out of its mode is +1 (no crossing); a measure that is not a number counts as below
  // its threshold (-1): the step's end finds it (check), as it finds a jump.
  Status evaluate(double t, const double* y, double* g) override;
  Status on_event(int i, double t, const double* y) override;
  // At a step's end: the first watch below its threshold ends the run there.
  Status check(double t, const double* y);
  // The watch (index in Model::contact_watches) that ended the run, or -1; where, and the state
  // y = [q; q'] there.
  int fired() const { return fired_; }
  double fired_t() const { return fired_t_; }
  const double* fired_y() const { return fired_y_.data(); }

 private:
  struct Watch {
    Tape measure;
    double threshold;
    int mode_contact;  // the contact's index among those with modes, or -1
    bool touching_only, free_only;
    int index;         // in Model::contact_watches
  };
  Status stop(int index, double t, const double* y);
  Data& data_;
  EventFunctions* user_ = nullptr;
  int user_count_ = 0;
  int n_;
  std::vector<Watch> watches_;
  std::vector<double> registers_;
  int fired_ = -1;
  double fired_t_ = 0.0;
  std::vector<double> fired_y_;
};

}  // namespace nhdyn
