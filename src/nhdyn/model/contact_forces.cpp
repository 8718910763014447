#include "nhdyn/model/contact_forces.hpp"

#include <fmt/format.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "nhdyn/model/contact_modes.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/detail/residual_round_off.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// A stacked system whose least-squares residual is above this, relative to its right side, is not
// consistent: a balance the contacts cannot meet (round-off is near 1e-15 at the check's state).
constexpr double kConsistent = 1e-8;
// A null vector of M with a component above this (relative) along an output leaves it undetermined.
constexpr double kDetermined = 1e-8;
// A row of the contact-force system at most this part of the largest is round-off (scaled_null_space).
constexpr double kRoundOffRow = 1e-12;

// A state counts as on the constraints when every position and velocity residual is at most this,
// or within the round-off of its terms where that is larger.
constexpr double kOnConstraints = 1e-11;

// The largest |residual| of the position-level (velocity = false) or the position- and
// velocity-level constraints at (t, q, v), into `r`; infinity when one is not finite. The
// evaluator's default leaves `r` as it finds it, zero: a model with no residuals is on them.
double largest_residual(const Model& model, double t, const Vector& q, const Vector& v, bool velocity,
                        std::vector<double>& scratch, Vector& r) {
  r.setZero();
  if (r.size() == 0) return 0.0;
  if (velocity) model.evaluator->velocity_residual(t, q.data(), v.data(), scratch.data(), r.data());
  else model.evaluator->position_residual(t, q.data(), scratch.data(), r.data());
  return r.allFinite() ? r.cwiseAbs().maxCoeff() : std::numeric_limits<double>::infinity();
}

