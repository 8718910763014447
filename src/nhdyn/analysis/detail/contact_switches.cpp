#include "nhdyn/analysis/detail/contact_switches.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/LU>
#include <Eigen/QR>

#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/contact_modes.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
#include "nhdyn/formulation/detail/row_scaling.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

constexpr int kSlots = 3;               // event functions per contact
constexpr long kMaxSwitches = 10000;    // switches judged together by ContactSwitches::count_switch
// The last kMaxSwitches switches accumulate when they took less than this part of the run's length
// (t_end - t0): a ball bouncing elastically every 0.4 s for hours is regular, chattering or a Zeno
// sequence puts its 10000 switches into a vanishing stretch of the run.
constexpr double kAccumulatedFraction = 1e-3;
constexpr int kMaxSameTime = 8;         // successive switches without progress in t

// The slip below which a contact is taken not to slip (the integration error of its velocity
// constraint, not a motion): as in formulation/contact_modes.cpp.
// Of the velocities v; slip_floor(data) of those Data holds.
double slip_floor(const Eigen::Ref<const Vector>& v) { return 1e-10 * (1.0 + v.lpNorm<Eigen::Infinity>()); }
double slip_floor(const Data& data) { return slip_floor(data.v); }

double norm2(const std::array<double, 2>& x) { return std::hypot(x[0], x[1]); }

// The direction of the friction at the onset of slip (docs/derivations/contact-modes.md section
// 5): the unit e (unit tangent basis) along which the slip acceleration sigma(e) of the sliding
// mode, with the friction -mu_k N e, points: e x sigma(e) = 0, e . sigma(e) > 0 (O3). That is (O1)
// for a contact whose N does not depend on the friction, and the direction opposite to the
// friction rolling needs, F_roll, for an isotropic one (O2, a ball). Each trial e is one solve of
// the sliding mode, whose slip is zero here (the carried direction serves it): sigma is its rows
// of b times q'' plus b0. The circle is scanned at kScan points placed so that (O2) lies midway
// between two, and every change of sign of e x sigma with e . sigma > 0 is bisected. Leaves
// contact i's mode and carried direction as found; `why` says what failed (no direction, or more
// than one: a non-uniqueness like Painleve's).
constexpr int kScan = 48;

struct Onset {
  bool ok = false;
  std::array<double, 2> e{1.0, 0.0};
  std::string why;
  std::optional<std::array<double, 2>> nearest;  // when several: the one nearest (O2)
};

Onset onset_direction(const Model& model, Data& data, const FormulationOptions& formulation, std::size_t i, double t,
                      const double* q, const double* v) {
  ContactModeData& w = data.modes;
  const ContactModeContact& c = model.contact_modes->contacts[i];
  const ContactMode mode = w.mode[i];
  const std::array<double, 2> carried = w.direction[i];
  Onset out;
  w.mode[i] = ContactMode::rolling;
  if (compute_dynamics(model, data, formulation, t, q, v) != Status::ok) {
    w.mode[i] = mode;
    out.why = "the rolling mode has no solution there";
    return out;
  }
  const std::array<double, 2> rolling = w.friction[i];
  const double size = norm2(rolling);
  // A bilateral contact whose ground pulls slides with the friction of |N| (3.6).
  w.normal_sign[i] = !c.unilateral && w.normal_force[i] < 0.0 ? -1.0 : 1.0;
  if (!(size > 0.0)) {
    w.mode[i] = mode;
    return {true, carried, "", std::nullopt};
  }
  const double beta0 = std::atan2(-rolling[1], -rolling[0]);
  // e x sigma and e . sigma over |sigma|, and |sigma|, at angle beta; NaN where the sliding mode
  // has no solution.
  struct Trial {
    double cross = std::numeric_limits<double>::quiet_NaN(), dot = 0.0, size = 0.0;
  };
  w.mode[i] = ContactMode::sliding;
  w.onset_trial = static_cast<int>(i);  // the trial direction even where the slip is above round-off
  const auto trial = [&](double beta) {
    const std::array<double, 2> e = {std::cos(beta), std::sin(beta)};
    w.direction[i] = e;
    Trial out;
    if (compute_dynamics(model, data, formulation, t, q, v) != Status::ok) return out;
    std::array<double, 2> sigma;
    for (std::size_t a = 0; a < 2; ++a) {
      const auto row = static_cast<Eigen::Index>(c.roll[a]);
      sigma[a] = (data.b.row(row).dot(data.qdd) + data.b0(row)) / w.tangent_length[i][a];
    }
    out.size = norm2(sigma);
    if (!(out.size > 0.0)) return Trial{0.0, 0.0, 0.0};
    out.dot = (e[0] * sigma[0] + e[1] * sigma[1]) / out.size;
    out.cross = (e[0] * sigma[1] - e[1] * sigma[0]) / out.size;
    return out;
  };
  constexpr double kStep = 2.0 * std::numbers::pi / kScan;
  std::vector<double> roots;
  double beta_a = beta0 - 0.5 * kStep;
  Trial at_a = trial(beta_a);
  double largest = 0.0;  // the scale of sigma over the circle
  std::vector<std::pair<double, double>> brackets;
  for (int k = 0; k < kScan; ++k) {
    const double beta_b = beta_a + kStep;
    const Trial at_b = trial(beta_b);
    if (std::isfinite(at_b.size)) largest = std::max(largest, at_b.size);
    if (std::isfinite(at_a.cross) && std::isfinite(at_b.cross) && (at_a.cross > 0.0) != (at_b.cross > 0.0))
      brackets.emplace_back(beta_a, at_a.cross);
    beta_a = beta_b;
    at_a = at_b;
  }
  for (const auto& [start, cross_start] : brackets) {
    double lo = start, hi = start + kStep, cross_lo = cross_start;
    for (int n = 0; n < 48; ++n) {
      const double mid = 0.5 * (lo + hi);
      const Trial at = trial(mid);
      if (!std::isfinite(at.cross)) break;
      if (at.size <= 1e-9 * largest) {  // sigma = 0 (below)
        lo = hi = mid;
        break;
      }
      if ((at.cross > 0.0) == (cross_lo > 0.0)) {
        lo = mid;
        cross_lo = at.cross;
      } else {
        hi = mid;
      }
    }
    const double root = 0.5 * (lo + hi);
    // A root with the slip growing along e, not a pole of N(e) (where sigma grows without bound
    // and turns over). At the onset itself, |F_roll| = mu_s N and mu_k = mu_s, sigma vanishes at
    // the root (the slip grows at second order): its direction is the limit of the roots just past
    // the onset, this one.
    const Trial at = trial(root);
    if ((std::abs(at.cross) < 1e-6 && at.dot > 0.0) || at.size <= 1e-9 * largest) roots.push_back(root);
  }
  w.onset_trial = -1;
  w.mode[i] = mode;
  w.direction[i] = carried;
  if (roots.size() == 1) return {true, {std::cos(roots[0]), std::sin(roots[0])}, "", std::nullopt};
  if (roots.size() > 1) {
    const auto distance = [&](double beta) { return std::abs(std::remainder(beta - beta0, 2.0 * std::numbers::pi)); };
    const double nearest = *std::min_element(roots.begin(), roots.end(),
                                             [&](double a, double b) { return distance(a) < distance(b); });
    out.nearest = std::array<double, 2>{std::cos(nearest), std::sin(nearest)};
  }
  out.why = roots.empty() ? "no direction of sliding makes the slip grow along it"
                          : fmt::format("{} directions of sliding make the slip grow along them (the slip's onset is not "
                                        "unique, as in Painleve's paradox)",
                                        roots.size());
  return out;
}

std::string onset_failure(const ContactModeContact& c, double t, const std::string& why) {
  return fmt::format("contact '{}' starts to slip at t = {:.12g}, but {} (docs/derivations/contact-modes.md section 5, "
                     "(O3)); the run ends here with its results so far",
                     c.name, t, why);
}

// Painleve's paradox is watched on w_eff relative to its frictionless part (section 3.8): the run
// stops before the matrix of (S4) turns singular at w_eff = 0.
constexpr double kPainleve = 1e-9;

