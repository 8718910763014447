// Contacts that can slip, lift off and land (docs/contact-modes.md; derived in
// docs/derivations/contact-modes.md): the numeric description of each [[contacts]] entry that has
// `friction` or `unilateral`, frozen at load (ContactModeModel), and the state of its mode during
// a run with the per-contact results (ContactModeData, in Data). A contact is in one of three
// modes: rolling (its gap and no-slip rows are constraints, as without modes), sliding (the gap
// row stays, the no-slip rows are dropped and Coulomb's friction -mu_k N e_s acts along them) and
// free (all its rows dropped). The solve of each mode is formulation/contact_modes.hpp; the
// switches between them are analysis/detail/contact_switches.hpp.
//
//     symbolic/contact_modes (compile_contact_modes) -> Model::contact_modes
//         -> make_data (ContactModeData) -> compute_mode_acceleration -> CSV columns NAME_mode ...
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/LU>
#include <Eigen/QR>

#include "nhdyn/core/types.hpp"
#include "nhdyn/model/tape.hpp"

namespace nhdyn {

struct Model;
struct Data;

// The column NAME_mode holds these numbers.
enum class ContactMode : int { rolling = 0, sliding = 1, free = 2 };
const char* contact_mode_name(ContactMode mode);  // "rolling", "sliding", "free"

// One contact with modes: the rows of b (constraint indices) its modes keep or drop, and where its
// residuals are among phi and f (the position and velocity residuals of analysis/residuals.hpp).
struct ContactModeContact {
  std::string name;
  std::string where;          // file:line of its [[contacts]] entry
  int gap = -1;               // row of NAME_contact (position level): its residual is the gap
  int gap_position = -1;      // its index among the position residuals
  int gap_velocity = -1;      // its index among the velocity residuals (the gap's rate)
  std::array<int, 2> roll{-1, -1};           // rows of NAME_roll1, NAME_roll2
  std::array<int, 2> roll_velocity{-1, -1};  // their indices among the velocity residuals (the slip)
  int spin = -1;              // row of NAME_spin (rubber rolling), dropped while sliding; -1 if none
  int spin_velocity = -1;     // its index among the velocity residuals
  bool friction = false;      // a friction limit is given: the contact may slide
  bool unilateral = false;    // the ground only pushes: the contact may lift off
  int initial = -1;           // ContactMode at t0 as given by `mode`, or -1 (chosen from the state)
};

// Frozen at load (symbolic/contact_modes.hpp, compile_contact_modes).
struct ContactModeModel {
  std::vector<ContactModeContact> contacts;
  // Per contact, kOutputs values in (t, q): mu_s, mu_k, e (restitution), n (3, world, unit), t1 (3),
  // t2 (3) (the tangent directions of the no-slip rows, world, not necessarily unit: row a is
  // t_a . (v_P - v_ground)). Parametric: bound by make_contact_mode_data.
  Tape tape;
  static constexpr int kOutputs = 12;
};

// The mode of every contact and the results of the last solve (compute_mode_acceleration), with
// the workspace of that solve. Sized by make_contact_mode_data (inactive for a model without
// contact modes); the mode changes only at a switch (analysis/detail/contact_switches.hpp), where the
// workspace may be resized (the only allocation).
struct ContactModeData {
  bool active = false;
  PreparedTape tape;            // ContactModeModel::tape bound to the parameter values, prepared
  std::vector<double> registers, outputs;
  std::vector<ContactMode> mode;   // per contact
  std::vector<ContactMode> solved;  // the modes of the last compute_mode_acceleration that succeeded
  // While every contact rolls, q'' is the ordinary Do Sanh solve and the contact values below
  // (N, F_t, the slips) are wanted only where the switches are watched and rows written, not at
  // every stage of a step: an integrator's right-hand side sets defer_forces around its solve, and
  // forces_current says whether they belong to the last solve (compute_mode_forces completes them).
  bool defer_forces = false;
  // A contact whose sliding solve takes its carried direction whatever its slip (the trials of its
  // onset direction, analysis/detail/contact_switches.cpp), or -1.
  int onset_trial = -1;
  bool forces_current = false;
  // Per contact, the slip direction carried through the sliding mode (unit, in the basis of the
  // unit tangents): e_s = s / |s| oriented like it, and the friction's direction where |s| is at
  // round-off (docs/derivations/contact-modes.md sections 5 and 6). Set at every switch into
  // sliding and after every accepted step.
  std::vector<std::array<double, 2>> direction;
  // Per contact, the sign of N carried through the sliding mode (+1, or -1 while a bilateral
  // contact's ground pulls): Coulomb's friction is -mu_k |N| e_s, so the sliding reaction is
  // N (n - mu_k sign(N) e_s) (docs/derivations/contact-modes.md 3.6). Flipped where N crosses 0.
  std::vector<double> normal_sign;
  // --- results of compute_mode_acceleration, per contact ---
  std::vector<double> mu_s, mu_k, restitution;
  std::vector<double> normal_force;        // N [N]: positive when the ground pushes (0 when free)
  std::vector<std::array<double, 2>> friction;  // F_t in the unit tangent basis [N]
  std::vector<std::array<double, 2>> slip;      // s in the unit tangent basis [m/s]
  std::vector<std::array<double, 3>> slip_world;  // s in world components
  std::vector<std::array<double, 2>> sliding_direction;  // e_s used by the solve (sliding)
  std::vector<double> friction_power;      // -mu_k |N| |s| [W] (sliding; 0 otherwise)
  // Sliding: the effective normal inverse mass w_eff = n^T Lambda (n - mu_k e_s) and its
  // frictionless part Lambda_nn [1/kg] (docs/derivations/contact-modes.md (S7), (S9), (S10));
  // w_eff <= 0 is Painleve's paradox. 0 in the other modes.
  std::vector<double> w_eff, lambda_nn;
  double power_friction = 0.0;             // the sum over the contacts
  std::vector<double> gap;                 // the gap [m] (record_contact_gaps; 0 while touching)
  // --- workspace (sized for the current modes) ---
  std::vector<double> velocity_residuals;  // the model's velocity residuals (the slips are among them)
  std::vector<int> kept;                   // rows of b kept as constraints
  std::vector<int> gap_column;             // per contact: its gap row's column in reaction_rows, or -1
  std::vector<std::array<double, 2>> tangent_length;  // per contact: |t1|, |t2| of the tape's outputs
  Matrix reaction_rows;                    // n x r, the reaction directions B~^T (columns)
  Matrix M;                                // n x n, [D A; b_kept]
  Vector rhs, multipliers;                 // n; r
  Vector row_scale;                        // n, the powers of two the rows of M and rhs were scaled by (1: none)
  Vector coordinate_scale;                 // n, S: the coordinates' scales, q'' = S y (formulation/contact_modes.cpp)
  Vector probe, response, coefficients;    // n, n, r: the solves of (S9) and (S10)
  Eigen::ColPivHouseholderQR<Matrix> qr;   // of reaction_rows
  Eigen::PartialPivLU<Matrix> lu;          // of M
  // The contact and time of a failed solve (a singular system: Painleve), for the message.
  int failed_contact = -1;
};

ContactModeData make_contact_mode_data(const Model& model);

// The result columns of the contacts with modes: per contact NAME_mode, NAME_slip_speed,
// NAME_slip_x, NAME_slip_y, NAME_slip_z, NAME_gap, then work_friction (the friction's work since
// t0) and impact_loss (the energy the touchdowns took since t0, analysis/detail/contact_switches.hpp). Empty for a model without contact modes. Appended after the contact forces
// (contact_forces.hpp).
std::vector<std::string> contact_mode_columns(const Model& model);
// Appends their values (after compute_mode_acceleration and record_contact_gaps); `work_friction`
// is Data::work_friction.
void append_contact_mode_values(const Model& model, const Data& data, std::vector<double>& row);
// The same from a Data made for a model with contact modes (nothing for another).
void append_contact_mode_values(const Data& data, std::vector<double>& row);

// After compute_residuals: keeps each contact's gap (its position residual) in data.modes.gap, and
// sets to 0 the residuals of the rows its mode drops (the slip of a sliding contact, the gap and
// slip of a free one are motion, not constraint error; they have their own columns).
void record_contact_gaps(const Model& model, Data& data);

// The constraints that hold in every mode of the model's contacts: s less the rows some mode can
// drop (free drops a unilateral contact's rows, sliding a contact with friction's no-slip and spin
// rows). A model may have s >= n when this is below n (docs/contact-modes.md, "More contacts than
// freedom"): the solve then refuses a set of modes that keeps n rows or more.
int constraints_always_held(const Model& model);

// Whether the constraint called `constraint` is a row that its contact's current mode drops.
bool contact_mode_drops(const Model& model, const Data& data, const std::string& constraint);
// Whether contact c in `mode` drops the row `row` of b (a constraint index): sliding drops its
// no-slip rows and its spin row, free also its gap; rolling none. The one rule the mode solve, the
// residuals and the constraint watch share.
bool contact_mode_drops_row(const ContactModeContact& c, ContactMode mode, int row);

}  // namespace nhdyn
