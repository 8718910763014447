#include "nhdyn/formulation/contact_modes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "nhdyn/formulation/detail/row_scaling.hpp"
#include "nhdyn/formulation/sanh.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

// The slip below which its direction is taken from the carried one (the onset direction, or the
// direction of the last step): the slip a rolling contact leaves is the integration error of its
// velocity constraint, not a direction (docs/derivations/contact-modes.md section 5, "In the
// sliding mode near s = 0").
double slip_floor(const Data& data) { return 1e-10 * (1.0 + data.v.lpNorm<Eigen::Infinity>()); }

// Per contact: mu, the unit tangents' lengths, the slip, and for a sliding contact e_s.
void contact_kinematics(const ContactModeModel& cm, Data& data, std::vector<std::array<double, 2>>& lengths) {
  ContactModeData& w = data.modes;
  const double floor = slip_floor(data);
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const ContactModeContact& c = cm.contacts[i];
    const double* o = w.outputs.data() + ContactModeModel::kOutputs * i;
    w.mu_s[i] = o[0];
    w.mu_k[i] = o[1];
    w.restitution[i] = o[2];
    const double* t[2] = {o + 6, o + 9};
    std::array<double, 3> world{0.0, 0.0, 0.0};
    for (std::size_t a = 0; a < 2; ++a) {
      const double length = std::sqrt(t[a][0] * t[a][0] + t[a][1] * t[a][1] + t[a][2] * t[a][2]);
      lengths[i][a] = length > 0.0 ? length : 1.0;
      w.slip[i][a] = w.velocity_residuals[static_cast<std::size_t>(c.roll_velocity[a])] / lengths[i][a];
      for (std::size_t k = 0; k < 3; ++k) world[k] += w.slip[i][a] * t[a][k] / lengths[i][a];
    }
    w.slip_world[i] = world;
    const double speed = std::hypot(w.slip[i][0], w.slip[i][1]);
    std::array<double, 2> e = w.direction[i];
    if (speed > floor && static_cast<int>(i) != w.onset_trial) {
      e = {w.slip[i][0] / speed, w.slip[i][1] / speed};
      // Continued through zero: oriented like the carried direction (section 6), so that the
      // friction stays smooth within the step that holds the stick and s . e_s falls through 0.
      if (e[0] * w.direction[i][0] + e[1] * w.direction[i][1] < 0.0) e = {-e[0], -e[1]};
    }
    w.sliding_direction[i] = e;
  }
}

Status fail(Data& data, const ContactModeModel& cm, int contact, const std::string& why) {
  data.modes.failed_contact = contact;
  record_failure(data, Status::singular_system, "");
  data.failed_quantity = contact >= 0 ? fmt::format("contact '{}': {}", cm.contacts[static_cast<std::size_t>(contact)].name, why)
                                      : why;
  return Status::singular_system;
}

// The coordinates' scales S (powers of two, w.coordinate_scale) in which the solve works when
// their inertias A_jj are more than kRowScaleRatio apart; 1 otherwise. A body 1e-6 m across has
// A_jj = m for its position and about m r^2 = 1e-12 m for its angles: the QR of B~^T, and with it
// D, mixes these directions in whatever units they have, and the rows D A then carry entries 1e12
// apart, below what double precision keeps beside each other (the stacked matrix was judged
// singular, "Painleve", for a sliding tippe top 40 nm across). In the coordinates q = S q~ with
// S_jj about 1 / sqrt(A_jj), every coordinate has an inertia of order 1 (the kinetic energy's own
// metric, whatever the units): B~^T becomes S B~^T and D = D~ S, with D~ from the QR of S B~^T.
void coordinate_scales(const Data& data, ContactModeData& w) {
  w.coordinate_scale.setOnes();
  scale_rows_by_powers_of_two(
      static_cast<int>(w.coordinate_scale.size()), [&](int j) { return std::abs(data.A(j, j)); },
      [&](int j, int exponent) { w.coordinate_scale(j) = std::ldexp(1.0, -exponent / 2); });
}

// The coefficients y of f (n) on the columns of B~^T (r), f = B~^T y, by the QR of S B~^T (least
// squares; exact when f lies in their span): S f = (S B~^T) y. Overwrites f.
void reaction_coefficients(ContactModeData& w, int r, Vector& f, Vector& y) {
  f.array() *= w.coordinate_scale.array();
  f.applyOnTheLeft(w.qr.householderQ().adjoint());
  w.qr.matrixQR().topLeftCorner(r, r).triangularView<Eigen::Upper>().solveInPlace(f.head(r));
  for (int j = 0; j < r; ++j) y(w.qr.colsPermutation().indices()(j)) = f(j);
}