// Moves (q, v) onto the position- and velocity-level constraints (docs/derivations/contact-forces.md
// step 5: the check's identities hold on the constraints; off them a model whose contact point is
// held by coordinates of its own, an implicit shape's, does not balance). Gauss-Newton with the
// least-norm step through the constraints' rows of b (their gradients), halved until the residual
// falls; then the velocities, linear in v, by the least-norm change. The norm is the inertia's,
// sum_j A_jj dq_j^2 (A at the first state), as --fix-initial's: in the coordinates' own units a
// disk 400 mm across, 50 mm above the floor, had its gap closed by turning it (the gap's gradient
// along its tilt is r sin(theta) = 60 against 1 along its height), a step too long for the line
// search, and the check gave up. False when it does not converge. Cold path: allocates.
bool onto_constraints(const Model& model, double t, Vector& q, Vector& v, std::vector<double>& scratch) {
  const int n = model.n(), s = model.s();
  std::vector<int> position_rows, velocity_rows;
  for (int i = 0; i < s; ++i) {
    const ConstraintLevel level = model.constraints[static_cast<std::size_t>(i)].level;
    if (level == ConstraintLevel::position) position_rows.push_back(i);
    if (level != ConstraintLevel::acceleration) velocity_rows.push_back(i);
  }
  Matrix A(n, n), b(s, n);
  Vector Q(n), G(n), b0(s);
  const auto rows_of_b = [&](const std::vector<int>& rows) {
    model.evaluator->terms(t, q.data(), v.data(), scratch.data(), TermsOut{A.data(), Q.data(), G.data(), b.data(), b0.data()});
    Matrix J(static_cast<Eigen::Index>(rows.size()), n);
    for (std::size_t k = 0; k < rows.size(); ++k) J.row(static_cast<Eigen::Index>(k)) = b.row(rows[k]);
    return J;
  };
  // W = diag(1 / sqrt(A_jj)): the least-norm step of J W in the inertia's norm, then dq = W dz
  // (1 where A_jj is not positive: a coordinate without inertia of its own).
  rows_of_b(position_rows);
  Vector weight = Vector::Ones(n);
  for (int j = 0; j < n; ++j)
    if (const double a = A(j, j); a > 0.0 && std::isfinite(a)) weight(j) = 1.0 / std::sqrt(a);
  const auto least_norm = [&](const Matrix& J, const Vector& r) -> Vector {
    const Matrix JW = J * weight.asDiagonal();
    return weight.asDiagonal() * Eigen::CompleteOrthogonalDecomposition<Matrix>(JW).solve(r);
  };
  // Whether each residual r(k) of `rows` is within kOnConstraints or the round-off of its terms
  // (residual_round_off.hpp) at the state of the last rows_of_b: a ball 1000 km across has its
  // gap at 1e-10 from rounding alone.
  const auto on = [&](const std::vector<int>& rows, const Vector& x, const Vector& r, bool velocity) {
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const Eigen::Index i = static_cast<Eigen::Index>(k);
      const double value = std::abs(r(i));
      if (!(value <= kOnConstraints) && !(value <= residual_round_off(b.row(rows[k]), x, n, r(i), velocity)))
        return false;
    }
    return true;
  };
  Vector phi(static_cast<Eigen::Index>(position_rows.size())), trial_phi = phi;
  double worst = largest_residual(model, t, q, v, false, scratch, phi);
  for (int iteration = 0; iteration < 40 && std::isfinite(worst); ++iteration) {
    const Matrix J = rows_of_b(position_rows);
    if (on(position_rows, q, phi, false)) break;
    const Vector step = least_norm(J, -phi);
    if (!step.allFinite()) return false;
    bool better = false;
    for (double scale = 1.0; scale > 1e-3 && !better; scale *= 0.5) {
      const Vector trial = q + scale * step;
      const double w = largest_residual(model, t, trial, v, false, scratch, trial_phi);
      if (w < worst) {
        q = trial;
        phi = trial_phi;
        worst = w;
        better = true;
      }
    }
    if (!better) break;
  }
  rows_of_b(position_rows);
  if (!(std::isfinite(worst) && on(position_rows, q, phi, false))) return false;
  Vector f(static_cast<Eigen::Index>(velocity_rows.size()));
  worst = largest_residual(model, t, q, v, true, scratch, f);
  for (int iteration = 0; iteration < 3 && std::isfinite(worst); ++iteration) {
    const Matrix J = rows_of_b(velocity_rows);
    if (on(velocity_rows, v, f, true)) break;
    v += least_norm(J, -f);
    worst = largest_residual(model, t, q, v, true, scratch, f);
  }
  rows_of_b(velocity_rows);
  return std::isfinite(worst) && on(velocity_rows, v, f, true) && q.allFinite() && v.allFinite();
}

// The ideal-constraint dynamics: [A b^T; b 0] [q''; -lambda] = [Q + G; -b0], R = A q'' - Q - G.
// A and Q + G carry the masses and b does not: with the upper rows divided by mu, a power of two
// near the largest |A|, and lambda by the same mu, every block is of order one whatever the
// masses (`--set m=1e-100` made A's pivots look like round-off beside b's). Exact: q'' is the same.
Vector ideal_acceleration(const Matrix& A, const Vector& h, const Matrix& b, const Vector& b0) {
  const auto n = A.rows(), s = b.rows();
  const double largest_A = A.size() > 0 ? A.cwiseAbs().maxCoeff() : 0.0;
  int mass_exponent = 0;
  if (largest_A > 0.0 && std::isfinite(largest_A)) std::frexp(largest_A, &mass_exponent);
  const auto unit = [&](double x) { return std::ldexp(x, -mass_exponent); };
  Matrix K = Matrix::Zero(n + s, n + s);
  K.topLeftCorner(n, n) = A.unaryExpr(unit);
  K.topRightCorner(n, s) = b.transpose();
  K.bottomLeftCorner(s, n) = b;
  Vector k(n + s);
  k.head(n) = h.unaryExpr(unit);
  k.tail(s) = -b0;
  // Then rows and columns together by powers of two (a few passes of Ruiz's equilibration, which
  // keeps K symmetric): b's rows hold lengths (a ball's moment arm r) beside ones, and a ball
  // 1e5 m across spread K's entries over 14 decades, where the LU took pivots for round-off and
  // dropped the constraints' multipliers (R = 0). Powers of two: the scaling itself rounds nothing.
  Vector d = Vector::Ones(n + s);
  for (int pass = 0; pass < 4; ++pass)
    for (Eigen::Index i = 0; i < n + s; ++i) {
      const double row = K.row(i).cwiseAbs().maxCoeff();
      if (!(row > 0.0) || !std::isfinite(row)) continue;
      int exponent = 0;
      std::frexp(row, &exponent);
      const int half = -exponent / 2;
      d(i) = std::ldexp(d(i), half);
      K.row(i) = K.row(i).unaryExpr([&](double x) { return std::ldexp(x, half); });
      K.col(i) = K.col(i).unaryExpr([&](double x) { return std::ldexp(x, half); });
    }
  const Vector y = K.fullPivLu().solve(k.cwiseProduct(d));
  return y.cwiseProduct(d).head(n);
}

