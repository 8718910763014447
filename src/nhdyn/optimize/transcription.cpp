// The collocation NLP of transcription.hpp: layout, bounds, starting point, rank rules, and the
// values and exact derivatives of the objective and constraints.
#include "nhdyn/optimize/transcription.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/model/detail/tape_tangent.hpp"

namespace nhdyn {

double Transcription::nlp_bound(double b) { return std::isfinite(b) ? b : (b > 0 ? kNlpInfinity : -kNlpInfinity); }

std::vector<std::string> Transcription::residual_row_names() const {
  std::vector<std::string> names;
  for (const Constraint& c : problem_.model.constraints)
    if (c.level == ConstraintLevel::position) names.push_back(c.name + " (position)");
  for (const Constraint& c : problem_.model.constraints)
    if (c.level != ConstraintLevel::acceleration) names.push_back(c.name + " (velocity)");
  return names;
}

Transcription::Transcription(const OptimalControlProblem& problem) : problem_(problem) {
  const Model& model = problem_.model;
  require_fewer_constraints(model, "optimize");
  const auto* programs = dynamic_cast<const TapeEvaluator*>(model.evaluator.get());
  if (programs == nullptr) throw InputError("optimize needs a model compiled from a model file");
  if (programs->sparsity() != nullptr)
    throw InputError(fmt::format("optimize takes models compiled dense; {} is compiled sparse ({} coordinates)",
                                 model.name, model.n()));
  terms_ = &programs->tapes().terms;
  position_residual_ = &programs->tapes().position_residual;
  velocity_residual_ = &programs->tapes().velocity_residual;
  n_ = model.n();
  m_ = problem_.m();
  s_ = model.s();
  k_ = n_ - s_;
  hs_ = problem_.method == CollocationMethod::hermite_simpson;
  intervals_ = problem_.nodes - 1;
  points_ = hs_ ? 2 * intervals_ + 1 : intervals_ + 1;
  width_ = 3 * n_ + m_;
  variables_ = points_ * width_ + (problem_.free_time ? 1 : 0);
  fixed_duration_ = problem_.t_end - problem_.t0;
  path_count_ = static_cast<int>(problem_.path_constraints.size());

  std::size_t registers = 0;
  for (const Tape* program : std::initializer_list<const Tape*>{terms_, position_residual_, velocity_residual_,
                                 &problem_.force, &problem_.actuators, &problem_.integrand, &problem_.path})
    registers = std::max(registers, static_cast<std::size_t>(program->registers()));
  if (problem_.final_term) registers = std::max(registers, static_cast<std::size_t>(problem_.final_term->registers()));
  terms_registers_.assign(static_cast<std::size_t>(terms_->registers()), 0.0);
  force_registers_.assign(static_cast<std::size_t>(problem_.force.registers()), 0.0);
  velocity_registers_.assign(static_cast<std::size_t>(velocity_residual_->registers()), 0.0);
  other_registers_.assign(registers, 0.0);
  tangents_.assign(registers, 0.0);
  terms_out_.assign(static_cast<std::size_t>(terms_->outputs()), 0.0);
  dterms_.assign(terms_out_.size(), 0.0);
  force_out_.assign(static_cast<std::size_t>(n_), 0.0);
  dforce_.assign(static_cast<std::size_t>(n_), 0.0);
  std::size_t layout = static_cast<std::size_t>(n_ + m_);
  layout_q_.assign(layout, 0.0);
  layout_v_.assign(layout, 0.0);
  layout_dq_.assign(layout, 0.0);
  layout_dv_.assign(layout, 0.0);
  A_.resize(n_, n_);
  b_.resize(s_, n_);
  r_.resize(n_);
  mu_.resize(s_);
  work_.resize(n_);

  // Variable bounds: the bounds of [optimize], then the boundary values fixed (within them).
  x_lower_.assign(static_cast<std::size_t>(variables_), -kNlpInfinity);
  x_upper_.assign(static_cast<std::size_t>(variables_), kNlpInfinity);
  for (int p = 0; p < points_; ++p) {
    for (int i = 0; i < 2 * n_; ++i) {
      x_lower_[static_cast<std::size_t>(q_index(p, i))] = nlp_bound(problem_.state_lower[static_cast<std::size_t>(i)]);
      x_upper_[static_cast<std::size_t>(q_index(p, i))] = nlp_bound(problem_.state_upper[static_cast<std::size_t>(i)]);
    }
    for (int j = 0; j < m_; ++j) {
      x_lower_[static_cast<std::size_t>(u_index(p, j))] = nlp_bound(problem_.controls[static_cast<std::size_t>(j)].lower);
      x_upper_[static_cast<std::size_t>(u_index(p, j))] = nlp_bound(problem_.controls[static_cast<std::size_t>(j)].upper);
    }
  }
  // The messages give the bounds as written (none is IPOPT's +-kNlpInfinity), at their file:line.
  const auto fix = [&](int p, const BoundaryValue& b, const char* which) {
    const std::size_t at = static_cast<std::size_t>(b.velocity ? v_index(p, b.index) : q_index(p, b.index));
    const std::size_t slot = static_cast<std::size_t>(b.index + (b.velocity ? n_ : 0));
    const std::string name = model.coordinates[static_cast<std::size_t>(b.index)] + (b.velocity ? "'" : "");
    const std::string place = b.where.empty() ? "" : b.where + ": ";
    if (!(std::abs(b.value) < 0.5 * kNlpInfinity))
      throw InputError(fmt::format("{}the {} value {} = {} is too large for the optimizer, which reads a bound beyond "
                                   "{:g} as no bound: give the model in units that make it smaller",
                                   place, which, name, b.value, 0.5 * kNlpInfinity));
    const double lower = problem_.state_lower[slot], upper = problem_.state_upper[slot];
    if (b.value < lower || b.value > upper) {
      const std::string bounds = slot < problem_.state_bounds_where.size() ? problem_.state_bounds_where[slot] : "";
      throw InputError(fmt::format("{}the {} value {} = {} lies outside its bounds [{}, {}]{}: change one of them",
                                   place, which, name, b.value, lower, upper,
                                   bounds.empty() ? "" : " (given at " + bounds + ")"));
    }
    x_lower_[at] = x_upper_[at] = b.value;
  };
  for (const BoundaryValue& b : problem_.initial) fix(0, b, "initial");
  for (const BoundaryValue& b : problem_.final) fix(points_ - 1, b, "final");
  if (problem_.free_time) {
    x_lower_[static_cast<std::size_t>(duration_index())] = problem_.duration_min;
    x_upper_[static_cast<std::size_t>(duration_index())] = problem_.duration_max;
  }

  make_start();
  release_determined_final_values();
  choose_splits_and_initial_rows();
  build_collocation();
  collocation_rows_ = static_cast<int>(collocation_.size());
  dynamics_row0_ = collocation_rows_;
  initial_row0_ = dynamics_row0_ + points_ * n_;
  path_row0_ = initial_row0_ + static_cast<int>(initial_rows_.size());
  rows_ = path_row0_ + points_ * path_count_;
  build_pattern();
  build_hessian_pattern();
  check_controls_act();
  require_path_at_fixed_ends();
}

double Transcription::tau(int p) const {
  return static_cast<double>(p) / static_cast<double>(points_ - 1);
}

double Transcription::weight(int p) const {
  if (!hs_) return p == 0 || p == points_ - 1 ? 0.5 : 1.0;
  if (p % 2 == 1) return 4.0 / 6.0;
  return p == 0 || p == points_ - 1 ? 1.0 / 6.0 : 2.0 / 6.0;
}

void Transcription::make_start() {
  const Model& model = problem_.model;
  std::vector<double> q0(static_cast<std::size_t>(2 * n_)), q1;
  std::vector<char> given0(static_cast<std::size_t>(2 * n_), 0), given1(static_cast<std::size_t>(2 * n_), 0);
  for (int i = 0; i < n_; ++i) {
    q0[static_cast<std::size_t>(i)] = model.q0(i);
    q0[static_cast<std::size_t>(n_ + i)] = model.v0(i);
  }
  for (const BoundaryValue& b : problem_.initial) {
    q0[static_cast<std::size_t>(b.index + (b.velocity ? n_ : 0))] = b.value;
    given0[static_cast<std::size_t>(b.index + (b.velocity ? n_ : 0))] = 1;
  }
  q1 = q0;
  for (const BoundaryValue& b : problem_.final) {
    q1[static_cast<std::size_t>(b.index + (b.velocity ? n_ : 0))] = b.value;
    given1[static_cast<std::size_t>(b.index + (b.velocity ? n_ : 0))] = 1;
  }
  // A velocity given at neither end follows the straight line of its coordinate.
  for (int i = 0; i < n_; ++i) {
    const std::size_t v = static_cast<std::size_t>(n_ + i);
    if (!given0[v] && !given1[v]) {
      const double slope = (q1[static_cast<std::size_t>(i)] - q0[static_cast<std::size_t>(i)]) / (problem_.t_end - problem_.t0);
      q0[v] = q1[v] = slope;
    } else if (!given0[v]) {
      q0[v] = q1[v];
    }
  }
  start_.assign(static_cast<std::size_t>(variables_), 0.0);
  for (int p = 0; p < points_; ++p) {
    const double s = tau(p);
    for (int i = 0; i < 2 * n_; ++i)
      start_[static_cast<std::size_t>(q_index(p, i))] =
          (1 - s) * q0[static_cast<std::size_t>(i)] + s * q1[static_cast<std::size_t>(i)];
  }
  if (problem_.free_time) start_[static_cast<std::size_t>(duration_index())] = problem_.t_end - problem_.t0;
  for (std::size_t i = 0; i < start_.size(); ++i) {
    if (start_[i] < x_lower_[i] || start_[i] > x_upper_[i])
      start_[i] = x_lower_[i] > -kNlpInfinity && x_upper_[i] < kNlpInfinity ? 0.5 * (x_lower_[i] + x_upper_[i])
                  : x_lower_[i] > -kNlpInfinity                            ? x_lower_[i]
                                                                           : x_upper_[i];
  }
}

// Per point, the split of the partition complement: the s dependent coordinates are the pivots of
// a column-pivoted QR of b at the starting point (docs/derivations/optimal-programs.md, section 4).
// Then the rank rule at the first node.
void Transcription::choose_splits_and_initial_rows() {
  const Model& model = problem_.model;
  split_.assign(static_cast<std::size_t>(points_ * n_), 0);
  const double* x = start_.data();
  for (int p = 0; p < points_; ++p) {
    int* split = split_.data() + static_cast<std::size_t>(p) * static_cast<std::size_t>(n_);
    for (int i = 0; i < n_; ++i) split[i] = i;
    if (s_ == 0) continue;
    terms_->run(time(p, x), x + q_index(p, 0), x + v_index(p, 0), terms_registers_.data(), terms_out_.data());
    const Eigen::Map<const Eigen::MatrixXd> b(terms_out_.data() + n_ * n_ + 2 * n_, s_, n_);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(b);
    if (qr.rank() < s_)
      throw InputError(fmt::format("the constraints of {} are dependent at the starting point (t = {}): the constraint "
                                   "matrix b has rank {} < {}",
                                   model.name, time(p, x), qr.rank(), s_));
    std::vector<char> dependent(static_cast<std::size_t>(n_), 0);
    for (int i = 0; i < s_; ++i) dependent[static_cast<std::size_t>(qr.colsPermutation().indices()(i))] = 1;
    int at = 0;
    for (int i = 0; i < n_; ++i)
      if (dependent[static_cast<std::size_t>(i)]) split[at++] = i;
    for (int i = 0; i < n_; ++i)
      if (!dependent[static_cast<std::size_t>(i)]) split[at++] = i;
  }

  // The rank rule: the rows phi (position level) and f (position level as d phi/dt, and velocity
  // level) at the first node, restricted to the initial values left free, kept when independent.
  const int pcount = model.position_constraints(), rcount = model.velocity_constraints();
  const int candidates = pcount + rcount;
  if (candidates == 0) return;
  std::vector<char> fixed(static_cast<std::size_t>(2 * n_), 0);
  for (const BoundaryValue& b : problem_.initial) fixed[static_cast<std::size_t>(b.index + (b.velocity ? n_ : 0))] = 1;
  std::vector<double> values;
  Eigen::MatrixXd J;
  constraint_rows(time(0, x), x + q_index(0, 0), x + v_index(0, 0), values, J);
  for (int col = 0; col < 2 * n_; ++col)
    if (fixed[static_cast<std::size_t>(col)]) J.col(col).setZero();
  const std::vector<std::string> names = residual_row_names();
  Eigen::MatrixXd basis(2 * n_, 0);
  for (int c = 0; c < candidates; ++c) {
    Eigen::VectorXd row = J.row(c).transpose();
    const double norm0 = row.norm();
    for (int k = 0; k < basis.cols(); ++k) row -= basis.col(k).dot(row) * basis.col(k);
    if (norm0 > 0 && row.norm() > 1e-8 * norm0) {
      basis.conservativeResize(Eigen::NoChange, basis.cols() + 1);
      basis.col(basis.cols() - 1) = row / row.norm();
      initial_rows_.push_back(c);
      continue;
    }
    if (std::abs(values[static_cast<std::size_t>(c)]) > 1e-8)
      throw InputError(fmt::format("the initial values of [optimize] violate the constraint {}: its residual is {:.3e} "
                                   "and no free initial value can change it; give initial values on the constraint",
                                   names[static_cast<std::size_t>(c)], values[static_cast<std::size_t>(c)]));
    notes_.push_back(fmt::format("the constraint {} holds at the first node by the fixed initial values: not imposed "
                                 "there again",
                                 names[static_cast<std::size_t>(c)]));
  }
}

void Transcription::build_collocation() {
  for (int j = 0; j < intervals_; ++j) {
    const int a = hs_ ? 2 * j : j, b = hs_ ? 2 * j + 2 : j + 1, c = 2 * j + 1;
    for (int level = 0; level < 2; ++level) {  // q rows from v, v rows from a
      for (int i = 0; i < n_; ++i) {
        const auto y = [&](int p) { return level == 0 ? q_index(p, i) : v_index(p, i); };
        const auto dy = [&](int p) { return level == 0 ? v_index(p, i) : a_index(p, i); };
        if (!hs_) {
          collocation_.push_back({{y(b), 1, 0}, {y(a), -1, 0}, {dy(a), 0, -0.5}, {dy(b), 0, -0.5}});
        } else {
          collocation_.push_back({{y(b), 1, 0}, {y(a), -1, 0}, {dy(a), 0, -1.0 / 6}, {dy(c), 0, -4.0 / 6}, {dy(b), 0, -1.0 / 6}});
          collocation_.push_back({{y(c), 1, 0}, {y(a), -0.5, 0}, {y(b), -0.5, 0}, {dy(a), 0, -1.0 / 8}, {dy(b), 0, 1.0 / 8}});
        }
      }
    }
  }
}

void Transcription::build_pattern() {
  const auto add = [&](int row, int column) {
    jac_rows_.push_back(row);
    jac_columns_.push_back(column);
  };
  for (int r = 0; r < collocation_rows_; ++r) {
    for (const CollocationTerm& t : collocation_[static_cast<std::size_t>(r)]) add(r, t.column);
    if (problem_.free_time) add(r, duration_index());
  }
  for (int p = 0; p < points_; ++p)
    for (int row = 0; row < n_; ++row) {
      for (int c = 0; c < width_; ++c) add(dynamics_row0_ + p * n_ + row, p * width_ + c);
      if (problem_.free_time) add(dynamics_row0_ + p * n_ + row, duration_index());
    }
  for (std::size_t r = 0; r < initial_rows_.size(); ++r)
    for (int c = 0; c < 2 * n_; ++c) add(initial_row0_ + static_cast<int>(r), c);
  for (int p = 0; p < points_; ++p)
    for (int g = 0; g < path_count_; ++g) {
      for (int c = 0; c < 2 * n_; ++c) add(path_row0_ + p * path_count_ + g, p * width_ + c);
      for (int j = 0; j < m_; ++j) add(path_row0_ + p * path_count_ + g, u_index(p, j));
      if (problem_.free_time) add(path_row0_ + p * path_count_ + g, duration_index());
    }
}

void Transcription::bounds(double* x_lower, double* x_upper, double* g_lower, double* g_upper) const {
  std::copy(x_lower_.begin(), x_lower_.end(), x_lower);
  std::copy(x_upper_.begin(), x_upper_.end(), x_upper);
  std::fill(g_lower, g_lower + path_row0_, 0.0);
  std::fill(g_upper, g_upper + path_row0_, 0.0);
  for (int p = 0; p < points_; ++p)
    for (int g = 0; g < path_count_; ++g) {
      const PathConstraint& c = problem_.path_constraints[static_cast<std::size_t>(g)];
      g_lower[path_row0_ + p * path_count_ + g] = nlp_bound(c.lower);
      g_upper[path_row0_ + p * path_count_ + g] = nlp_bound(c.upper);
    }
}

void Transcription::starting_point(double* x) const { std::copy(start_.begin(), start_.end(), x); }

void Transcription::layout_inputs(int p, const double* x) {
  for (int i = 0; i < n_; ++i) {
    layout_q_[static_cast<std::size_t>(i)] = x[q_index(p, i)];
    layout_v_[static_cast<std::size_t>(i)] = x[v_index(p, i)];
  }
  for (int j = 0; j < m_; ++j) {
    layout_q_[static_cast<std::size_t>(n_ + j)] = x[u_index(p, j)];
    layout_v_[static_cast<std::size_t>(n_ + j)] = 0.0;
  }
}

bool Transcription::objective(const double* x, double& f) {
  const double T = duration(x);
  const double h = T / intervals_;
  double sum = 0.0;
  double value = 0.0;
  for (int p = 0; p < points_; ++p) {
    layout_inputs(p, x);
    problem_.integrand.run(time(p, x), layout_q_.data(), layout_v_.data(), other_registers_.data(), &value);
    sum += weight(p) * value;
  }
  f = h * sum;
  if (problem_.final_term) {
    layout_inputs(points_ - 1, x);
    problem_.final_term->run(time(points_ - 1, x), layout_q_.data(), layout_v_.data(), other_registers_.data(), &value);
    f += value;
  }
  if (problem_.minimum_time) f += T;
  return std::isfinite(f);
}

bool Transcription::gradient(const double* x, double* grad) {
  std::fill(grad, grad + variables_, 0.0);
  const double T = duration(x);
  const double h = T / intervals_;
  double value = 0.0, dvalue = 0.0, dT = 0.0;
  const auto differentiate = [&](const Tape& program, int p, double w) {
    layout_inputs(p, x);
    program.run(time(p, x), layout_q_.data(), layout_v_.data(), other_registers_.data(), &value);
    for (int c = 0; c < 2 * n_ + m_; ++c) {
      std::fill(layout_dq_.begin(), layout_dq_.end(), 0.0);
      std::fill(layout_dv_.begin(), layout_dv_.end(), 0.0);
      int column = 0;
      if (c < n_) {
        layout_dq_[static_cast<std::size_t>(c)] = 1.0;
        column = q_index(p, c);
      } else if (c < 2 * n_) {
        layout_dv_[static_cast<std::size_t>(c - n_)] = 1.0;
        column = v_index(p, c - n_);
      } else {
        layout_dq_[static_cast<std::size_t>(n_ + c - 2 * n_)] = 1.0;
        column = u_index(p, c - 2 * n_);
      }
      run_tangent(program, other_registers_.data(), 0.0, layout_dq_.data(), layout_dv_.data(), tangents_.data(), &dvalue);
      grad[column] += w * dvalue;
    }
    if (problem_.free_time) {
      std::fill(layout_dq_.begin(), layout_dq_.end(), 0.0);
      std::fill(layout_dv_.begin(), layout_dv_.end(), 0.0);
      run_tangent(program, other_registers_.data(), 1.0, layout_dq_.data(), layout_dv_.data(), tangents_.data(), &dvalue);
      dT += w * tau(p) * dvalue;
    }
  };
  for (int p = 0; p < points_; ++p) {
    differentiate(problem_.integrand, p, h * weight(p));
    dT += weight(p) / intervals_ * value;
  }
  if (problem_.final_term) differentiate(*problem_.final_term, points_ - 1, 1.0);
  if (problem_.free_time) grad[duration_index()] = dT + (problem_.minimum_time ? 1.0 : 0.0);
  for (int i = 0; i < variables_; ++i)
    if (!std::isfinite(grad[i])) return false;
  return true;
}

bool Transcription::evaluate_point(int p, const double* x) {
  const double t = time(p, x);
  terms_->run(t, x + q_index(p, 0), x + v_index(p, 0), terms_registers_.data(), terms_out_.data());
  layout_inputs(p, x);
  problem_.force.run(t, layout_q_.data(), layout_v_.data(), force_registers_.data(), force_out_.data());
  A_ = Eigen::Map<const Eigen::MatrixXd>(terms_out_.data(), n_, n_);
  const Eigen::Map<const Eigen::VectorXd> Q(terms_out_.data() + n_ * n_, n_), G(terms_out_.data() + n_ * n_ + n_, n_);
  b_ = Eigen::Map<const Eigen::MatrixXd>(terms_out_.data() + n_ * n_ + 2 * n_, s_, n_);
  const Eigen::Map<const Eigen::VectorXd> a(x + a_index(p, 0), n_), F(force_out_.data(), n_);
  r_ = A_ * a - Q - G - F;
  current_split_ = split_.data() + static_cast<std::size_t>(p) * static_cast<std::size_t>(n_);
  if (s_ > 0) {
    const int* split = current_split_;
    bt_d_.resize(s_, s_);
    Eigen::VectorXd rd(s_);
    for (int i = 0; i < s_; ++i) {
      for (int l = 0; l < s_; ++l) bt_d_(i, l) = b_(l, split[i]);  // b_d^T
      rd(i) = r_(split[i]);
    }
    lu_.compute(bt_d_);
    const double det = std::abs(lu_.determinant());
    if (!(det > 1e-300)) return false;
    mu_ = lu_.solve(rd);
  }
  for (double v : terms_out_)
    if (!std::isfinite(v)) return false;
  for (double v : force_out_)
    if (!std::isfinite(v)) return false;
  return true;
}

void Transcription::project(const Eigen::VectorXd& y, double* out) const {
  // D y = y_i - b_i^T b_d^-T y_d  (O6), the independent coordinates in split order.
  if (s_ == 0) {
    for (int i = 0; i < n_; ++i) out[i] = y(i);
    return;
  }
  Eigen::VectorXd yd(s_);
  for (int i = 0; i < s_; ++i) yd(i) = y(current_split_[i]);
  const Eigen::VectorXd w = lu_.solve(yd);
  for (int l = 0; l < k_; ++l) {
    const int c = current_split_[s_ + l];
    double value = y(c);
    for (int i = 0; i < s_; ++i) value -= b_(i, c) * w(i);
    out[l] = value;
  }
}


void Transcription::dynamics_values(int p, const double* x, double* out) {
  project(r_, out);
  if (s_ == 0) return;
  if (problem_.level == OptimizeConstraintLevel::given && p > 0) {
    velocity_residual_->run(time(p, x), x + q_index(p, 0), x + v_index(p, 0), velocity_registers_.data(), out + k_);
    return;
  }
  const Eigen::Map<const Eigen::VectorXd> a(x + a_index(p, 0), n_), b0(terms_out_.data() + n_ * n_ + 2 * n_ + s_ * n_, s_);
  Eigen::Map<Eigen::VectorXd>(out + k_, s_) = b_ * a + b0;
}

// (O5), (O7): d(D r) = D (dr - db^T mu), dr = dA a - dQ - dG - d(B u).
void Transcription::dynamics_direction(int p, const double* x, double dt, const double* dq, const double* dv,
                                       const double* du, double* out) {
  const bool state = dt != 0.0 || std::any_of(dq, dq + n_, [](double d) { return d != 0.0; }) ||
                     std::any_of(dv, dv + n_, [](double d) { return d != 0.0; });
  if (state)
    run_tangent(*terms_, terms_registers_.data(), dt, dq, dv, tangents_.data(), dterms_.data());
  else
    std::fill(dterms_.begin(), dterms_.end(), 0.0);
  for (int i = 0; i < n_; ++i) {
    layout_dq_[static_cast<std::size_t>(i)] = dq[i];
    layout_dv_[static_cast<std::size_t>(i)] = dv[i];
  }
  for (int j = 0; j < m_; ++j) {
    layout_dq_[static_cast<std::size_t>(n_ + j)] = du[j];
    layout_dv_[static_cast<std::size_t>(n_ + j)] = 0.0;
  }
  run_tangent(problem_.force, force_registers_.data(), dt, layout_dq_.data(), layout_dv_.data(), tangents_.data(),
              dforce_.data());
  const Eigen::Map<const Eigen::MatrixXd> dA(dterms_.data(), n_, n_), db(dterms_.data() + n_ * n_ + 2 * n_, s_, n_);
  const Eigen::Map<const Eigen::VectorXd> dQ(dterms_.data() + n_ * n_, n_), dG(dterms_.data() + n_ * n_ + n_, n_),
      db0(dterms_.data() + n_ * n_ + 2 * n_ + s_ * n_, s_), dF(dforce_.data(), n_), a(x + a_index(p, 0), n_);
  work_ = dA * a - dQ - dG - dF;
  if (s_ > 0) work_ -= db.transpose() * mu_;
  project(work_, out);
  if (s_ == 0) return;
  if (problem_.level == OptimizeConstraintLevel::given && p > 0) {
    if (state)
      run_tangent(*velocity_residual_, velocity_registers_.data(), dt, dq, dv, tangents_.data(), out + k_);
    else
      std::fill(out + k_, out + n_, 0.0);
    return;
  }
  Eigen::Map<Eigen::VectorXd>(out + k_, s_) = db * a + db0;
}

bool Transcription::constraint_values(const double* x, double* g) {
  const double h = duration(x) / intervals_;
  for (int r = 0; r < collocation_rows_; ++r) {
    double value = 0.0;
    for (const CollocationTerm& t : collocation_[static_cast<std::size_t>(r)]) value += (t.c + h * t.c_h) * x[t.column];
    g[r] = value;
  }
  for (int p = 0; p < points_; ++p) {
    if (!evaluate_point(p, x)) return false;
    dynamics_values(p, x, g + dynamics_row0_ + p * n_);
  }
  if (!initial_rows_.empty()) {
    const int pcount = problem_.model.position_constraints();
    std::vector<double> all(static_cast<std::size_t>(pcount + problem_.model.velocity_constraints()));
    const double t = time(0, x);
    if (pcount > 0) position_residual_->run(t, x + q_index(0, 0), x + v_index(0, 0), other_registers_.data(), all.data());
    if (all.size() > static_cast<std::size_t>(pcount))
      velocity_residual_->run(t, x + q_index(0, 0), x + v_index(0, 0), velocity_registers_.data(), all.data() + pcount);
    for (std::size_t r = 0; r < initial_rows_.size(); ++r)
      g[initial_row0_ + static_cast<int>(r)] = all[static_cast<std::size_t>(initial_rows_[r])];
  }
  for (int p = 0; p < points_ && path_count_ > 0; ++p) {
    layout_inputs(p, x);
    problem_.path.run(time(p, x), layout_q_.data(), layout_v_.data(), other_registers_.data(),
                      g + path_row0_ + p * path_count_);
  }
  for (int r = 0; r < rows_; ++r)
    if (!std::isfinite(g[r])) return false;
  return true;
}

void Transcription::jacobian_pattern(int* rows, int* columns) const {
  std::copy(jac_rows_.begin(), jac_rows_.end(), rows);
  std::copy(jac_columns_.begin(), jac_columns_.end(), columns);
}

void Transcription::constraint_rows(double t, const double* q, const double* v, std::vector<double>& values,
                                    Eigen::MatrixXd& jacobian) {
  const int pcount = problem_.model.position_constraints(), rcount = problem_.model.velocity_constraints();
  const int rows = pcount + rcount;
  values.assign(static_cast<std::size_t>(rows), 0.0);
  jacobian.resize(rows, 2 * n_);
  if (pcount > 0) position_residual_->run(t, q, v, other_registers_.data(), values.data());
  if (rcount > 0) velocity_residual_->run(t, q, v, velocity_registers_.data(), values.data() + pcount);
  std::vector<double> d(static_cast<std::size_t>(rows)), dq(static_cast<std::size_t>(n_)), dv(static_cast<std::size_t>(n_));
  for (int c = 0; c < 2 * n_; ++c) {
    std::fill(dq.begin(), dq.end(), 0.0);
    std::fill(dv.begin(), dv.end(), 0.0);
    (c < n_ ? dq[static_cast<std::size_t>(c)] : dv[static_cast<std::size_t>(c - n_)]) = 1.0;
    if (pcount > 0) run_tangent(*position_residual_, other_registers_.data(), 0.0, dq.data(), nullptr, tangents_.data(), d.data());
    if (rcount > 0)
      run_tangent(*velocity_residual_, velocity_registers_.data(), 0.0, dq.data(), dv.data(), tangents_.data(),
                  d.data() + pcount);
    for (int r = 0; r < rows; ++r) jacobian(r, c) = d[static_cast<std::size_t>(r)];
  }
}

bool Transcription::jacobian_values(const double* x, double* values) {
  std::size_t at = 0;
  const double h = duration(x) / intervals_;
  for (int r = 0; r < collocation_rows_; ++r) {
    double dT = 0.0;
    for (const CollocationTerm& t : collocation_[static_cast<std::size_t>(r)]) {
      values[at++] = t.c + h * t.c_h;
      dT += t.c_h * x[t.column] / intervals_;
    }
    if (problem_.free_time) values[at++] = dT;
  }
  // The dynamics block of each point: n rows, the point's 3n + m columns (and T).
  const int columns = width_ + (problem_.free_time ? 1 : 0);
  Eigen::MatrixXd block(n_, columns);
  std::vector<double> zero_n(static_cast<std::size_t>(n_), 0.0), e_n(static_cast<std::size_t>(n_), 0.0),
      zero_m(static_cast<std::size_t>(m_), 0.0), e_m(static_cast<std::size_t>(m_), 0.0), scratch(static_cast<std::size_t>(n_));
  for (int p = 0; p < points_; ++p) {
    if (!evaluate_point(p, x)) return false;
    dynamics_values(p, x, scratch.data());
    for (int i = 0; i < n_; ++i) {
      std::fill(e_n.begin(), e_n.end(), 0.0);
      e_n[static_cast<std::size_t>(i)] = 1.0;
      dynamics_direction(p, x, 0.0, e_n.data(), zero_n.data(), zero_m.data(), block.col(i).data());
      dynamics_direction(p, x, 0.0, zero_n.data(), e_n.data(), zero_m.data(), block.col(n_ + i).data());
      // q'' enters linearly: [D A; b] e_i (or 0 in the rows of the constraints at the level given).
      work_ = A_.col(i);
      project(work_, block.col(2 * n_ + i).data());
      for (int l = 0; l < s_; ++l)
        block(k_ + l, 2 * n_ + i) = problem_.level == OptimizeConstraintLevel::given && p > 0 ? 0.0 : b_(l, i);
    }
    for (int j = 0; j < m_; ++j) {
      std::fill(e_m.begin(), e_m.end(), 0.0);
      e_m[static_cast<std::size_t>(j)] = 1.0;
      dynamics_direction(p, x, 0.0, zero_n.data(), zero_n.data(), e_m.data(), block.col(3 * n_ + j).data());
    }
    if (problem_.free_time)
      dynamics_direction(p, x, tau(p), zero_n.data(), zero_n.data(), zero_m.data(), block.col(width_).data());
    for (int row = 0; row < n_; ++row)
      for (int c = 0; c < columns; ++c) values[at++] = block(row, c);
  }
  if (!initial_rows_.empty()) {
    std::vector<double> all;
    Eigen::MatrixXd J;
    constraint_rows(time(0, x), x + q_index(0, 0), x + v_index(0, 0), all, J);
    for (int r : initial_rows_)
      for (int c = 0; c < 2 * n_; ++c) values[at++] = J(r, c);
  }
  if (path_count_ > 0) {
    Eigen::MatrixXd gblock(path_count_, 2 * n_ + m_ + 1);
    std::vector<double> g(static_cast<std::size_t>(path_count_));
    for (int p = 0; p < points_; ++p) {
      layout_inputs(p, x);
      problem_.path.run(time(p, x), layout_q_.data(), layout_v_.data(), other_registers_.data(), g.data());
      for (int c = 0; c <= 2 * n_ + m_; ++c) {
        std::fill(layout_dq_.begin(), layout_dq_.end(), 0.0);
        std::fill(layout_dv_.begin(), layout_dv_.end(), 0.0);
        double dt = 0.0;
        if (c < n_)
          layout_dq_[static_cast<std::size_t>(c)] = 1.0;
        else if (c < 2 * n_)
          layout_dv_[static_cast<std::size_t>(c - n_)] = 1.0;
        else if (c < 2 * n_ + m_)
          layout_dq_[static_cast<std::size_t>(n_ + c - 2 * n_)] = 1.0;
        else
          dt = tau(p);
        run_tangent(problem_.path, other_registers_.data(), dt, layout_dq_.data(), layout_dv_.data(), tangents_.data(),
                    g.data());
        for (int r = 0; r < path_count_; ++r) gblock(r, c) = g[static_cast<std::size_t>(r)];
      }
      for (int r = 0; r < path_count_; ++r) {
        for (int c = 0; c < 2 * n_ + m_; ++c) values[at++] = gblock(r, c);
        if (problem_.free_time) values[at++] = gblock(r, 2 * n_ + m_);
      }
    }
  }
  for (std::size_t i = 0; i < at; ++i)
    if (!std::isfinite(values[i])) return false;
  return true;
}

void Transcription::build_hessian_pattern() {
  for (int p = 0; p < points_; ++p)
    for (int i = 0; i < width_; ++i)
      for (int j = 0; j <= i; ++j) {
        hess_rows_.push_back(p * width_ + i);
        hess_columns_.push_back(p * width_ + j);
      }
  if (problem_.free_time)
    for (int c = 0; c <= duration_index(); ++c) {
      hess_rows_.push_back(duration_index());
      hess_columns_.push_back(c);
    }
}

void Transcription::hessian_pattern(int* rows, int* columns) const {
  std::copy(hess_rows_.begin(), hess_rows_.end(), rows);
  std::copy(hess_columns_.begin(), hess_columns_.end(), columns);
}

bool Transcription::lagrangian_gradient(const double* x, double sigma, const double* lambda, double* out) {
  if (!gradient(x, out)) return false;
  for (int i = 0; i < variables_; ++i) out[i] *= sigma;
  jac_work_.resize(jac_rows_.size());
  if (!jacobian_values(x, jac_work_.data())) return false;
  for (std::size_t k = 0; k < jac_work_.size(); ++k)
    out[jac_columns_[k]] += lambda[jac_rows_[k]] * jac_work_[k];
  return true;
}

// Forward differences of exact first derivatives: the step sqrt(eps) (1 + |x|) balances the
// truncation error (h times third derivatives) against round-off (eps / h), about 1e-8 relative,
// far below what Newton's steps need; central differences (twice the gradients) took the same
// iterations on every example. The point blocks are symmetrized; the T row comes from T's column.
bool Transcription::hessian_values(const double* x, double sigma, const double* lambda, double* values) {
  const std::size_t nv = static_cast<std::size_t>(variables_), w = static_cast<std::size_t>(width_);
  hess_x_.assign(x, x + nv);
  hess_plus_.resize(nv);
  hess_minus_.resize(nv);
  hess_step_.resize(static_cast<std::size_t>(points_));
  hess_blocks_.assign(static_cast<std::size_t>(points_) * w * w, 0.0);  // per point, column-major W x W
  const double sqrt_eps = 1.4901161193847656e-08;
  if (!lagrangian_gradient(x, sigma, lambda, hess_minus_.data())) return false;  // at x itself
  for (std::size_t c = 0; c < w; ++c) {
    for (int p = 0; p < points_; ++p) {
      const std::size_t at = static_cast<std::size_t>(p) * w + c;
      hess_step_[static_cast<std::size_t>(p)] = sqrt_eps * (1.0 + std::abs(x[at]));
      hess_x_[at] = x[at] + hess_step_[static_cast<std::size_t>(p)];
    }
    if (!lagrangian_gradient(hess_x_.data(), sigma, lambda, hess_plus_.data())) return false;
    for (int p = 0; p < points_; ++p) {
      const std::size_t base = static_cast<std::size_t>(p) * w;
      hess_x_[base + c] = x[base + c];
      double* block = hess_blocks_.data() + base * w;
      for (std::size_t i = 0; i < w; ++i)
        block[c * w + i] = (hess_plus_[base + i] - hess_minus_[base + i]) / hess_step_[static_cast<std::size_t>(p)];
    }
  }
  std::size_t at = 0;
  for (int p = 0; p < points_; ++p) {
    const double* block = hess_blocks_.data() + static_cast<std::size_t>(p) * w * w;
    for (std::size_t i = 0; i < w; ++i)
      for (std::size_t j = 0; j <= i; ++j) values[at++] = 0.5 * (block[j * w + i] + block[i * w + j]);
  }
  if (problem_.free_time) {
    const std::size_t T = static_cast<std::size_t>(duration_index());
    const double step = sqrt_eps * (1.0 + std::abs(x[T]));
    hess_x_[T] = x[T] + step;
    if (!lagrangian_gradient(hess_x_.data(), sigma, lambda, hess_plus_.data())) return false;
    hess_x_[T] = x[T];
    for (std::size_t c = 0; c <= T; ++c) values[at++] = (hess_plus_[c] - hess_minus_[c]) / step;
  }
  for (std::size_t i = 0; i < at; ++i)
    if (!std::isfinite(values[i])) return false;
  return true;
}

double Transcription::constraint_violation(const double* x) {
  double worst = 0.0;
  for (int i = 0; i < variables_; ++i)
    worst = std::max({worst, x_lower_[static_cast<std::size_t>(i)] - x[i], x[i] - x_upper_[static_cast<std::size_t>(i)]});
  std::vector<double> g(static_cast<std::size_t>(rows_)), lo(g.size()), hi(g.size());
  std::vector<double> xl(static_cast<std::size_t>(variables_)), xu(xl.size());
  if (!constraint_values(x, g.data())) return std::numeric_limits<double>::infinity();
  bounds(xl.data(), xu.data(), lo.data(), hi.data());
  for (std::size_t r = 0; r < g.size(); ++r) worst = std::max({worst, lo[r] - g[r], g[r] - hi[r]});
  return worst;
}

}  // namespace nhdyn