// (S9), (S10): w_eff and Lambda_nn of the sliding contact whose normal row is column j of B~^T
// (row k + j of M), from the factorizations of M and B~^T already made: two more solves.
void effective_inverse_mass(const Model& model, Data& data, int contact_gap_row, int j, int k, int r, double& w_eff,
                            double& lambda_nn) {
  ContactModeData& w = data.modes;
  const int n = model.n();
  // The probes are right-hand sides of M: they take its rows' scaling (w.row_scale), and the
  // responses its columns' (the coordinates' scales S: q'' = S y).
  w.probe.setZero();
  w.probe(k + j) = w.row_scale(k + j);
  w.response.noalias() = w.lu.solve(w.probe);
  w.response.array() *= w.coordinate_scale.array();
  data.tmp_n.noalias() = data.A * w.response;
  reaction_coefficients(w, r, data.tmp_n, w.coefficients);
  const double inverse = w.coefficients(j);  // 1 / w_eff
  w.probe.head(k).noalias() = data.Q_full.rightCols(k).transpose() * data.b.row(contact_gap_row).transpose();
  w.probe.tail(n - k).setZero();
  w.probe.head(k).array() *= w.row_scale.head(k).array();
  w.response.noalias() = w.lu.solve(w.probe);
  w.response.array() *= w.coordinate_scale.array();
  data.tmp_n.noalias() = data.A * w.response;
  data.tmp_n -= data.b.row(contact_gap_row).transpose();
  reaction_coefficients(w, r, data.tmp_n, w.coefficients);
  if (!(std::abs(inverse) > 0.0)) {
    // The sliding column does not move the normal at all: no finite w_eff, and so no paradox.
    w_eff = std::numeric_limits<double>::infinity();
    lambda_nn = 0.0;
    return;
  }
  w_eff = 1.0 / inverse;
  lambda_nn = -w.coefficients(j) / inverse;
}

// Rows of M in different units (the masses' --set m=1e-100) scaled exactly, with rhs, as in every
// solve of [D A; b] (row_scaling.hpp), so that the conditioning test is about the matrix and not its
// units; the factors stay in w.row_scale for the probes of effective_inverse_mass.
void scale_rows(ContactModeData& w) {
  w.row_scale.setOnes();
  scale_rows_by_powers_of_two(
      static_cast<int>(w.M.rows()), [&](int i) { return w.M.row(i).cwiseAbs().maxCoeff(); },
      [&](int i, int exponent) {
        w.row_scale(i) = std::ldexp(1.0, -exponent);
        w.M.row(i) *= w.row_scale(i);
        w.rhs(i) *= w.row_scale(i);
      });
}

// (S4) with D the last n - r columns of the orthogonal factor of B~^T (D B~^T = 0), the kept rows
// in w.reaction_rows: q'' and R. With no row kept (a free body and nothing else) D is the
// identity: A q'' = Q + G. In scaled coordinates (coordinate_scales: w.reaction_rows holds
// S B~^T), D = D~ S and the unknown is y = S^-1 q'': [D A S; b S] y = [D (Q + G); -b0].
Status mode_acceleration(const Model& model, Data& data, int r) {
  const ContactModeModel& cm = *model.contact_modes;
  ContactModeData& w = data.modes;
  const int n = model.n();
  const int k = n - r;
  data.Q_full.resize(n, n);
  data.hh_work.resize(n);
  if (r == 0) data.Q_full.setIdentity();
  else w.qr.compute(w.reaction_rows);
  if (r > 0 && w.qr.rank() < r) {
    for (std::size_t i = 0; i < cm.contacts.size(); ++i)
      if (w.mode[i] == ContactMode::sliding)
        return fail(data, cm, static_cast<int>(i),
                    "the reaction directions of the sliding contact are dependent (its friction direction lies in "
                    "the span of the other constraints)");
    return record_failure(data, Status::dependent_constraints, "b");
  }
  if (r > 0) w.qr.householderQ().evalTo(data.Q_full, data.hh_work);
  // D^T = S D~^T: the rows of the orthogonal factor scaled in place (Q_full is this solve's own).
  data.Q_full.array().colwise() *= w.coordinate_scale.array();
  w.M.topRows(k).noalias() = data.Q_full.rightCols(k).transpose() * data.A;
  w.rhs.head(k).noalias() = data.Q_full.rightCols(k).transpose() * (data.Q + data.G);
  for (int j = 0; j < r; ++j) {
    const int row = w.kept[static_cast<std::size_t>(j)];
    w.M.row(k + j) = data.b.row(row);
    w.rhs(k + j) = -data.b0(row);
  }
  w.M.array().rowwise() *= w.coordinate_scale.transpose().array();
  scale_rows(w);
  w.lu.compute(w.M);
  const double rcond = w.lu.rcond();
  if (!(rcond > 1e-14)) {
    for (std::size_t i = 0; i < cm.contacts.size(); ++i)
      if (w.mode[i] == ContactMode::sliding)
        return fail(data, cm, static_cast<int>(i),
                    fmt::format("the equations of its sliding are singular (Painleve's paradox: with mu_k = {:.6g} "
                                "its normal force no longer decides its normal acceleration, "
                                "docs/contact-modes.md); lower the friction coefficient",
                                w.mu_k[i]));
    return record_failure(data, Status::singular_system, "stacked matrix [D A; b] of the contact modes");
  }
  data.qdd = w.lu.solve(w.rhs);
  data.qdd.array() *= w.coordinate_scale.array();
  data.R.noalias() = data.A * data.qdd;
  data.R -= data.Q;
  data.R -= data.G;
  return Status::ok;
}