bool painleve(const ContactModeData& w, std::size_t i) {
  return w.mode[i] == ContactMode::sliding && !(w.w_eff[i] > kPainleve * w.lambda_nn[i]);
}

// The message of a sliding contact in Painleve's paradox, after compute_dynamics in that mode.
std::string painleve_message(const ContactModeContact& c, const ContactModeData& w, std::size_t i, double t) {
  const double N = w.normal_force[i];
  const double nu0 = -N * w.w_eff[i];  // the gap's acceleration were the contact free, (S8)
  const char* kind = w.w_eff[i] < 0.0 && nu0 < 0.0   ? "no mode is consistent (sliding would need the ground to pull, "
                                                         "free the body would sink into it)"
                     : w.w_eff[i] < 0.0 && nu0 > 0.0 ? "two modes are consistent (sliding with N > 0, and free)"
                                                     : "its normal force would grow without bound";
  return fmt::format("contact '{}' slides in Painleve's paradox at t = {:.9g}: with mu_k = {:.6g} its effective normal "
                     "inverse mass w_eff = {:.6g} 1/kg is not positive (frictionless {:.6g} 1/kg; N = {:.6g} N, the free "
                     "gap acceleration {:.6g} m/s^2): {} (docs/derivations/contact-modes.md 3.4, 3.8). Lower the friction "
                     "coefficient",
                     c.name, t, w.mu_k[i], w.w_eff[i], w.lambda_nn[i], N, nu0, kind);
}

// Whether contact c starts free whatever the dynamics: given mode = "free", or unilateral with
// its gap open (above 1e-9 m).
bool starts_free(const ContactModeContact& c, double gap) {
  if (c.initial >= 0) return c.initial == static_cast<int>(ContactMode::free);
  return c.unilateral && gap > 1e-9;
}

// When every touching contact rolling is no motion (more contact rows than coordinates, a ball on
// a floor against a wall), the contacts with friction that slip at t0 slide from the start: their
// no-slip rows are dropped before the first solve. True when the solve then succeeds.
bool slide_the_slipping(const Model& model, Data& data, const FormulationOptions& formulation, double t0,
                        const Vector& q0, const Vector& v0) {
  const ContactModeModel& cm = *model.contact_modes;
  ContactModeData& w = data.modes;
  const double floor = slip_floor(data);
  bool any = false;
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const ContactModeContact& c = cm.contacts[i];
    if (w.mode[i] != ContactMode::rolling || !c.friction || c.initial == static_cast<int>(ContactMode::rolling))
      continue;
    const double s1 = w.velocity_residuals[static_cast<std::size_t>(c.roll_velocity[0])];
    const double s2 = w.velocity_residuals[static_cast<std::size_t>(c.roll_velocity[1])];
    if (std::hypot(s1, s2) <= floor) continue;
    w.mode[i] = ContactMode::sliding;
    any = true;
  }
  if (!any || compute_dynamics(model, data, formulation, t0, q0.data(), v0.data()) != Status::ok) return false;
  // The slips are the state's; the friction of each now opposes its own.
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const double slip = norm2(w.slip[i]);
    if (w.mode[i] == ContactMode::sliding && slip > 0.0) w.direction[i] = {w.slip[i][0] / slip, w.slip[i][1] / slip};
  }
  return compute_dynamics(model, data, formulation, t0, q0.data(), v0.data()) == Status::ok;
}

void throw_at_start(const Model& model, const Data& data) {
  throw ModelError(fmt::format("model '{}': at the initial state: {}", model.name, explain_failure(model, data)));
}

}  // namespace

void choose_initial_contact_modes(const Model& model, Data& data, const FormulationOptions& formulation, double t0,
                                  const Vector& q0, const Vector& v0) {
  if (!data.modes.active || !model.contact_modes) return;
  const ContactModeModel& cm = *model.contact_modes;
  ContactModeData& w = data.modes;
  // The coefficients as the run evaluates them: the model file's checks saw the file's values, and
  // `--set mu=-0.1` made a ball speed up under its friction, `--set e=-0.5` sank a disk into the floor.
  w.tape.run(t0, q0.data(), v0.data(), w.registers.data(), w.outputs.data());
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const ContactModeContact& c = cm.contacts[i];
    const double* o = w.outputs.data() + ContactModeModel::kOutputs * i;
    if (c.friction && !(o[0] >= 0.0 && o[1] >= 0.0 && std::isfinite(o[0]) && std::isfinite(o[1])))
      throw ModelError(fmt::format("{}: contact '{}': its friction coefficients are mu_s = {:.6g}, mu_k = {:.6g} with "
                                   "the parameters' values; a Coulomb friction coefficient is a number >= 0",
                                   c.where, c.name, o[0], o[1]));
    if (c.friction && !(o[0] >= o[1]))
      throw ModelError(fmt::format("{}: contact '{}': its friction has mu_s = {:.6g} below mu_k = {:.6g} with the "
                                   "parameters' values; the static coefficient must be at least the kinetic one",
                                   c.where, c.name, o[0], o[1]));
    if (!(o[2] >= 0.0 && o[2] <= 1.0))
      throw ModelError(fmt::format("{}: contact '{}': its restitution is {:.6g} with the parameters' values; Newton's "
                                   "coefficient of restitution is between 0 (a plastic impact) and 1 (an elastic one)",
                                   c.where, c.name, o[2]));
  }
  if (model.position_constraints() > 0)
    model.evaluator->position_residual(t0, q0.data(), data.scratch.data(), data.phi.data());
  // The contacts that start free say so without the dynamics: given mode = "free", or unilateral
  // and off the ground. The others' rolling forces are those with these free (a body with more
  // contact rows than coordinates can hold only some of its contacts at once).
  if (!w.velocity_residuals.empty())
    model.evaluator->velocity_residual(t0, q0.data(), v0.data(), data.scratch.data(), w.velocity_residuals.data());
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const ContactModeContact& c = cm.contacts[i];
    w.mode[i] = starts_free(c, data.phi(c.gap_position)) ? ContactMode::free : ContactMode::rolling;
    const double gap = data.phi(c.gap_position), rate = w.velocity_residuals[static_cast<std::size_t>(c.gap_velocity)];
    // Inside the ground: free, the gap would never close again (no touchdown is a crossing of 0
    // from above); checked before any normal force, which a body in the ground gets wrong.
    if (c.unilateral && gap < -1e-9)
      throw ModelError(fmt::format("{}: contact '{}' is unilateral, but at t0 its gap is {:.6g} m < 0: the body starts "
                                   "inside the ground (a gap of about minus twice the body's size says it is on the "
                                   "other side of the surface); start it on the ground (gap 0) or above it",
                                   c.where, c.name, gap));
    // Free on the ground and moving into it: an impact at t0, which no event would find.
    if (w.mode[i] == ContactMode::free && gap <= 1e-9 && rate < -slip_floor(data))
      throw ModelError(fmt::format("{}: contact '{}' is given mode = \"free\", but at t0 it touches the ground (gap "
                                   "{:.6g} m) and moves into it ({:.6g} m/s): a free start needs the gap open or "
                                   "opening; start it higher, or rolling (mode = \"rolling\", or leave the key out)",
                                   c.where, c.name, gap + 0.0, rate));
  }
  if (compute_dynamics(model, data, formulation, t0, q0.data(), v0.data()) != Status::ok) {
    // The first failure is the one to report when sliding the slipping contacts does not help.
    const std::string first = fmt::format("model '{}': at the initial state: {}", model.name, explain_failure(model, data));
    if (!slide_the_slipping(model, data, formulation, t0, q0, v0)) throw ModelError(first);
  }
  const double floor = slip_floor(data);
  const ContactModeData rolling = w;  // the rolling forces and slips of every contact
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const ContactModeContact& c = cm.contacts[i];
    const double gap = data.phi(c.gap_position);
    const double slip = norm2(rolling.slip[i]);
    const bool cone_violated = c.friction && norm2(rolling.friction[i]) > rolling.mu_s[i] * std::abs(rolling.normal_force[i]);
    ContactMode mode = ContactMode::rolling;
    // A unilateral contact that carries no load at t0 (N at round-off below 0: a ball resting
    // against a wall) starts free, not refused as pulling.
    const bool unloaded = c.unilateral && rolling.normal_force[i] < 0.0 &&
                          rolling.normal_force[i] >= -1e-10 * (1.0 + data.R.lpNorm<Eigen::Infinity>());
    if (c.initial >= 0) mode = static_cast<ContactMode>(c.initial);
    else if (starts_free(c, gap) || unloaded) mode = ContactMode::free;
    else if (c.friction && (slip > floor || cone_violated)) mode = ContactMode::sliding;
    if (mode == ContactMode::sliding) {
      if (slip > floor) {
        w.direction[i] = {rolling.slip[i][0] / slip, rolling.slip[i][1] / slip};
        w.normal_sign[i] = !c.unilateral && rolling.normal_force[i] < 0.0 ? -1.0 : 1.0;
      } else if (norm2(rolling.friction[i]) > 1e-12 * std::abs(rolling.normal_force[i])) {
        // (Friction at round-off relative to N, as a contact whose point is held by coordinates
        // gives where rolling needs none, defines no direction either.)
        const Onset onset = onset_direction(model, data, formulation, i, t0, q0.data(), v0.data());
        if (!onset.ok)
          throw ModelError(fmt::format("{}: contact '{}' starts sliding at t0, but {} (docs/derivations/"
                                       "contact-modes.md section 5); start it in another mode (mode = \"rolling\" "
                                       "or \"free\")",
                                       c.where, c.name, onset.why));
        w.direction[i] = onset.e;
      } else {
        throw ModelError(fmt::format("{}: contact '{}' is given mode = \"sliding\", but at t0 it does not slip and "
                                     "rolling needs no friction there, so no direction of sliding is defined; "
                                     "start it rolling (mode = \"rolling\", or leave the key out)",
                                     c.where, c.name));
      }
    }
    w.mode[i] = mode;
  }
  if (compute_dynamics(model, data, formulation, t0, q0.data(), v0.data()) != Status::ok) throw_at_start(model, data);
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    // A bilateral contact sliding with the sign of N that rolling has: the sliding one decides (3.6).
    const ContactModeContact& c = cm.contacts[i];
    if (c.unilateral || w.mode[i] != ContactMode::sliding || !(w.normal_sign[i] * w.normal_force[i] < 0.0)) continue;
    w.normal_sign[i] = -w.normal_sign[i];
    if (compute_dynamics(model, data, formulation, t0, q0.data(), v0.data()) != Status::ok) throw_at_start(model, data);
    if (w.normal_sign[i] * w.normal_force[i] < 0.0)
      throw ModelError(fmt::format("{}: contact '{}' starts sliding, but neither sign of its normal force is consistent "
                                   "(docs/derivations/contact-modes.md 3.6); start it in another mode (mode = "
                                   "\"rolling\")",
                                   c.where, c.name));
  }
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const ContactModeContact& c = cm.contacts[i];
    if (painleve(w, i))
      throw ModelError(fmt::format("{}: at t0 {}; or start it in another mode (mode = \"rolling\" or \"free\")", c.where,
                                   painleve_message(c, w, i, t0)));
    if (!c.unilateral || w.mode[i] == ContactMode::free || !(w.normal_force[i] < 0.0)) continue;
    throw ModelError(fmt::format("{}: contact '{}' is unilateral, but at t0 its normal force in the {} mode is N = "
                                 "{:.6g} N < 0: the ground would have to pull the body. Start it free (mode = "
                                 "\"free\"): the body leaves the ground at once; or make the contact bilateral "
                                 "(unilateral = false)",
                                 c.where, c.name, contact_mode_name(w.mode[i]), w.normal_force[i]));
  }
}