// M and rhs from the tape's outputs, q'' and R (docs/derivations/contact-forces.md step 6).
void assemble(const ContactForceModel& c, const double* o, const double* qdd, const double* R, Matrix& M,
              Vector& rhs) {
  const int n = c.n;
  M.setZero();
  rhs.setZero();
  for (int u = 0; u < c.unknowns; ++u) {
    const double* column = o + c.unknown_offset(u);
    for (int j = 0; j < n; ++j) M(j, u) = column[j];
    const int s = c.unknown_system[static_cast<std::size_t>(u)];
    if (!c.balance_rows[static_cast<std::size_t>(s)]) continue;
    for (int r = 0; r < 6; ++r) M(n + 6 * s + r, u) = column[n + r];
  }
  for (int h = 0; h < c.hand_constraints; ++h) {
    const double* row = o + c.hand_offset(h);
    for (int j = 0; j < n; ++j) M(j, c.unknowns + h) = row[j];
  }
  for (int j = 0; j < n; ++j) rhs(j) = R[j];
  for (int s = 0; s < c.systems; ++s) {
    if (!c.balance_rows[static_cast<std::size_t>(s)]) continue;
    const double* K = o + c.system_offset(s);
    for (int r = 0; r < 6; ++r) {
      double sum = K[6 * n + r];
      for (int j = 0; j < n; ++j) sum += K[6 * j + r] * qdd[j];
      rhs(n + 6 * s + r) = sum;
    }
  }
}

// The world force of reported contact `contact` from the unknowns x.
void force_of(const ContactForceModel& c, const ContactForceContact& contact, const double* o, const double* x,
              double* F) {
  F[0] = F[1] = F[2] = 0.0;
  for (int k = 0; k < contact.unknowns; ++k) {
    const int u = contact.first_unknown + k;
    const double* d = o + c.unknown_offset(u) + c.n + 6;
    for (int i = 0; i < 3; ++i) F[i] += x[u] * d[i];
  }
}

// The coefficients over the unknowns of output `component` of a reported contact (`index` among
// the reported ones): which combination of x the output is.
void functional(const ContactForceModel& c, const ContactForceContact& contact, int index, const double* o,
                ContactComponent component, Vector& coefficients) {
  coefficients.setZero();
  const double* basis = o + c.direction_offset(index);  // n, e_long, e_lat
  for (int k = 0; k < contact.unknowns; ++k) {
    const int u = contact.first_unknown + k;
    const double* d = o + c.unknown_offset(u) + c.n + 6;
    const int which = static_cast<int>(component);
    if (component == ContactComponent::Mspin) {
      coefficients(u) = u == contact.spin_unknown ? 1.0 : 0.0;
    } else if (which < 3) {
      coefficients(u) = d[which];
    } else {
      const double* e = basis + 3 * (which - 3);
      coefficients(u) = e[0] * d[0] + e[1] * d[1] + e[2] * d[2];
    }
  }
}

}  // namespace

