// Events: the times at which functions g_i(t, y) of the state cross zero, found while a run goes
// on. The integrators with a continuous extension (dopri5, dop853) look for a change of sign of
// each g_i between the ends of every accepted step and then locate the root on the step's own
// interpolating polynomial to round-off (Brent's method in the step's fraction theta); CVODE uses
// its own root finding (CVodeRootInit). Several crossings in one step are reported in time order.
// A g that may cross zero and come back within one step (a gap: EventFunctions::may_dip) is also
// searched for a minimum inside each step, by every integrator.
// rk4 has no continuous extension: integrate() refuses events with it.
// Like the rest of integrators/, this knows nothing of mechanics: the simulation driver
// (analysis/simulation.hpp) turns the model's event expressions into an EventFunctions.
#pragma once

#include <functional>
#include <vector>

#include "nhdyn/core/status.hpp"

namespace nhdyn {

// Which crossings of zero count: g going from negative to positive (rising), from positive to
// negative (falling) or either. The values are CVODE's root directions.
enum class CrossingDirection : int { falling = -1, both = 0, rising = 1 };

class EventFunctions {
 public:
  virtual ~EventFunctions() = default;
  // Number of event functions m.
  virtual int count() const = 0;
  virtual CrossingDirection direction(int i) const = 0;
  // g[0..m) = every event function at (t, y). A non-ok status ends the run as a failed
  // right-hand side does.
  virtual Status evaluate(double t, const double* y, double* g) = 0;
  // Called for every located crossing of event i that its direction admits, in time order
  // (crossings at the same time in index order), with the state y(t) there. Return
  // Status::stopped to end the run at t, Status::ok to go on; any other status fails the run.
  virtual Status on_event(int i, double t, const double* y) = 0;
  // Whether g_i may cross zero and come back inside one step, on the same side at both ends (a
  // gap that closes and opens again within a step too long for it: a body in flight passing
  // through another in one step). The integrators then also look for such a dip in every step
  // (EventTracker::locate). Default: no.
  virtual bool may_dip(int /*i*/) const { return false; }
};

// The sign bookkeeping and root location shared by the explicit integrators: the sign of each g_i
// at the start of the current step (the last nonzero one, so that a g that lands exactly on zero
// at a step end and leaves on the other side counts once), the crossings of a step, and Brent's
// method on an interpolant. Allocates when made, not per step.
class EventTracker {
 public:
  struct Crossing {
    int index = 0;
    double t = 0.0;
    double theta = 0.0;  // (t - step start) / h as found: evaluate the interpolant here, not at t
  };

  // n: the size of the state; rtol, atol: the integrator's tolerances, from which a dip of a g
  // that may dip is told from the interpolant's error.
  EventTracker(EventFunctions& events, int n, double rtol = 0.0, double atol = 0.0);

  // g at the start of the run (or after the state was changed by OdeSystem::after_step).
  Status restart(double t, const double* y);
  // Evaluates g at the step end (t1, y1) and says whether locate() is due: some g_i changed sign
  // since the step's start in a direction its event admits, or one that may dip (may_dip) kept
  // the side from which its event admits a crossing. Does not update the signs: call advance()
  // once the step is done.
  Status check(double t1, const double* y1, bool& crossed);
  // The same for the g_i that may dip only, for an integrator that finds sign changes by itself
  // (CVODE): then locate() looks for dips alone, also before a sign change at (t1, y1).
  Status check_dips(double t1, const double* y1, bool& dipped);
  // Whether some g_i may dip (EventFunctions::may_dip): else check_dips is never due.
  bool any_may_dip() const;
  // y(theta) on a step (t, y) -> (t + h, y1), theta in [0, 1]: writes n values.
  using Interpolant = std::function<void(double theta, double* y)>;
  // For each crossing found by check(), the time of the root of g_i(t + theta h, y(theta)) for
  // theta in [0, 1]; sorted by time, then index. Brent's method to the resolution of double
  // precision in theta (a few dozen evaluations of the interpolant and g per crossing). A sign
  // change by a jump of g (|g| at the located point above 1e-3 of its size at the ends: a pole,
  // a wrap-around) is not a crossing: it is counted in jumps() and left out.
  // A g_i that may dip and kept its side: sampled across the step on the interpolant (16 samples,
  // more where it turns often), each local minimum of the samples followed by golden sections, and
  // where g_i first passes zero on the way down to a dip is a crossing like any other (and on the
  // way back, for an event of both directions). A dip shallower than the tolerances on g's size
  // (atol + rtol |g|), or than 1e-7 of its change over the step, is not told from the interpolant's error
  // and is left out. A g that may dip and changed sign over the step is searched the same way, so
  // that a dip before the change gives the first crossing (for an event of both directions, the
  // dip's two crossings; a third, the change at the end, is then not reported).
  Status locate(double t, double h, const Interpolant& interpolate, std::vector<Crossing>& out);
  // The step is taken: the signs at its end become those of the next step's start.
  void advance();

  EventFunctions& events() { return events_; }
  // Sign changes that locate() found to be jumps of g (a pole such as 1/x, the wrap-around of
  // atan2), not zeros, and did not report; and the time of the first.
  int jumps() const { return jumps_; }
  double first_jump_t() const { return first_jump_t_; }

 private:
  // g_i at time t + theta h on the interpolant.
  Status value(int i, double t, double h, double theta, const Interpolant& interpolate, double& g);
  // dips_: the g_i that may dip and start on the side they may cross from, by g_end_: those that
  // kept it, and with_changes those that left it too.
  void collect_dips(bool with_changes);
  // For a g_i in dips_: the fraction theta of the step where it first reaches zero inside a dip,
  // or -1 when the step holds none; and theta_back where it comes back, for an event that admits
  // both directions (else -1).
  Status find_dip(int i, double t, double h, const Interpolant& interpolate, double& theta, double& theta_back);

  EventFunctions& events_;
  double rtol_, atol_;
  int m_;
  std::vector<int> sign_;        // sign of g_i at the step's start (last nonzero); 0 if never nonzero
  std::vector<double> g_end_;    // g at the step's end, from check()
  std::vector<double> g_;        // scratch for evaluate()
  std::vector<double> y_;        // scratch state on the interpolant
  std::vector<double> g_start_;  // g at the step's start
  std::vector<int> crossed_;     // indices that crossed in the step
  std::vector<int> dips_;        // indices that may dip and kept the side they may cross from
  std::vector<double> samples_;  // scratch for find_dip
  int jumps_ = 0;
  double first_jump_t_ = 0.0;
};

// Whether a sign change of g located at a point where g = g_root is a jump of g (a pole such as
// 1/x, the wrap-around of atan2), not a zero: |g_root| above 1e-3 of max(|g_start|, |g_end|), its
// size at the ends of the step that holds the change, or g_root not finite. At a true root |g| is
// round-off, orders of magnitude below. The one test of EventTracker::locate and of CVODE's root
// returns (sundials/cvode.cpp), so that every integrator reports the same crossings.
bool is_jump(double g_root, double g_start, double g_end);

// Brent's method (Brent 1973, "zeroin") for a root of f in [a, b] given fa = f(a), fb = f(b) of
// opposite signs (or one of them zero), to the resolution of double precision: the final bracket
// is at most a few ulps wide, and `root` is its end on b's side (where f has the sign of fb), so
// that the state reported at a crossing is already past it; or an exact zero of f. f writes its
// value and returns a status; a non-ok one ends the search and is returned.
Status find_root(const std::function<Status(double x, double& fx)>& f, double a, double fa, double b,
                 double fb, double& root);

}  // namespace nhdyn