double ContactSwitches::window_span(double t) const {
  // The oldest of the last min(switch_count_, kMaxSwitches) switches: slot 0 until the ring is full.
  const long oldest = switch_count_ < kMaxSwitches ? 0 : switch_count_ % kMaxSwitches;
  return switch_count_ > 0 ? t - switch_times_[static_cast<std::size_t>(oldest)] : 0.0;
}

bool ContactSwitches::count_switch(double t) {
  // The slot of the switch kMaxSwitches before this one, which this one replaces.
  double& slot = switch_times_[static_cast<std::size_t>(switch_count_ % kMaxSwitches)];
  const double oldest = slot;
  slot = t;
  ++switch_count_;
  return switch_count_ > kMaxSwitches && t - oldest < kAccumulatedFraction * run_length_;
}

ContactSwitches::ContactSwitches(const Model& model, Data& data, const FormulationOptions& formulation,
                                 int state_size, EventFunctions* user, Handler handler, double run_length)
    : model_(model), data_(data), formulation_(formulation), user_(user), handler_(std::move(handler)),
      user_count_(user ? user->count() : 0), size_(state_size),
      switch_y_(static_cast<std::size_t>(state_size), 0.0), run_length_(run_length) {
  const std::size_t m = model.contact_modes ? model.contact_modes->contacts.size() : 0;
  if (m > 0) switch_times_.assign(static_cast<std::size_t>(kMaxSwitches), -HUGE_VAL);
  last_touchdown_.assign(m, -HUGE_VAL);
  previous_touchdown_.assign(m, -HUGE_VAL);
  touchdowns_.assign(m, 0);
  user_before_.assign(static_cast<std::size_t>(user_count_), 0.0);
  user_after_.assign(static_cast<std::size_t>(user_count_), 0.0);
}

int ContactSwitches::count() const {
  return user_count_ + kSlots * static_cast<int>(model_.contact_modes ? model_.contact_modes->contacts.size() : 0);
}

CrossingDirection ContactSwitches::direction(int i) const {
  return i < user_count_ ? user_->direction(i) : CrossingDirection::falling;
}

bool ContactSwitches::may_dip(int i) const {
  if (i < user_count_) return user_->may_dip(i);
  const int contact = (i - user_count_) / kSlots;
  const int slot = (i - user_count_) % kSlots;
  return slot == 0 && data_.modes.mode[static_cast<std::size_t>(contact)] == ContactMode::free;
}

Status ContactSwitches::evaluate(double t, const double* y, double* g) {
  if (user_) {
    const Status status = user_->evaluate(t, y, g);
    if (status != Status::ok) return status;
  }
  const int n = model_.n();
  const ContactModeModel& cm = *model_.contact_modes;
  ContactModeData& w = data_.modes;
  // The integrator's last right-hand side is often this very state (the first stage of the next
  // step, FSAL): solved in the same modes, every value below is already there. Only while every
  // contact rolls, whose solve depends on the state alone (a sliding one also on its carried
  // direction).
  const bool rolling = std::all_of(w.mode.begin(), w.mode.end(), [](ContactMode m) { return m == ContactMode::rolling; });
  const bool solved = rolling && data_.stage >= Stage::acceleration && w.solved == w.mode && data_.t == t &&
                      std::equal(y, y + n, data_.q.data()) && std::equal(y + n, y + 2 * n, data_.v.data());
  if (!solved) {
    const Status status = compute_dynamics(model_, data_, formulation_, t, y, y + n);
    if (status != Status::ok) return status;
  } else {
    const Status status = compute_mode_forces(model_, data_);
    if (status != Status::ok) return status;
  }
  const bool any_free = std::find(w.mode.begin(), w.mode.end(), ContactMode::free) != w.mode.end();
  if (any_free) model_.evaluator->position_residual(t, y, data_.scratch.data(), data_.phi.data());
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const ContactModeContact& c = cm.contacts[i];
    double* gi = g + user_count_ + kSlots * static_cast<int>(i);
    gi[0] = gi[1] = gi[2] = 1.0;
    const double N = w.normal_force[i];
    switch (w.mode[i]) {
      case ContactMode::rolling:
        if (c.unilateral) gi[0] = N;
        if (c.friction) gi[1] = w.mu_s[i] * (c.unilateral ? N : std::abs(N)) - norm2(w.friction[i]);
        break;
      case ContactMode::sliding:
        gi[0] = c.unilateral ? N : w.normal_sign[i] * N;  // lift-off, or a bilateral N changing sign
        gi[1] = w.slip[i][0] * w.direction[i][0] + w.slip[i][1] * w.direction[i][1];
        gi[2] = w.w_eff[i] - kPainleve * w.lambda_nn[i];  // Painleve (section 3.8)
        break;
      case ContactMode::free: gi[0] = data_.phi(c.gap_position); break;
    }
    // At the start of a segment a switch has just set the slip (sliding) or the gap (free) to 0,
    // from where it rises: that zero is not a crossing, and the sign it starts with is the one it
    // leaves with, so that a flight or a slide shorter than the integrator's first step is still
    // seen to end (section 4: "the touchdown event must ignore the zero it starts on").
    // A gap at rest there (its rate within the integration error) is as good as opening: one that
    // then closes is a touchdown, found as g falls from this positive start (a body set down free
    // on its ground, or released by another contact's impulse, would else pass through it).
    if (t == start_t_) {
      if (w.mode[i] == ContactMode::free && static_cast<int>(i) != grazed_ &&
          w.velocity_residuals[static_cast<std::size_t>(c.gap_velocity)] >= -slip_floor(data_))
        gi[0] = std::max(gi[0], std::numeric_limits<double>::min());
      if (w.mode[i] == ContactMode::sliding) gi[1] = std::max(gi[1], std::numeric_limits<double>::min());
      if (w.mode[i] == ContactMode::sliding && !c.unilateral)  // N's zero after a reversal
        gi[0] = std::max(gi[0], std::numeric_limits<double>::min());
    }
  }
  return Status::ok;
}