const char* contact_component_name(ContactComponent component) {
  static const char* const names[kContactComponentKinds] = {"Fx", "Fy", "Fz", "N", "Flong", "Flat", "Mspin"};
  const int k = static_cast<int>(component);
  return k >= 0 && k < kContactComponentKinds ? names[k] : "?";
}

std::vector<ContactComponent> contact_components(ContactKind kind, bool spin, bool axle) {
  using C = ContactComponent;
  if (kind == ContactKind::rolling) {
    std::vector<C> out = {C::Fx, C::Fy, C::Fz, C::N};
    if (axle) out.insert(out.end(), {C::Flong, C::Flat});
    if (spin) out.push_back(C::Mspin);
    return out;
  }
  return {C::Fx, C::Fy, C::Fz, C::N, C::Flong, C::Flat};
}

int ContactForceModel::reported() const {
  int count = 0;
  for (const ContactForceContact& c : contacts) count += c.reported ? 1 : 0;
  return count;
}

int ContactForceModel::values() const {
  int count = 0;
  for (const ContactForceContact& c : contacts) count += c.reported ? static_cast<int>(c.components.size()) : 0;
  return count;
}

ContactForceData make_contact_force_data(const Model& model) {
  ContactForceData w;
  if (!model.contact_forces) return w;
  const ContactForceModel& c = *model.contact_forces;
  w.active = true;
  std::vector<double> values;
  for (const Parameter& p : model.parameters) values.push_back(p.value);
  w.tape = PreparedTape(c.tape.bind(values.data(), values.size()));
  w.registers.assign(static_cast<std::size_t>(w.tape.registers()), 0.0);
  w.outputs.assign(static_cast<std::size_t>(w.tape.outputs()), 0.0);
  if (c.native) {
    w.stage.assign(c.native->stage_size() + 1, 0.0);  // + 1: data() of an empty stage
    c.native->stage(values.data(), w.stage.data());
  }
  w.M = Matrix::Zero(c.rows(), c.columns());
  w.rhs = Vector::Zero(c.rows());
  w.x = Vector::Zero(c.columns());
  w.work = Vector::Zero(c.rows());
  w.misfit = Vector::Zero(c.rows());
  w.qr = Eigen::ColPivHouseholderQR<Matrix>(c.rows(), c.columns());
  w.values = Vector::Constant(c.values(), kNaN);
  for (const ContactForceContact& contact : c.contacts) {
    int index = -1;
    if (model.contact_modes)
      for (std::size_t i = 0; i < model.contact_modes->contacts.size(); ++i)
        if (model.contact_modes->contacts[i].name == contact.name) index = static_cast<int>(i);
    w.mode_contact.push_back(index);
  }
  return w;
}

