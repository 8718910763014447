// The layout of a simulation's results, one row per output time, in this order:
//   t, the coordinates q (by name), their velocities (x'), accelerations (x''), reactions (R_x),
//   the constraint residuals — position level (residual_pos_<constraint>), velocity level
//   (residual_vel_<constraint>), acceleration level (residual_acc_<constraint>) — energy
//   (E = T + V, when the model defines one) and the energy balance (when the model has one,
//   docs/derivations/energy-balance.md): energy_function (h), power (P), work_forces,
//   work_reactions, work_time, work (W, their sum) and balance_error (h - h(t0) - W); then, for a
//   model with programs (docs/derivations/program-motion.md), the actuator forces (u_<program>)
//   and the programs' residuals at the three levels, named like the constraints'
//   (residual_pos_<program>, ...); for a multibody model with wheels or knife edges, their
//   contact forces NAME_Fx, NAME_Fy, NAME_Fz, NAME_N, NAME_Flong, NAME_Flat and contact_residual
//   (model/contact_forces.hpp, docs/multibody.md); last the derived outputs (model/output.hpp: a
//   multibody model's point and frame positions and velocities, then the file's [outputs], by name).
// Shared by the CSV writer and the plots so that both name the columns the same way.
#pragma once

#include <string>
#include <vector>

#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

struct ResultColumns {
  std::vector<std::string> all;          // every column, in order
  std::vector<std::string> coordinates;  // q
  std::vector<std::string> reactions;    // R
  std::vector<std::string> residuals;    // the three levels
  std::string energy;                    // empty when the model defines none
  std::vector<std::string> actuators;    // u, one per program (empty without programs)
  // The energy balance, when the model has one (docs/derivations/energy-balance.md): h, the power
  // P, the work of each agent and their sum W, and h - h(t0) - W. Empty otherwise.
  std::vector<std::string> energy_balance;
  // The contact forces and their check column (model/contact_forces.hpp); empty without contacts.
  std::vector<std::string> contact_forces;
  std::vector<std::string> outputs;      // the derived outputs, Model::outputs (empty without)
};

// Throws ModelError when a derived output is named like another column (naming where the output
// was written and the column), so that no run starts with two columns of one name.
ResultColumns make_result_columns(const Model& model);

// Fills `row` (sized to the column count; no allocation after the first call) from Data after
// compute_acceleration, compute_residuals, compute_energy and compute_outputs (and compute_program_residuals for a
// model with programs; with an energy balance, compute_power and the work and balance error that
// simulate sets).
void fill_result_row(const Model& model, const Data& data, std::vector<double>& row);

}  // namespace nhdyn