std::string ContactSwitches::switch_contact(int contact, int slot, double t, const double* y) {
  const auto i = static_cast<std::size_t>(contact);
  const ContactModeContact& c = model_.contact_modes->contacts[i];
  ContactModeData& w = data_.modes;
  const ContactMode before = w.mode[i];
  if (slot == 0 && before == ContactMode::sliding && !c.unilateral) {
    // A bilateral contact sliding on while its N changes sign: the friction of |N| turns with it
    // (docs/derivations/contact-modes.md 3.6); the mode stays.
    w.normal_sign[i] = -w.normal_sign[i];
    if (compute_dynamics(model_, data_, formulation_, t, y, y + model_.n()) != Status::ok) return "";
    if (!check_sliding(contact, t)) return "";
    return c.name + "_reversal";
  }
  if (slot == 0 && before != ContactMode::free) {
    // From rolling, N can reach 0 while the friction rolling needs does not (a contact without
    // friction limit): free, the contact then starts with g'' = -Lambda_nt F_t, which is < 0 for a
    // coupled contact: it would sink into the ground at once while rolling would pull. No mode is
    // consistent there (docs/derivations/contact-modes.md section 6, "Lift-off"): the lift-off row
    // is written and the run ends with the reason. From sliding F_t = mu_k N falls to 0 with N.
    double needed = 0.0;
    if (before == ContactMode::rolling) {
      if (compute_dynamics(model_, data_, formulation_, t, y, y + model_.n()) != Status::ok) return "";
      needed = norm2(w.friction[i]);
    }
    w.mode[i] = ContactMode::free;
    const std::string name = c.name + "_liftoff";
    if (before != ContactMode::rolling) return name;
    if (compute_dynamics(model_, data_, formulation_, t, y, y + model_.n()) != Status::ok) return "";
    const auto row = static_cast<Eigen::Index>(c.gap);
    const double gap_acceleration = data_.b.row(row).dot(data_.qdd) + data_.b0(row);
    const double scale = data_.b.row(row).cwiseAbs().dot(data_.qdd.cwiseAbs()) + std::abs(data_.b0(row));
    if (!(gap_acceleration < -1e-6 * scale)) return name;
    if (handler_(name, t, switch_y_.data()) != Status::ok) return "";
    accumulation_ = fmt::format(
        "contact '{}': its normal force falls to 0 at t = {:.12g} while rolling still needs the friction |F_t| = "
        "{:.6g} N; free, the contact would at once sink into the ground (gap acceleration {:.6g} m/s^2): no mode is "
        "consistent (docs/derivations/contact-modes.md section 6, \"Lift-off\"). Give the contact a friction "
        "coefficient (friction = ...): it then slides before N reaches 0; the run ends here with its results so far",
        c.name, t, needed, gap_acceleration);
    return "";
  }
  if (slot == 0) return touchdown(contact, t);
  if (slot == 2) {
    // w_eff fell through 0 while sliding (section 3.8): Painleve's paradox ends the run here.
    if (compute_dynamics(model_, data_, formulation_, t, y, y + model_.n()) == Status::ok)
      accumulation_ = painleve_message(c, w, i, t) + "; the run ends here with its results so far";
    return "";
  }
  if (before == ContactMode::rolling) {
    // Slip starts: the friction that rolling needs leaves the cone; it slides in the onset direction.
    if (!start_sliding(contact, t, y, y + model_.n())) return "";
    return c.name + "_slip";
  }
  // The slip reached 0: stick if rolling is consistent and inside the cone, else lift off or slide
  // on in the onset direction (section 6, "Stick or slide on").
  w.mode[i] = ContactMode::rolling;
  if (compute_dynamics(model_, data_, formulation_, t, y, y + model_.n()) != Status::ok) return "";
  const double N = w.normal_force[i];
  if (c.unilateral && !(N > 0.0)) {
    w.mode[i] = ContactMode::free;
    return c.name + "_liftoff";
  }
  if (norm2(w.friction[i]) <= w.mu_s[i] * std::abs(N)) return c.name + "_stick";
  if (!start_sliding(contact, t, y, y + model_.n())) return "";
  return c.name + "_slip";
}

void ContactSwitches::hold_row(double t, const double* y) {
  held_y_.assign(y, y + size_);
  held_t_ = t;
  held_direction_ = data_.modes.direction;
  held_ = true;
}

Status ContactSwitches::flush_row() {
  if (!held_) return Status::ok;
  held_ = false;
  if (!output_) return Status::ok;
  // The row as it was when held: a sliding contact whose slip is still at round-off there (its
  // start) takes the direction carried then, not the one the next step has carried on to.
  std::swap(data_.modes.direction, held_direction_);
  const Status status = (*output_)(held_t_, held_y_.data());
  std::swap(data_.modes.direction, held_direction_);
  return status;
}

Status ContactSwitches::flush_row_after_failure() {
  if (!held_) return Status::ok;
  // What the run's message reads (explain_failure, singular_contact_message): the failure's
  // record and the state it happened at.
  const double t = data_.t, failed_t = data_.failed_t, failed_value = data_.failed_value;
  const Vector q = data_.q, v = data_.v;
  const Status failure = data_.status;
  const std::string quantity = data_.failed_quantity;
  const int contact = data_.modes.failed_contact;
  // And the terms there, which the diagnosis of a singular system reads (formulation/diagnosis.hpp).
  const Matrix A = data_.A, b = data_.b, D = data_.D;
  const Vector b0 = data_.b0, Q = data_.Q, G = data_.G;
  const Status status = flush_row();
  data_.A = A;
  data_.b = b;
  data_.D = D;
  data_.b0 = b0;
  data_.Q = Q;
  data_.G = G;
  data_.t = t;
  data_.q = q;
  data_.v = v;
  data_.status = failure;
  data_.failed_quantity = quantity;
  data_.failed_t = failed_t;
  data_.failed_value = failed_value;
  data_.modes.failed_contact = contact;
  return status;
}