void compute_contact_forces(const Model& model, Data& data) {
  ContactForceData& w = data.contact;
  if (!w.active || !model.contact_forces) return;
  if (data.stage != Stage::acceleration)
    throw std::logic_error("compute_contact_forces needs the accelerations of the current state: call "
                           "compute_dynamics (or compute_acceleration) first");
  const ContactForceModel& c = *model.contact_forces;
  if (c.native)
    c.native->run(w.stage.data(), data.t, data.q.data(), data.v.data(), w.outputs.data());
  else
    w.tape.run(data.t, data.q.data(), data.v.data(), w.registers.data(), w.outputs.data());
  const double* o = w.outputs.data();
  assemble(c, o, data.qdd.data(), data.R.data(), w.M, w.rhs);
  Eigen::Index solved = c.columns();  // the columns solved for: all but a free contact's
  if (data.modes.active)
    for (std::size_t i = 0; i < c.contacts.size(); ++i) {
      const int m = w.mode_contact[i];
      if (m < 0 || data.modes.mode[static_cast<std::size_t>(m)] != ContactMode::free) continue;
      w.M.middleCols(c.contacts[i].first_unknown, c.contacts[i].unknowns).setZero();
      solved -= c.contacts[i].unknowns;
    }
  bool determined = true;
  if (c.single_contact) {
    // One contact supports the only system: F = sum_B m_B (a_B - g), its first balance rows.
    w.x = w.rhs.segment(c.n, 3);
  } else {
    w.qr.compute(w.M);
    const Eigen::Index rank = w.qr.rank();
    w.work = w.rhs;
    w.work.applyOnTheLeft(w.qr.householderQ().setLength(w.qr.nonzeroPivots()).adjoint());
    w.qr.matrixQR().topLeftCorner(rank, rank).triangularView<Eigen::Upper>().solveInPlace(w.work.head(rank));
    w.x.setZero();
    for (Eigen::Index i = 0; i < rank; ++i) w.x(w.qr.colsPermutation().indices()(i)) = w.work(i);
    // The load's analysis (ContactForceModel::determined) holds every contact at once, which a
    // model with s >= n never does: its rows are judged here, on the contacts touching.
    determined = model.s() < model.n() || rank == solved;
  }
  w.misfit.noalias() = w.M * w.x;
  w.misfit -= w.rhs;
  double scale = w.rhs.norm();
  if (solved < c.columns()) {
    // A free contact's body may be in flight, its balance m (a - g) = 0 a difference of round-offs:
    // measured against the balance's own terms k_S (weight and inertia), not against that.
    double terms = 0.0;
    for (int sys = 0; sys < c.systems; ++sys)
      if (c.balance_rows[static_cast<std::size_t>(sys)])
        for (int r = 0; r < 6; ++r) terms = std::hypot(terms, o[c.system_offset(sys) + 6 * c.n + r]);
    scale = std::max(scale, terms);
  }
  w.residual = scale > 0.0 ? w.misfit.norm() / scale : w.misfit.norm();
  int index = 0;
  for (std::size_t k = 0; k < c.contacts.size(); ++k) {
    const ContactForceContact& contact = c.contacts[k];
    if (!contact.reported) continue;
    // A free contact's force is 0 whatever the others share (its unknowns were not solved for).
    const int m = w.mode_contact[k];
    const bool is_free = data.modes.active && m >= 0 && data.modes.mode[static_cast<std::size_t>(m)] == ContactMode::free;
    double F[3];
    force_of(c, contact, o, w.x.data(), F);
    const double* basis = o + c.direction_offset(index);
    double* out = w.values.data() + contact.first_value;
    for (std::size_t j = 0; j < contact.components.size(); ++j) {
      const int k = static_cast<int>(contact.components[j]);
      if (contact.components[j] == ContactComponent::Mspin) {
        out[j] = w.x(contact.spin_unknown);
      } else if (k < 3) {
        out[j] = F[k];
      } else {
        const double* e = basis + 3 * (k - 3);
        out[j] = e[0] * F[0] + e[1] * F[1] + e[2] * F[2];
      }
      if (!c.determined[static_cast<std::size_t>(contact.first_value) + j] || (!determined && !is_free)) out[j] = kNaN;
    }
    ++index;
  }
}

std::vector<std::string> contact_force_columns(const Model& model) {
  std::vector<std::string> columns;
  if (!model.contact_forces) return columns;
  for (const ContactForceContact& c : model.contact_forces->contacts)
    if (c.reported)
      for (ContactComponent k : c.components) columns.push_back(c.name + "_" + contact_component_name(k));
  columns.push_back("contact_residual");
  const std::vector<std::string> modes = contact_mode_columns(model);  // contact_modes.hpp
  columns.insert(columns.end(), modes.begin(), modes.end());
  return columns;
}

