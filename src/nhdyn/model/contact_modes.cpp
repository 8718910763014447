#include "nhdyn/model/contact_modes.hpp"

#include <cmath>

#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

const char* contact_mode_name(ContactMode mode) {
  switch (mode) {
    case ContactMode::rolling: return "rolling";
    case ContactMode::sliding: return "sliding";
    case ContactMode::free: return "free";
  }
  return "rolling";
}

ContactModeData make_contact_mode_data(const Model& model) {
  ContactModeData w;
  if (!model.contact_modes) return w;
  const ContactModeModel& c = *model.contact_modes;
  w.active = true;
  std::vector<double> values;
  for (const Parameter& p : model.parameters) values.push_back(p.value);
  w.tape = PreparedTape(c.tape.bind(values.data(), values.size()));
  w.registers.assign(static_cast<std::size_t>(w.tape.registers()), 0.0);
  w.outputs.assign(static_cast<std::size_t>(w.tape.outputs()), 0.0);
  const std::size_t m = c.contacts.size();
  // The modes a fresh Data solves in, before a run chooses them from the state
  // (choose_initial_contact_modes): rolling, or free where the model file says so (a contact that
  // starts away from the ground; with more contact rows than coordinates, all rolling is no motion).
  w.mode.assign(m, ContactMode::rolling);
  for (std::size_t i = 0; i < m; ++i)
    if (model.contact_modes->contacts[i].initial == static_cast<int>(ContactMode::free)) w.mode[i] = ContactMode::free;
  w.solved.assign(m, ContactMode::free);
  w.direction.assign(m, {1.0, 0.0});
  w.normal_sign.assign(m, 1.0);
  w.mu_s.assign(m, 0.0);
  w.mu_k.assign(m, 0.0);
  w.restitution.assign(m, 0.0);
  w.normal_force.assign(m, 0.0);
  w.friction.assign(m, {0.0, 0.0});
  w.slip.assign(m, {0.0, 0.0});
  w.slip_world.assign(m, {0.0, 0.0, 0.0});
  w.sliding_direction.assign(m, {0.0, 0.0});
  w.friction_power.assign(m, 0.0);
  w.w_eff.assign(m, 0.0);
  w.lambda_nn.assign(m, 0.0);
  w.gap.assign(m, 0.0);
  w.gap_column.assign(m, -1);
  w.tangent_length.assign(m, {1.0, 1.0});
  w.kept.reserve(static_cast<std::size_t>(model.s()));
  w.velocity_residuals.assign(static_cast<std::size_t>(model.velocity_constraints()), 0.0);
  const int n = model.n();
  w.M = Matrix::Zero(n, n);
  w.rhs = Vector::Zero(n);
  w.row_scale = Vector::Ones(n);
  w.coordinate_scale = Vector::Ones(n);
  w.probe = Vector::Zero(n);
  w.response = Vector::Zero(n);
  w.lu = Eigen::PartialPivLU<Matrix>(n);
  return w;
}

std::vector<std::string> contact_mode_columns(const Model& model) {
  std::vector<std::string> columns;
  if (!model.contact_modes) return columns;
  for (const ContactModeContact& c : model.contact_modes->contacts)
    for (const char* suffix : {"_mode", "_slip_speed", "_slip_x", "_slip_y", "_slip_z", "_gap"})
      columns.push_back(c.name + suffix);
  columns.push_back("work_friction");
  columns.push_back("impact_loss");
  return columns;
}

void append_contact_mode_values(const Model& model, const Data& data, std::vector<double>& row) {
  if (model.contact_modes) append_contact_mode_values(data, row);
}

void append_contact_mode_values(const Data& data, std::vector<double>& row) {
  const ContactModeData& w = data.modes;
  if (!w.active) return;
  for (std::size_t i = 0; i < w.mode.size(); ++i) {
    row.push_back(static_cast<double>(static_cast<int>(w.mode[i])));
    const auto& s = w.slip_world[i];
    row.push_back(w.mode[i] == ContactMode::free ? 0.0 : std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]));
    for (int k = 0; k < 3; ++k) row.push_back(w.mode[i] == ContactMode::free ? 0.0 : s[static_cast<std::size_t>(k)]);
    row.push_back(w.gap[i]);
  }
  row.push_back(data.work_friction);
  row.push_back(data.impact_loss);
}

bool contact_mode_drops_row(const ContactModeContact& c, ContactMode mode, int row) {
  if (mode == ContactMode::rolling || row < 0) return false;
  if (row == c.roll[0] || row == c.roll[1] || row == c.spin) return true;
  return mode == ContactMode::free && row == c.gap;
}

int constraints_always_held(const Model& model) {
  if (!model.contact_modes) return model.s();
  int held = 0;
  for (int row = 0; row < model.s(); ++row) {
    bool dropped = false;
    for (const ContactModeContact& c : model.contact_modes->contacts)
      dropped = dropped || (c.unilateral && contact_mode_drops_row(c, ContactMode::free, row)) ||
                (c.friction && contact_mode_drops_row(c, ContactMode::sliding, row));
    held += dropped ? 0 : 1;
  }
  return held;
}

bool contact_mode_drops(const Model& model, const Data& data, const std::string& constraint) {
  if (!model.contact_modes || !data.modes.active) return false;
  const std::vector<ContactModeContact>& contacts = model.contact_modes->contacts;
  for (int row = 0; row < model.s(); ++row) {
    if (model.constraints[static_cast<std::size_t>(row)].name != constraint) continue;
    for (std::size_t i = 0; i < contacts.size(); ++i)
      if (contact_mode_drops_row(contacts[i], data.modes.mode[i], row)) return true;
  }
  return false;
}

void record_contact_gaps(const Model& model, Data& data) {
  if (!model.contact_modes) return;
  ContactModeData& w = data.modes;
  const std::vector<ContactModeContact>& contacts = model.contact_modes->contacts;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const ContactModeContact& c = contacts[i];
    w.gap[i] = c.gap_position >= 0 && c.gap_position < data.phi.size() ? data.phi(c.gap_position) : 0.0;
    if (w.mode[i] == ContactMode::rolling) continue;
    for (int a = 0; a < 2; ++a) {
      if (c.roll_velocity[static_cast<std::size_t>(a)] < data.f.size())
        data.f(c.roll_velocity[static_cast<std::size_t>(a)]) = 0.0;
      if (c.roll[static_cast<std::size_t>(a)] < data.e.size()) data.e(c.roll[static_cast<std::size_t>(a)]) = 0.0;
    }
    if (c.spin >= 0 && c.spin < data.e.size()) data.e(c.spin) = 0.0;
    if (c.spin_velocity >= 0 && c.spin_velocity < data.f.size()) data.f(c.spin_velocity) = 0.0;
    if (w.mode[i] == ContactMode::free) {
      if (c.gap_position < data.phi.size()) data.phi(c.gap_position) = 0.0;
      if (c.gap_velocity < data.f.size()) data.f(c.gap_velocity) = 0.0;
      if (c.gap < data.e.size()) data.e(c.gap) = 0.0;
    }
  }
}

}  // namespace nhdyn