Status ContactSwitches::on_event(int i, double t, const double* y) {
  // The row held at an output time goes first; a switch at that time, to round-off, takes its
  // place instead (a user event's row keeps the rule that the first row written stands).
  if (held_ && i >= user_count_ &&
      std::abs(t - held_t_) <= 64 * std::numeric_limits<double>::epsilon() *
                                   std::max({1.0, std::abs(t), std::abs(held_t_)}))
    held_ = false;
  if (const Status status = flush_row(); status != Status::ok) return status;
  if (i < user_count_) return user_->on_event(i, t, y);
  const int contact = (i - user_count_) / kSlots;
  const int slot = (i - user_count_) % kSlots;
  if (slot == 0 && data_.modes.mode[static_cast<std::size_t>(contact)] == ContactMode::free && grazes(contact, t, y)) {
    // No touchdown: the contact stays free and leaves. The segment restarts there without a row,
    // its gap taken as it is (not as a fresh lift-off's), so that an integrator that locates roots
    // itself (CVODE) does not meet the same zero again at once.
    // Counted as switches are, so that grazes that keep coming back end the run rather than hang it.
    const bool accumulating = count_switch(t);
    same_graze_ = t == last_graze_t_ ? same_graze_ + 1 : 0;
    last_graze_t_ = t;
    if (same_graze_ > kMaxSameTime || accumulating) {
      accumulation_ = fmt::format("contact '{}' grazed its ground at t = {:.9g} ({} times at that instant, {} switches "
                                  "in the run, the last {} of them within {:.3g} s): no consistent mode; the run ends "
                                  "here with its results so far",
                                  model_.contact_modes->contacts[static_cast<std::size_t>(contact)].name, t,
                                  same_graze_ + 1, switch_count_, std::min(switch_count_, kMaxSwitches),
                                  window_span(t));
      return Status::integrator_failure;
    }
    std::copy(y, y + size_, switch_y_.begin());
    switch_t_ = t;
    start_t_ = t;
    grazed_ = contact;
    switched_ = true;
    return Status::stopped;
  }
  grazed_ = -1;
  const bool accumulating = count_switch(t);
  same_time_ = switch_count_ > 1 && std::abs(t - last_switch_t_) <= 64 * std::numeric_limits<double>::epsilon() *
                                                                          std::max(1.0, std::abs(t))
                   ? same_time_ + 1
                   : 0;
  last_switch_t_ = t;
  const std::string& name = model_.contact_modes->contacts[static_cast<std::size_t>(contact)].name;
  if (same_time_ > kMaxSameTime) {
    accumulation_ = fmt::format("no consistent mode for contact '{}' at t = {:.9g}: it switched {} times at that "
                                "instant (the modes tried each call for another at once); the run ends here with its "
                                "results so far",
                                name, t, same_time_);
    return Status::integrator_failure;
  }
  if (accumulating) {
    const double span = window_span(t);
    accumulation_ = fmt::format("the contacts switched {} times by t = {:.9g} (the last: '{}'), the last {} of them "
                                "within {:.3g} s, an accumulation of switches (Zeno or chattering); the run ends here "
                                "with its results so far",
                                switch_count_, t, name, kMaxSwitches, span);
    return Status::integrator_failure;
  }
  std::copy(y, y + size_, switch_y_.begin());  // a touchdown changes its velocities
  settled_.clear();
  // Only an impulse makes another free gap's rate jump: after a touchdown (a free contact's gap
  // reaching 0), not after a lift-off or a slip, where a free gap at the drift's level is no
  // contact closing.
  const bool impact = slot == 0 && data_.modes.mode[static_cast<std::size_t>(contact)] == ContactMode::free;
  // The run's own events before the switch, to find those its jump carries across zero.
  const bool user_before = user_ && user_->evaluate(t, y, user_before_.data()) == Status::ok;
  const std::string event = switch_contact(contact, slot, t, y);
  if (event.empty()) {
    if (accumulation_.empty())
      accumulation_ = fmt::format("contact '{}': the equations could not be solved at the switch at t = {:.9g}: {}",
                                  name, t, data_.status != Status::ok ? explain_failure(model_, data_) : "");
    return Status::integrator_failure;
  }
  switch_t_ = t;
  start_t_ = t;
  switched_ = true;
  // Other contacts touching at this instant, moving into their grounds: their touchdowns now, one
  // after the other, each with the modes the ones before left; then the row, with the state after
  // all of them, and an event record each.
  std::vector<std::string> events{event};
  events.insert(events.end(), settled_.begin(), settled_.end());
  settled_.clear();
  for (std::size_t k = 0; impact && k < data_.modes.mode.size(); ++k) {
    const int next = closing_contact(t);
    if (next < 0) break;
    count_switch(t);  // the same instant as the impact's: judged with it
    const std::vector<double> before = switch_y_;
    const std::string also = switch_contact(next, 0, t, before.data());
    events.push_back(also);
    events.insert(events.end(), settled_.begin(), settled_.end());
    settled_.clear();
    if (also.empty()) {
      if (accumulation_.empty())
        accumulation_ = fmt::format("contact '{}': the equations could not be solved at its touchdown at t = {:.9g}: {}",
                                    model_.contact_modes->contacts[static_cast<std::size_t>(next)].name, t,
                                    data_.status != Status::ok ? explain_failure(model_, data_) : "");
      return Status::integrator_failure;
    }
  }
  for (const std::string& name : events)
    if (const Status status = handler_(name, t, switch_y_.data()); status != Status::ok) return status;
  // A run's event whose function the switch's jump carries across zero (an impact that makes a
  // contact force or a speed pass a stop condition's bound) crosses there: no integrator step
  // would see it, the next segment starting on the other side.
  // Every one is recorded, a stop among them ending the run after them.
  bool stop = false;
  if (user_before && user_->evaluate(t, switch_y_.data(), user_after_.data()) == Status::ok)
    for (int k = 0; k < user_count_; ++k) {
      const double before = user_before_[static_cast<std::size_t>(k)], after = user_after_[static_cast<std::size_t>(k)];
      const CrossingDirection d = user_->direction(k);
      const bool rising = before < 0.0 && after > 0.0, falling = before > 0.0 && after < 0.0;
      if (!(d == CrossingDirection::rising ? rising : d == CrossingDirection::falling ? falling : rising || falling))
        continue;
      const Status status = user_->on_event(k, t, switch_y_.data());
      if (status == Status::stopped) stop = true;
      else if (status != Status::ok) return status;
    }
  if (stop) switched_ = false;  // the run ends here, as planned
  return Status::stopped;
}

int ContactSwitches::closing_contact(double t) {
  const ContactModeModel& cm = *model_.contact_modes;
  ContactModeData& w = data_.modes;
  const int n = model_.n();
  const double* q = switch_y_.data();
  const double* v = q + n;
  if (model_.position_constraints() > 0)
    model_.evaluator->position_residual(t, q, data_.scratch.data(), data_.phi.data());
  if (!w.velocity_residuals.empty())
    model_.evaluator->velocity_residual(t, q, v, data_.scratch.data(), w.velocity_residuals.data());
  double scale = 1.0;
  for (int j = 0; j < n; ++j) scale = std::max(scale, std::abs(q[j]));
  const double touching = 64 * std::numeric_limits<double>::epsilon() * scale;
  const double closing = slip_floor(Eigen::Map<const Vector>(v, n));  // at this state, not Data's
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const ContactModeContact& c = cm.contacts[i];
    if (w.mode[i] != ContactMode::free) continue;
    if (data_.phi(c.gap_position) <= touching &&
        w.velocity_residuals[static_cast<std::size_t>(c.gap_velocity)] < -closing)
      return static_cast<int>(i);
  }
  return -1;
}

bool ContactSwitches::start_sliding(int contact, double t, const double* q, const double* v) {
  const auto i = static_cast<std::size_t>(contact);
  ContactModeData& w = data_.modes;
  if (frictionless(i)) {
    // No friction force: the direction of sliding takes no part in the equations.
    w.direction[i] = {1.0, 0.0};
    w.mode[i] = ContactMode::sliding;
    return compute_dynamics(model_, data_, formulation_, t, q, v) == Status::ok && check_sliding(contact, t);
  }
  const Onset onset = onset_direction(model_, data_, formulation_, i, t, q, v);
  // Several directions: the one nearest (O2) tells whether the sliding is in Painleve's paradox
  // (the message that says which modes are consistent); else the onset is not unique.
  if (!onset.ok && !onset.nearest) {
    accumulation_ = onset_failure(model_.contact_modes->contacts[i], t, onset.why);
    return false;
  }
  w.direction[i] = onset.ok ? onset.e : *onset.nearest;
  w.mode[i] = ContactMode::sliding;
  if (compute_dynamics(model_, data_, formulation_, t, q, v) != Status::ok) return false;
  if (!check_sliding(contact, t)) return false;
  if (onset.ok) return true;
  accumulation_ = onset_failure(model_.contact_modes->contacts[i], t, onset.why);
  return false;
}