// Defined below the entry points it serves.
Status solve_modes(const Model& model, Data& data, bool rolling, bool forces_only = false);

}  // namespace

Status compute_mode_acceleration(const Model& model, Data& data) {
  if (data.stage < Stage::terms)
    throw std::logic_error("compute_mode_acceleration: call compute_terms first for the current state");
  if (data.sparse || !model.contact_modes)
    throw std::logic_error("compute_mode_acceleration: contact modes are solved on the dense path of a model that has them");
  ContactModeData& w = data.modes;
  w.failed_contact = -1;
  w.forces_current = false;
  const bool rolling = std::all_of(w.mode.begin(), w.mode.end(), [](ContactMode m) { return m == ContactMode::rolling; });
  if (rolling && w.defer_forces && model.s() > 0 && model.s() < model.n()) {
    // Every contact rolling: the ordinary Do Sanh form with D from b (sanh.hpp), as cheap as the
    // model without modes; no friction works.
    const Status status = compute_sanh_acceleration(model, data, Complement::qr);
    if (status != Status::ok) return status;
    data.power_friction = w.power_friction = 0.0;
    std::copy(w.mode.begin(), w.mode.end(), w.solved.begin());
    return Status::ok;
  }
  return solve_modes(model, data, rolling);
}

Status compute_mode_forces(const Model& model, Data& data) {
  ContactModeData& w = data.modes;
  if (w.forces_current) return Status::ok;
  if (data.stage < Stage::acceleration || w.solved != w.mode)
    throw std::logic_error("compute_mode_forces: call compute_mode_acceleration first for the current state and modes");
  return solve_modes(model, data, true, true);
}

