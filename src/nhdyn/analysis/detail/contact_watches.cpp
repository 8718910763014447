#include "nhdyn/analysis/detail/contact_watches.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "nhdyn/formulation/diagnosis.hpp"

namespace nhdyn {
namespace {

// The index of the contact `name` among the contacts with modes (model/contact_modes.hpp), or -1.
int mode_contact_index(const Model& model, const std::string& name) {
  if (!model.contact_modes) return -1;
  const std::vector<ContactModeContact>& contacts = model.contact_modes->contacts;
  for (std::size_t i = 0; i < contacts.size(); ++i)
    if (contacts[i].name == name) return static_cast<int>(i);
  return -1;
}

// Whether a contact's watch applies in its current mode (ContactWatch::touching_only, free_only):
// in the air a convexity describes no touching body, and the free flight's watch no contact.
bool watched_in_mode(const Data& data, int mode_contact, bool touching_only, bool free_only) {
  const bool free = mode_contact >= 0 && data.modes.active &&
                    data.modes.mode[static_cast<std::size_t>(mode_contact)] == ContactMode::free;
  return free ? !touching_only : !free_only;
}

}  // namespace

double calc_watch_measure(const Model& model, const ContactWatch& w, double t, const double* q, const double* v) {
  std::vector<double> values;
  for (const Parameter& p : model.parameters) values.push_back(p.value);
  const Tape measure = w.measure.bind(values.data(), values.size());
  std::vector<double> registers(static_cast<std::size_t>(measure.registers()));
  double value = 0.0;
  measure.run(t, q, v, registers.data(), &value);
  return value;
}

std::string watch_message(const Model& model, const ContactWatch& w, double value, double t, const double* q,
                          const double* v, const char* ending) {
  return fmt::format("{}{} '{}': {} ({} = {:.3g}) at t = {:.6g}, where {}; {}", w.where.empty() ? "" : w.where + ": ",
                     w.entry, w.contact, w.reason, w.quantity, value + 0.0 /* -0 as 0 */, t, describe_state(model, q, v),
                     ending);
}

std::string singular_contact_message(const Model& model, const Data& data, double t, const double* q,
                                     const double* v, const char* ending) {
  for (const ContactWatch& w : model.contact_watches) {
    if (!watched_in_mode(data, mode_contact_index(model, w.contact), w.touching_only, w.free_only)) continue;
    const double value = calc_watch_measure(model, w, t, q, v);
    if (value >= w.threshold) continue;
    return watch_message(model, w, value, t, q, v, ending);
  }
  return "";
}


WatchedEvents::WatchedEvents(const Model& model, Data& data)
    : data_(data), n_(model.n()), fired_y_(static_cast<std::size_t>(2 * model.n()), 0.0) {
  std::vector<double> values;
  for (const Parameter& p : model.parameters) values.push_back(p.value);
  for (std::size_t i = 0; i < model.contact_watches.size(); ++i) {
    const ContactWatch& w = model.contact_watches[i];
    if (!w.every_step) continue;
    watches_.push_back({w.measure.bind(values.data(), values.size()), w.threshold, mode_contact_index(model, w.contact),
                        w.touching_only, w.free_only, static_cast<int>(i)});
    registers_.resize(std::max(registers_.size(), static_cast<std::size_t>(watches_.back().measure.registers())));
  }
}

Status WatchedEvents::evaluate(double t, const double* y, double* g) {
  if (user_) {
    const Status status = user_->evaluate(t, y, g);
    if (status != Status::ok) return status;
  }
  for (std::size_t k = 0; k < watches_.size(); ++k) {
    const Watch& w = watches_[k];
    double& gk = g[static_cast<std::size_t>(user_count_) + k];
    if (!watched_in_mode(data_, w.mode_contact, w.touching_only, w.free_only)) {
      gk = 1.0;
      continue;
    }
    double value = 0.0;
    w.measure.run(t, y, y + n_, registers_.data(), &value);
    gk = std::isfinite(value) ? value - w.threshold : -1.0;
  }
  return Status::ok;
}

Status WatchedEvents::on_event(int i, double t, const double* y) {
  if (i < user_count_) return user_->on_event(i, t, y);
  return stop(watches_[static_cast<std::size_t>(i - user_count_)].index, t, y);
}

Status WatchedEvents::check(double t, const double* y) {
  for (const Watch& w : watches_) {
    if (!watched_in_mode(data_, w.mode_contact, w.touching_only, w.free_only)) continue;
    double value = 0.0;
    w.measure.run(t, y, y + n_, registers_.data(), &value);
    if (!(value >= w.threshold)) return stop(w.index, t, y);
  }
  return Status::ok;
}

Status WatchedEvents::stop(int index, double t, const double* y) {
  fired_ = index;
  fired_t_ = t;
  std::memcpy(fired_y_.data(), y, sizeof(double) * fired_y_.size());
  return Status::singular_system;
}

}  // namespace nhdyn