bool ContactSwitches::check_sliding(int contact, double t) {
  const auto i = static_cast<std::size_t>(contact);
  ContactModeData& w = data_.modes;
  const ContactModeContact& c = model_.contact_modes->contacts[i];
  if (!c.unilateral && w.normal_sign[i] * w.normal_force[i] < 0.0) {
    // The sign taken from rolling is not the sliding one: slide with the other (3.6).
    w.normal_sign[i] = -w.normal_sign[i];
    const Vector q = data_.q, v = data_.v;
    if (compute_dynamics(model_, data_, formulation_, t, q.data(), v.data()) != Status::ok) return false;
    if (w.normal_sign[i] * w.normal_force[i] < 0.0) {
      accumulation_ = fmt::format("contact '{}' starts to slide at t = {:.12g}, but neither sign of its normal force is "
                                  "consistent (N = {:.6g} N when the friction takes the other): as in Painleve's "
                                  "paradox (docs/derivations/contact-modes.md 3.6); the run ends here with its "
                                  "results so far",
                                  c.name, t, w.normal_force[i]);
      return false;
    }
  }
  if (!painleve(data_.modes, i)) return true;
  accumulation_ = painleve_message(model_.contact_modes->contacts[i], data_.modes, i, t) +
                  "; the run ends here with its results so far";
  return false;
}

namespace {

// Why the impulse of contact `i`'s touchdown has no Do Sanh form: the contacts held through the
// impact keep r rows of this rank on n coordinates. Named, since with two of them on one body (a
// ball rolling into a wall) their rows may be dependent, or as many as the coordinates.
std::string held_rows_failure(const Model& model, const ContactModeData& w, std::size_t i, bool sliding, double t,
                              int r, int rank) {
  const ContactModeModel& cm = *model.contact_modes;
  std::string held;
  for (std::size_t j = 0; j < cm.contacts.size(); ++j)
    if (j == i || w.mode[j] != ContactMode::free)
      held += fmt::format("{}'{}' ({})", held.empty() ? "" : ", ", cm.contacts[j].name,
                          j == i ? (sliding ? "sliding" : "touching down") : contact_mode_name(w.mode[j]));
  return fmt::format(
      "contact '{}' touches down at t = {:.9g}, where the contacts held through the impact, {}, keep {} constraint "
      "rows of rank {} on {} coordinates: the impact's equations in the Do Sanh form need fewer rows than "
      "coordinates, and independent ones (docs/contact-modes.md, \"More contacts than freedom\"); the run ends "
      "here with its results so far",
      cm.contacts[i].name, t, held, r, rank, model.n());
}

}  // namespace

Impulse ContactSwitches::solve_impulse(int contact, double t, const double* v, bool sliding,
                                       const std::array<double, 2>& direction) {
  Impulse out;
  const auto i = static_cast<std::size_t>(contact);
  const ContactModeModel& cm = *model_.contact_modes;
  const ContactModeContact& c = cm.contacts[i];
  const ContactModeData& w = data_.modes;
  const int n = model_.n();
  const int s = model_.s();
  const std::vector<double>& f = w.velocity_residuals;  // of the state before, by compute_dynamics
  const double e = w.restitution[i];
  const double vn = f[static_cast<std::size_t>(c.gap_velocity)];  // the gap's rate before, < 0
  // (I1)-(I2): the rows kept after the impact hold their velocity residuals, the gap's rate
  // becomes -e times what it was; sticking, the slip becomes 0; sliding, the no-slip rows leave b
  // and the gap's column of B~ is w_n - mu_k w_s (section 7, "The sliding impulse, as solved").
  std::vector<int> rows;
  std::vector<double> target;
  int velocity_index = 0;
  const Eigen::Map<const Vector> v_before(v, n);
  for (int row = 0; row < s; ++row) {
    const bool has_velocity = model_.constraints[static_cast<std::size_t>(row)].level != ConstraintLevel::acceleration;
    bool keep = !(sliding && (row == c.roll[0] || row == c.roll[1] || row == c.spin));
    for (std::size_t j = 0; j < cm.contacts.size() && keep; ++j) {
      const ContactModeContact& o = cm.contacts[j];
      if (j == i || w.mode[j] == ContactMode::rolling) continue;
      keep = row != o.roll[0] && row != o.roll[1] && row != o.spin && !(w.mode[j] == ContactMode::free && row == o.gap);
    }
    if (keep) {
      double delta = 0.0;
      if (row == c.gap) delta = -(1.0 + e) * vn;
      else if (row == c.roll[0] || row == c.roll[1] || row == c.spin) delta = -f[static_cast<std::size_t>(velocity_index)];
      rows.push_back(row);
      target.push_back(data_.b.row(row).dot(v_before) + delta);
    }
    if (has_velocity) ++velocity_index;
  }
  const int r = static_cast<int>(rows.size());
  Matrix Bt(n, r);
  int gap_column = -1;
  std::array<int, 2> roll_column{-1, -1};
  for (int j = 0; j < r; ++j) {
    const int row = rows[static_cast<std::size_t>(j)];
    Bt.col(j) = data_.b.row(row).transpose();
    if (row == c.gap) gap_column = j;
    for (std::size_t a = 0; a < 2; ++a)
      if (row == c.roll[a]) roll_column[a] = j;
    // A sliding contact's reaction along n - mu_k e_s: this one's impulse when it slides, the
    // others' as in their mode.
    for (std::size_t o = 0; o < cm.contacts.size(); ++o) {
      const ContactModeContact& other = cm.contacts[o];
      if (row != other.gap) continue;
      const bool slides = o == i ? sliding : w.mode[o] == ContactMode::sliding;
      const std::array<double, 2>& d = o == i ? direction : w.sliding_direction[o];
      if (slides)
        for (std::size_t a = 0; a < 2; ++a)
          Bt.col(j) -= (w.mu_k[o] * d[a] / w.tangent_length[o][a]) * data_.b.row(other.roll[a]).transpose();
    }
  }
  // In the coordinates' own scales S of the modes' solve at this state (w.coordinate_scale,
  // formulation/contact_modes.cpp; ones where the inertias are within 2^26 of each other): the QR
  // of S B~^T, D = D~ S and v+ = S y, so that a disk 0.4 micrometres across, whose angles have
  // inertias 1e-14 of its mass, is not judged singular for its units.
  const Vector& S = w.coordinate_scale;
  Bt.array().colwise() *= S.array();
  Eigen::ColPivHouseholderQR<Matrix> qr(Bt);
  if (qr.rank() < r || r >= n || gap_column < 0) {
    out.failure = held_rows_failure(model_, w, i, sliding, t, r, static_cast<int>(qr.rank()));
    return out;
  }
  const Matrix Qf = qr.householderQ();
  Matrix D = Qf.rightCols(n - r).transpose();
  D.array().rowwise() *= S.transpose().array();  // D = D~ S
  Matrix M(n, n);
  Vector rhs(n);
  M.topRows(n - r) = D * data_.A;
  rhs.head(n - r) = D * (data_.A * v_before);
  for (int j = 0; j < r; ++j) {
    M.row(n - r + j) = data_.b.row(rows[static_cast<std::size_t>(j)]);
    rhs(n - r + j) = target[static_cast<std::size_t>(j)];
  }
  M.array().rowwise() *= S.transpose().array();  // the unknown is y, v+ = S y
  // Rows in different units scaled exactly first, as every solve of [D A; b] (formulation/detail/row_scaling.hpp).
  scale_rows_by_powers_of_two(
      n, [&](int i) { return M.row(i).cwiseAbs().maxCoeff(); },
      [&](int i, int exponent) {
        const double factor = std::ldexp(1.0, -exponent);
        M.row(i) *= factor;
        rhs(i) *= factor;
      });
  Eigen::PartialPivLU<Matrix> lu(M);
  if (!(lu.rcond() > 1e-14)) {
    out.failure = fmt::format("contact '{}' touches down at t = {:.9g} where the impulse equations are singular{}; "
                              "the run ends here with its results so far",
                              c.name, t, sliding ? " (a sliding impact in Painleve's paradox: lower the friction)" : "");
    return out;
  }
  out.v = lu.solve(rhs);
  out.v.array() *= S.array();
  // The impulse, A (q'+ - q'-) = B~^T Pi, read on the columns as N is from R: S A (q'+ - q'-) = (S B~^T) Pi.
  Vector impulse = data_.A * (out.v - v_before);
  impulse.array() *= S.array();
  const Vector Pi = qr.solve(impulse);
  out.normal = Pi(gap_column);
  const double largest = Pi.size() > 0 ? Pi.cwiseAbs().maxCoeff() : 0.0;
  for (int j = 0; j < r && out.pulling < 0; ++j)
    for (std::size_t o = 0; o < cm.contacts.size(); ++o)
      if (o != i && cm.contacts[o].unilateral && rows[static_cast<std::size_t>(j)] == cm.contacts[o].gap &&
          Pi(j) < -1e-10 * largest)
        out.pulling = static_cast<int>(o);
  for (std::size_t a = 0; a < 2; ++a)
    out.tangential[a] = sliding ? -w.mu_k[i] * out.normal * direction[a]
                                : (roll_column[a] >= 0 ? Pi(roll_column[a]) * w.tangent_length[i][a] : 0.0);
  out.ok = true;
  return out;
}