namespace {

// The contact values and, unless `forces_only` (q'' and R already solved with every contact
// rolling), the solve itself.
Status solve_modes(const Model& model, Data& data, bool rolling, bool forces_only) {
  const ContactModeModel& cm = *model.contact_modes;
  ContactModeData& w = data.modes;
  const int n = model.n();
  const int s = model.s();
  w.tape.run(data.t, data.q.data(), data.v.data(), w.registers.data(), w.outputs.data());
  if (!w.velocity_residuals.empty())
    model.evaluator->velocity_residual(data.t, data.q.data(), data.v.data(), data.scratch.data(),
                                       w.velocity_residuals.data());
  std::vector<std::array<double, 2>>& lengths = w.tangent_length;
  contact_kinematics(cm, data, lengths);

  // The kept rows, then the reaction directions: a sliding contact's gap row gets -mu_k w_s.
  w.kept.clear();
  for (int row = 0; row < s; ++row) {
    bool keep = true;
    for (std::size_t i = 0; i < cm.contacts.size() && keep; ++i) keep = !contact_mode_drops_row(cm.contacts[i], w.mode[i], row);
    if (keep) w.kept.push_back(row);
  }
  const int r = static_cast<int>(w.kept.size());
  if (r >= n) {
    // Contacts held together that leave the body no freedom (s >= n, constraints_always_held):
    // the Do Sanh form has no k = n - r > 0 rows of D to give the motion.
    std::string touching;
    for (std::size_t i = 0; i < cm.contacts.size(); ++i)
      if (w.mode[i] != ContactMode::free) touching += (touching.empty() ? "'" : ", '") + cm.contacts[i].name + "'";
    return fail(data, cm, -1,
                fmt::format("the contacts {} held together keep {} constraint rows on {} coordinates, which leaves "
                            "the Do Sanh form no row of D (it needs fewer independent rows than coordinates): the body "
                            "is wedged, or held by dependent rows (docs/contact-modes.md, \"More contacts than "
                            "freedom\"); start one of them free (a unilateral one, mode = \"free\"), or remove one",
                            touching, r, n));
  }
  if (w.reaction_rows.cols() != r) {
    w.reaction_rows.resize(n, r);
    w.multipliers.resize(r);
    w.qr = Eigen::ColPivHouseholderQR<Matrix>(n, r);
    w.coefficients.resize(r);
  }
  for (int j = 0; j < r; ++j) w.reaction_rows.col(j) = data.b.row(w.kept[static_cast<std::size_t>(j)]).transpose();
  std::vector<int>& gap_column = w.gap_column;
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const ContactModeContact& c = cm.contacts[i];
    gap_column[i] = -1;
    for (int j = 0; j < r; ++j)
      if (w.kept[static_cast<std::size_t>(j)] == c.gap) gap_column[i] = j;
    if (w.mode[i] != ContactMode::sliding || gap_column[i] < 0) continue;
    for (std::size_t a = 0; a < 2; ++a)
      w.reaction_rows.col(gap_column[i]) -=
          (w.mu_k[i] * w.normal_sign[i] * w.sliding_direction[i][a] / lengths[i][a]) * data.b.row(c.roll[a]).transpose();
  }
  coordinate_scales(data, w);
  w.reaction_rows.array().colwise() *= w.coordinate_scale.array();

  // Every contact rolling: the ordinary Do Sanh form with D from b (sanh.hpp), as cheap as the
  // model without modes; B~ = b, whose QR below gives only the multipliers.
  const int k = n - r;
  if (rolling && r > 0) {
    if (!forces_only) {
      const Status status = compute_sanh_acceleration(model, data, Complement::qr);
      if (status != Status::ok) return status;
    }
    w.qr.compute(w.reaction_rows);
    if (w.qr.rank() < r) return record_failure(data, Status::dependent_constraints, "b");
  } else {
    const Status status = mode_acceleration(model, data, r);
    if (status != Status::ok) return status;
  }

  // The multipliers, R = B~^T lambda (least squares through the same QR): N and F_t.
  if (r > 0) {
    data.tmp_n = data.R;
    reaction_coefficients(w, r, data.tmp_n, w.multipliers);
  }
  w.power_friction = 0.0;
  for (std::size_t i = 0; i < cm.contacts.size(); ++i) {
    const ContactModeContact& c = cm.contacts[i];
    w.friction_power[i] = 0.0;
    w.w_eff[i] = w.lambda_nn[i] = 0.0;
    if (w.mode[i] == ContactMode::free || gap_column[i] < 0) {
      w.normal_force[i] = 0.0;
      w.friction[i] = {0.0, 0.0};
      continue;
    }
    const double N = w.multipliers(gap_column[i]);
    w.normal_force[i] = N;
    if (w.mode[i] == ContactMode::sliding) {
      for (std::size_t a = 0; a < 2; ++a)
        w.friction[i][a] = -w.mu_k[i] * w.normal_sign[i] * N * w.sliding_direction[i][a];
      // -mu_k |N| |s| = F_t . s, the dissipation (section 8).
      w.friction_power[i] = w.friction[i][0] * w.slip[i][0] + w.friction[i][1] * w.slip[i][1];
      w.power_friction += w.friction_power[i];
      effective_inverse_mass(model, data, c.gap, gap_column[i], k, r, w.w_eff[i], w.lambda_nn[i]);
      continue;
    }
    for (std::size_t a = 0; a < 2; ++a) {
      w.friction[i][a] = 0.0;
      for (int j = 0; j < r; ++j)
        if (w.kept[static_cast<std::size_t>(j)] == c.roll[a]) w.friction[i][a] = w.multipliers(j) * lengths[i][a];
    }
  }
  data.power_friction = w.power_friction;
  std::copy(w.mode.begin(), w.mode.end(), w.solved.begin());
  w.forces_current = true;
  return Status::ok;
}

}  // namespace
}  // namespace nhdyn