void append_contact_force_values(const Model& model, const Data& data, std::vector<double>& row) {
  if (!model.contact_forces) return;
  const ContactForceData& w = data.contact;
  for (Eigen::Index i = 0; i < w.values.size(); ++i) row.push_back(w.values(i));
  row.push_back(w.residual);
  append_contact_mode_values(model, data, row);
}

namespace {

// The combinations of unknowns a stacked system M x = rhs does not fix: an orthonormal basis of
// the null space of M with its rows scaled to unit norm, so that the units do not decide (the
// balance of moments of a ball 1e8 m across is 1e8 times that of its forces: unscaled, its
// smallest singular value fell below the threshold relative to the largest). Rows are equations,
// so scaling them leaves the null space as it is; a row at round-off of the largest (a balance
// that cancels) is left as it is, not blown up into a row of noise. The columns, the unknowns, are
// not scaled: a column at round-off (an unknown that no equation sees) scaled to unit norm looked
// like one that every equation fixes.
struct NullSpace {
  Matrix basis;
};

NullSpace scaled_null_space(const Matrix& M) {
  NullSpace null;
  Matrix scaled = M;
  double largest_row = 0.0;
  for (Eigen::Index i = 0; i < M.rows(); ++i) largest_row = std::max(largest_row, M.row(i).norm());
  for (Eigen::Index i = 0; i < scaled.rows(); ++i)
    if (const double norm = scaled.row(i).norm(); norm > kRoundOffRow * largest_row && std::isfinite(norm))
      scaled.row(i) /= norm;
  const Eigen::JacobiSVD<Matrix> svd(scaled, Eigen::ComputeFullV);
  const Vector& sigma = svd.singularValues();
  const double largest = sigma.size() > 0 ? sigma(0) : 0.0;
  std::vector<Eigen::Index> columns;
  for (Eigen::Index j = 0; j < M.cols(); ++j)
    if (j >= sigma.size() || sigma(j) <= kDetermined * largest) columns.push_back(j);
  null.basis.resize(M.cols(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t k = 0; k < columns.size(); ++k)
    null.basis.col(static_cast<Eigen::Index>(k)) = svd.matrixV().col(columns[k]);
  return null;
}

}  // namespace

void analyse_contact_forces(const Model& model, ContactForceModel& c) {
  const int n = model.n();
  const int s = model.s();
  c.determined.assign(static_cast<std::size_t>(c.values()), 1);
  // Contacts never all held (s >= n) have no state with every row held to check: each row is
  // judged on the contacts touching there (compute_contact_forces).
  if (s >= n) return;
  // A generic admissible state near the initial one: shifted by fixed amounts (the same model gives
  // the same verdict), then moved onto the constraints (step 5); failing that the start itself when
  // it is on them. With neither, nothing is checked: a verdict off the constraints can be wrong.
  const double t = model.t0;
  std::vector<double> scratch(model.evaluator->scratch_size());
  Vector q = model.q0, v = model.v0;
  for (int i = 0; i < n; ++i) {
    q(i) += 0.1 * std::sin(1.3 * i + 0.7);
    v(i) += 0.3 * std::cos(0.9 * i + 0.2);
  }
  if (!onto_constraints(model, t, q, v, scratch)) {
    q = model.q0;
    v = model.v0;
    if (!onto_constraints(model, t, q, v, scratch)) {
      c.notes.push_back("the contact forces could not be checked at load (no state on the constraints was found near "
                        "the start); they are reported as solved, with the residual column as the check");
      return;
    }
  }
  Matrix A = Matrix::Zero(n, n), b = Matrix::Zero(s, n);
  Vector Q = Vector::Zero(n), G = Vector::Zero(n), b0 = Vector::Zero(s);
  model.evaluator->terms(t, q.data(), v.data(), scratch.data(), TermsOut{A.data(), Q.data(), G.data(), b.data(), b0.data()});
  const Vector qdd = ideal_acceleration(A, Q + G, b, b0);
  const Vector R = A * qdd - Q - G;

  ContactForceModel probe = c;
  probe.balance_rows.assign(static_cast<std::size_t>(c.systems), 1);
  probe.determined.assign(c.determined.size(), 1);
  ContactForceData w;
  {
    std::vector<double> values;
    for (const Parameter& p : model.parameters) values.push_back(p.value);
    w.tape = PreparedTape(c.tape.bind(values.data(), values.size()));
    w.registers.assign(static_cast<std::size_t>(w.tape.registers()), 0.0);
    w.outputs.assign(static_cast<std::size_t>(w.tape.outputs()), 0.0);
  }
  w.tape.run(t, q.data(), v.data(), w.registers.data(), w.outputs.data());
  const double* o = w.outputs.data();
  bool finite = qdd.allFinite();
  for (double x : w.outputs) finite = finite && std::isfinite(x);
  if (!finite) {
    c.notes.push_back("the contact forces could not be checked at load (a term is not finite at the state "
                      "checked); they are reported as solved, with the residual column as the check");
    return;
  }
  Matrix M(c.rows(), c.columns());
  Vector rhs(c.rows());
  const auto residual_with = [&](const std::vector<char>& rows) {
    probe.balance_rows = rows;
    assemble(probe, o, qdd.data(), R.data(), M, rhs);
    const Eigen::CompleteOrthogonalDecomposition<Matrix> cod(M);
    const Vector x = cod.solve(rhs);
    const double scale = rhs.norm();
    return scale > 0.0 ? (M * x - rhs).norm() / scale : 0.0;
  };
  std::vector<char> rows = c.balance_rows;
  if (residual_with(rows) > kConsistent) {
    // Keep the balance of the systems consistent with (C1) on their own.
    for (int sys = 0; sys < c.systems; ++sys) {
      if (!rows[static_cast<std::size_t>(sys)]) continue;
      std::vector<char> alone(static_cast<std::size_t>(c.systems), 0);
      alone[static_cast<std::size_t>(sys)] = 1;
      if (residual_with(alone) > kConsistent) {
        rows[static_cast<std::size_t>(sys)] = 0;
        c.notes.push_back(fmt::format(
            "the bodies hanging from frame '{}' are held by the coordinates in a direction no contact supports (their "
            "momentum balance does not close with the contact forces: e.g. a sled kept flat by its frames); the "
            "contact forces there are those the reactions R alone determine",
            c.system_names[static_cast<std::size_t>(sys)]));
      }
    }
  }
  c.balance_rows = rows;
  probe.balance_rows = rows;
  assemble(probe, o, qdd.data(), R.data(), M, rhs);
  const NullSpace null = scaled_null_space(M);
  Vector coefficients(c.columns());
  int index = 0;
  for (const ContactForceContact& contact : c.contacts) {
    if (!contact.reported) continue;
    std::string missing;
    for (std::size_t j = 0; j < contact.components.size(); ++j) {
      const ContactComponent component = contact.components[j];
      functional(c, contact, index, o, component, coefficients);
      const double size = coefficients.norm();
      bool determined = true;
      for (Eigen::Index j = 0; j < null.basis.cols(); ++j)
        if (std::abs(coefficients.dot(null.basis.col(j))) > kDetermined * size) determined = false;
      c.determined[static_cast<std::size_t>(contact.first_value) + j] = determined ? 1 : 0;
      if (!determined) missing += fmt::format("{}{}_{}", missing.empty() ? "" : ", ", contact.name, contact_component_name(component));
    }
    if (!missing.empty()) {
      const bool held = !c.balance_rows[static_cast<std::size_t>(contact.system)];
      c.notes.push_back(fmt::format(
          "contact '{}': {} not determined by the model, written as NaN ({})", contact.name, missing,
          held ? "its bodies are also held by their coordinates, which carry an unknown part of the load"
               : "a statically indeterminate support: the contacts share a load in a way rigid bodies do not fix"));
    }
    ++index;
  }
}

}  // namespace nhdyn