bool ContactSwitches::settle_others(int contact, double t, const double* q, const double* v) {
  ContactModeData& w = data_.modes;
  const ContactModeModel& cm = *model_.contact_modes;
  std::vector<std::size_t> sliding, rolling;
  for (std::size_t j = 0; j < cm.contacts.size(); ++j)
    if (static_cast<int>(j) != contact && w.mode[j] == ContactMode::sliding) sliding.push_back(j);
    else if (static_cast<int>(j) != contact && w.mode[j] == ContactMode::rolling &&
             (cm.contacts[j].unilateral || cm.contacts[j].friction))
      rolling.push_back(j);
  if (sliding.empty() && rolling.empty()) return true;
  if (compute_dynamics(model_, data_, formulation_, t, q, v) != Status::ok) return false;
  // A rolling contact that the impact leaves pulling lifts off; one that needs more friction than
  // its cone gives slips: each with its event at this time (the next segment would start past the
  // crossing that finds it).
  bool changed = false;
  for (std::size_t j : rolling) {
    const ContactModeContact& o = cm.contacts[j];
    if (o.unilateral && w.normal_force[j] < -1e-10 * (1.0 + data_.R.lpNorm<Eigen::Infinity>())) {
      w.mode[j] = ContactMode::free;
      settled_.push_back(o.name + "_liftoff");
      changed = true;
    } else if (o.friction && norm2(w.friction[j]) > w.mu_s[j] * std::abs(w.normal_force[j]) * (1.0 + 1e-12)) {
      if (!start_sliding(static_cast<int>(j), t, q, v)) return false;
      settled_.push_back(o.name + "_slip");
      changed = true;
    }
  }
  if (changed && compute_dynamics(model_, data_, formulation_, t, q, v) != Status::ok) return false;
  if (sliding.empty()) return true;
  std::vector<std::size_t> stopped;
  for (std::size_t j : sliding) {
    const double slip = norm2(w.slip[j]);
    if (slip > slip_floor(data_)) {
      w.direction[j] = {w.slip[j][0] / slip, w.slip[j][1] / slip};
    } else {
      w.mode[j] = ContactMode::rolling;
      stopped.push_back(j);
    }
  }
  if (stopped.empty()) return true;
  if (compute_dynamics(model_, data_, formulation_, t, q, v) != Status::ok) return false;
  for (std::size_t j : stopped) {
    if (norm2(w.friction[j]) > w.mu_s[j] * std::abs(w.normal_force[j])) {
      if (!start_sliding(static_cast<int>(j), t, q, v)) return false;
      continue;
    }
    settled_.push_back(cm.contacts[j].name + "_stick");  // an event row of its own, at the same time
  }
  return true;
}

bool ContactSwitches::grazes(int contact, double t, const double* y) {
  const ContactModeContact& c = model_.contact_modes->contacts[static_cast<std::size_t>(contact)];
  if (compute_dynamics(model_, data_, formulation_, t, y, y + model_.n()) != Status::ok) return false;
  const double approach = data_.modes.velocity_residuals[static_cast<std::size_t>(c.gap_velocity)];
  const double acceleration = data_.b.row(c.gap).dot(data_.qdd) + data_.b0(c.gap);  // the free gap's g''
  return approach >= -slip_floor(data_) && acceleration > 0.0;
}

// The impulse of `contact`'s touchdown at (t, v), after compute_dynamics there in the modes before
// (section 7, "Which impulse"): sticking if inside the cone, else sliding along the slip before it
// (`slip_before`); another unilateral contact that would pull through the impact leaves the ground
// at it (its own NAME_liftoff at the same time), and the impulse is solved again without it. False,
// with the message in accumulation_, when no impact law of the model is consistent there.
bool ContactSwitches::impact_impulse(int contact, double t, const double* v,
                                     const std::array<double, 2>& slip_before, Impulse& impulse) {
  const auto i = static_cast<std::size_t>(contact);
  const ContactModeModel& cm = *model_.contact_modes;
  const ContactModeContact& c = cm.contacts[i];
  ContactModeData& w = data_.modes;
  // Another unilateral contact that would pull through the impact leaves the ground at it
  // (its own NAME_liftoff at the same time), and the impulse is solved again without it.
  for (std::size_t released = 0;; ++released) {
    // Coulomb at the impulse level (section 7, "Which impulse"): sticking if inside the cone.
    // A frictionless contact (friction = 0) takes no tangential impulse: straight to the sliding one,
    // which keeps its gap row alone (the sticking one would hold its no-slip rows too).
    impulse = frictionless(i) ? Impulse{} : solve_impulse(contact, t, v, false, {0.0, 0.0});
    if (!frictionless(i) && !impulse.ok) {
      accumulation_ = impulse.failure;
      return false;
    }
    if (frictionless(i) || (c.friction && norm2(impulse.tangential) > w.mu_s[i] * impulse.normal)) {
      std::array<double, 2> direction{0.0, 0.0};
      const double slip = norm2(slip_before);
      if (slip > slip_floor(data_)) direction = {slip_before[0] / slip, slip_before[1] / slip};
      else if (frictionless(i)) direction = {1.0, 0.0};
      else {
        const double size = norm2(impulse.tangential);
        if (!(size > 0.0)) {
          // Outside the cone only because the sticking impulse pulls (normal <= 0), with no
          // tangential part and no slip: no direction to slide in, and no impact law holds.
          accumulation_ = fmt::format(
              "contact '{}' touches down at t = {:.9g} with a sticking impulse that pulls (normal impulse {:.6g} N s) "
              "and no slip to slide along: no impact law of this model is consistent there "
              "(docs/derivations/contact-modes.md section 7). The run ends here with its results so far",
              c.name, t, impulse.normal);
          return false;
        }
        direction = {-impulse.tangential[0] / size, -impulse.tangential[1] / size};
      }
      impulse = solve_impulse(contact, t, v, true, direction);
      if (!impulse.ok) {
        accumulation_ = impulse.failure;
        return false;
      }
      if (!(impulse.normal > 0.0) && frictionless(i)) {
        accumulation_ = fmt::format("contact '{}' touches down at t = {:.9g} with an impulse that would have to pull "
                                    "(normal impulse {:.6g} N s): no impact law of this model is consistent there "
                                    "(docs/derivations/contact-modes.md section 7). The run ends here with its "
                                    "results so far",
                                    c.name, t, impulse.normal);
        return false;
      }
      if (!(impulse.normal > 0.0)) {
        accumulation_ = fmt::format(
            "contact '{}' touches down at t = {:.9g} sliding (the sticking impulse is outside the friction cone) in "
            "Painleve's paradox: with mu_k = {:.6g} the impulse along n - mu_k e_s would have to pull (normal impulse "
            "{:.6g} N s), w_eff <= 0 (docs/derivations/contact-modes.md 3.8); no impact law of this model is "
            "consistent there. The run ends here with its results so far; lower the friction coefficient",
            c.name, t, w.mu_k[i], impulse.normal);
        return false;
      }
      w.direction[i] = direction;
    }
    if (impulse.pulling < 0) break;
    if (released >= cm.contacts.size()) {
      accumulation_ = fmt::format("contact '{}' touches down at t = {:.9g}, and releasing the contacts whose impulse "
                                  "would pull leaves one that still pulls ('{}'): no impact law of this model is "
                                  "consistent there; the run ends here with its results so far",
                                  c.name, t, cm.contacts[static_cast<std::size_t>(impulse.pulling)].name);
      return false;
    }
    w.mode[static_cast<std::size_t>(impulse.pulling)] = ContactMode::free;
    settled_.push_back(cm.contacts[static_cast<std::size_t>(impulse.pulling)].name + "_liftoff");
  }
  return true;
}

