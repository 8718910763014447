#include "nhdyn/io/results.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "nhdyn/analysis/residuals.hpp"
#include "nhdyn/core/error.hpp"

namespace nhdyn {

namespace {

// The derived outputs, last (model/output.hpp); an output may not take another column's name.
void add_output_columns(const Model& model, ResultColumns& c) {
  for (const DerivedOutput& o : model.outputs.list) {
    if (std::find(c.all.begin(), c.all.end(), o.name) != c.all.end())
      throw ModelError(fmt::format("{}output '{}' is named like the results' column '{}'; give it another name "
                                   "(the columns: docs/model-format.md, [outputs])",
                                   o.where.empty() ? "" : o.where + ": ", o.name, o.name));
    c.outputs.push_back(o.name);
    c.all.push_back(o.name);
  }
}

}  // namespace

ResultColumns make_result_columns(const Model& model) {
  ResultColumns c;
  c.all.push_back("t");
  for (const std::string& q : model.coordinates) c.coordinates.push_back(q);
  for (const std::string& q : model.coordinates) c.reactions.push_back("R_" + q);
  for (const Constraint& con : model.constraints)
    if (con.level == ConstraintLevel::position) c.residuals.push_back("residual_pos_" + con.name);
  for (const Constraint& con : model.constraints)
    if (con.level != ConstraintLevel::acceleration) c.residuals.push_back("residual_vel_" + con.name);
  for (const Constraint& con : model.constraints) c.residuals.push_back("residual_acc_" + con.name);
  c.all.insert(c.all.end(), c.coordinates.begin(), c.coordinates.end());
  for (const std::string& q : model.coordinates) c.all.push_back(q + "'");
  for (const std::string& q : model.coordinates) c.all.push_back(q + "''");
  c.all.insert(c.all.end(), c.reactions.begin(), c.reactions.end());
  c.all.insert(c.all.end(), c.residuals.begin(), c.residuals.end());
  if (model.evaluator && model.evaluator->has_energy()) {
    c.energy = "energy";
    c.all.push_back(c.energy);
  }
  if (model.evaluator && model.evaluator->has_energy_balance()) {
    c.energy_balance = {"energy_function", "power", "work_forces", "work_reactions", "work_time", "work",
                        "balance_error"};
    c.all.insert(c.all.end(), c.energy_balance.begin(), c.energy_balance.end());
  }
  // Program motion, after everything else so that a model without programs keeps its layout.
  std::vector<std::string> program_residuals;
  for (const ProgramConstraint& p : model.program_constraints) c.actuators.push_back("u_" + p.name);
  for (const ProgramConstraint& p : model.program_constraints)
    if (p.level == ConstraintLevel::position) program_residuals.push_back("residual_pos_" + p.name);
  for (const ProgramConstraint& p : model.program_constraints)
    if (p.level != ConstraintLevel::acceleration) program_residuals.push_back("residual_vel_" + p.name);
  for (const ProgramConstraint& p : model.program_constraints) program_residuals.push_back("residual_acc_" + p.name);
  c.all.insert(c.all.end(), c.actuators.begin(), c.actuators.end());
  c.all.insert(c.all.end(), program_residuals.begin(), program_residuals.end());
  c.residuals.insert(c.residuals.end(), program_residuals.begin(), program_residuals.end());
  c.contact_forces = contact_force_columns(model);
  c.all.insert(c.all.end(), c.contact_forces.begin(), c.contact_forces.end());
  add_output_columns(model, c);
  return c;
}

void fill_result_row(const Model& model, const Data& data, std::vector<double>& row) {
  row.clear();
  row.push_back(data.t);
  for (int i = 0; i < model.n(); ++i) row.push_back(data.q(i));
  for (int i = 0; i < model.n(); ++i) row.push_back(data.v(i));
  for (int i = 0; i < model.n(); ++i) row.push_back(data.qdd(i));
  for (int i = 0; i < model.n(); ++i) row.push_back(data.R(i));
  for (Eigen::Index i = 0; i < data.phi.size(); ++i) row.push_back(data.phi(i));
  for (Eigen::Index i = 0; i < data.f.size(); ++i) row.push_back(data.f(i));
  for (Eigen::Index i = 0; i < data.e.size(); ++i) row.push_back(data.e(i));
  if (model.evaluator->has_energy()) row.push_back(data.energy);
  if (model.evaluator->has_energy_balance()) {
    double balance[kEnergyBalanceColumns];
    fill_energy_balance(data, balance);
    row.insert(row.end(), balance, balance + kEnergyBalanceColumns);
  }
  if (model.m() > 0) {
    const ProgramMotionData& w = data.motion;
    for (Eigen::Index i = 0; i < w.u.size(); ++i) row.push_back(w.u(i));
    for (Eigen::Index i = 0; i < w.phi.size(); ++i) row.push_back(w.phi(i));
    for (Eigen::Index i = 0; i < w.f.size(); ++i) row.push_back(w.f(i));
    for (Eigen::Index i = 0; i < w.e.size(); ++i) row.push_back(w.e(i));
  }
  append_contact_force_values(model, data, row);
  const Vector& outputs = data.outputs.values;
  row.insert(row.end(), outputs.data(), outputs.data() + outputs.size());
}

}  // namespace nhdyn