std::string ContactSwitches::touchdown(int contact, double t) {
  const auto i = static_cast<std::size_t>(contact);
  const ContactModeModel& cm = *model_.contact_modes;
  const ContactModeContact& c = cm.contacts[i];
  ContactModeData& w = data_.modes;
  const int n = model_.n();
  // Zeno (section 9): touchdowns 1e-7 s apart (relative to t) accumulate: bounces of a height
  // 1e-14 m, a few orders above what the event location resolves, so none is missed.
  const double interval = t - last_touchdown_[i];
  const double previous = last_touchdown_[i] - previous_touchdown_[i];
  ++touchdowns_[i];
  previous_touchdown_[i] = last_touchdown_[i];
  last_touchdown_[i] = t;
  if (interval < 1e-7 * std::max(1.0, std::abs(t))) {
    const double rho = previous > 0.0 ? interval / previous : 0.0;
    accumulation_ = fmt::format("contact '{}' touched down {} times, the last two {:.3g} s apart (ratio {:.3g} to the "
                                "interval before): an accumulation of impacts (Zeno) near t = {:.9g}; the run ends "
                                "here at t = {:.9g} with its results so far",
                                c.name, touchdowns_[i], interval, rho,
                                rho > 0.0 && rho < 1.0 ? t + interval * rho / (1.0 - rho) : t, t);
    return "";
  }
  double* q = switch_y_.data();
  double* v = q + n;
  // The state before, in the current modes (this contact free): the terms, every contact's mu,
  // slip and tangent lengths, and the velocity residuals.
  if (compute_dynamics(model_, data_, formulation_, t, q, v) != Status::ok) return "";
  const double e = w.restitution[i];
  const double vn = w.velocity_residuals[static_cast<std::size_t>(c.gap_velocity)];
  const std::array<double, 2> slip_before = w.slip[i];
  Impulse impulse;
  if (!impact_impulse(contact, t, v, slip_before, impulse)) return "";
  const Evaluator& ev = *model_.evaluator;
  const bool balance = ev.has_energy_balance() && size_ > 2 * n + 4;
  const double h_before = balance ? ev.energy_function(t, q, v, data_.scratch.data()) : 0.0;
  std::copy(impulse.v.data(), impulse.v.data() + n, v);
  // The energy the impact takes, h- - h+ (section 8), booked as impact_loss (W includes -impact_loss),
  // so that h - h0 - W does not jump; the reactions' work keeps its meaning (the finite reactions).
  if (balance) {
    const double h_after = ev.energy_function(t, q, v, data_.scratch.data());
    const double loss = h_before - h_after;
    switch_y_[static_cast<std::size_t>(2 * n + 4)] += loss;
    if (loss < -1e-9 * (std::abs(h_before) + std::abs(h_after)) && !gained_energy_) {
      gained_energy_ = true;
      warnings_.push_back(fmt::format(
          "contact '{}': the impact at t = {:.9g} gains energy ({:.6g} J): Newton's restitution e = {:.6g} with "
          "friction at a contact whose normal and tangential motions couple can create energy "
          "(docs/derivations/contact-modes.md section 7); a smaller restitution avoids it. Later impacts that gain "
          "energy are not reported",
          c.name, t, -loss, e));
    }
  }
  const std::string name = c.name + "_touchdown";
  if (e > 0.0 && -e * vn > slip_floor(data_)) {
    w.mode[i] = c.unilateral ? ContactMode::free : ContactMode::rolling;
    return settle_others(contact, t, q, v) ? name : "";
  }
  // The contact stays closed: the mode as at the start (section 7, "After the impact"): sliding
  // if it slips after the impact, else rolling if inside the cone, free if it would pull.
  w.mode[i] = ContactMode::rolling;
  if (compute_dynamics(model_, data_, formulation_, t, q, v) != Status::ok) return "";
  const double slip = norm2(w.slip[i]);
  if (c.friction && slip > slip_floor(data_)) {
    w.direction[i] = {w.slip[i][0] / slip, w.slip[i][1] / slip};
    w.normal_sign[i] = 1.0;  // a touchdown is unilateral
    w.mode[i] = ContactMode::sliding;
    if (compute_dynamics(model_, data_, formulation_, t, q, v) != Status::ok) return "";
    if (!check_sliding(contact, t)) return "";
    if (c.unilateral && w.normal_force[i] < 0.0) w.mode[i] = ContactMode::free;
    return settle_others(contact, t, q, v) ? name : "";
  }
  if (c.unilateral && w.normal_force[i] < 0.0) w.mode[i] = ContactMode::free;
  else if (c.friction && norm2(w.friction[i]) > w.mu_s[i] * std::abs(w.normal_force[i])) {
    if (!start_sliding(contact, t, q, v)) return "";
  }
  return settle_others(contact, t, q, v) ? name : "";
}

IntegrationResult integrate_contact_modes(OdeSystem& ode, const IntegratorOptions& options, double t0,
                                          const double* y0, std::span<const double> output_times,
                                          const OutputFn& output, ContactSwitches& switches) {
  std::vector<double> y(y0, y0 + ode.size());
  double t = t0;
  std::size_t next = 0;
  IntegratorStats total;
  IntegratorOptions segment = options;
  // Each output time's row waits for the next call (ContactSwitches::hold_row): a switch found
  // within round-off after it replaces it.
  switches.set_output(&output);
  switches.start(t0);
  const OutputFn held = [&switches](double time, const double* state) {
    const Status status = switches.flush_row();
    if (status == Status::ok) switches.hold_row(time, state);
    return status;
  };
  while (true) {
    IntegrationResult result = integrate(ode, segment, t, y.data(), output_times.subspan(next), held, &switches);
    const bool failed = result.status != Status::ok && !(result.status == Status::stopped && switches.switched());
    if (const Status status = failed ? switches.flush_row_after_failure() : switches.flush_row();
        status != Status::ok && result.status == Status::ok)
      result.status = status;
    total.add(result.stats);
    result.stats = total;
    if (result.status == Status::stopped && switches.switched()) {
      switches.clear();
      t = switches.switch_t();
      y = switches.switch_y();
      while (next < output_times.size() && output_times[next] <= t) ++next;
      segment.max_steps = options.max_steps - total.steps - total.rejected_steps;
      if (next < output_times.size() && segment.max_steps > 0) continue;
      result.status = next < output_times.size() ? Status::too_many_steps : Status::ok;
      result.t_reached = t;
      return result;
    }
    if (!switches.accumulation().empty() && result.status != Status::ok) result.message = switches.accumulation();
    return result;
  }
}

}  // namespace nhdyn
