#include "nhdyn/analysis/linearization.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>

#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
#include "nhdyn/model/tape.hpp"
#include "nhdyn/model/detail/tape_tangent.hpp"

namespace nhdyn {
namespace {

using Index = Eigen::Index;

// Everything the linearization differentiates, as one flat vector: the terms A (n x n,
// col-major), Q, G, b (s x n, col-major), b0 — the order of the terms tape's outputs — then
// the position residuals phi (p) and the velocity residuals f (r).
struct Layout {
  int n = 0, s = 0, p = 0, r = 0;
  Index A() const { return 0; }
  Index Q() const { return n * n; }
  Index G() const { return Q() + n; }
  Index b() const { return G() + n; }
  Index b0() const { return b() + s * n; }
  Index phi() const { return b0() + s; }
  Index f() const { return phi() + p; }
  Index size() const { return f() + r; }
  Index terms() const { return phi(); }
};

// The inputs are numbered as a tape's registers: 0 is t, 1 + i is q_i, 1 + n + i is q'_i.
class Differentiator {
 public:
  Differentiator(const Model& model, const Layout& layout, double t, const Vector& q, const Vector& v)
      : model_(model), layout_(layout), t_(t), q_(q), v_(v) {
    tapes_ = dynamic_cast<const TapeEvaluator*>(model.evaluator.get());
    scratch_.assign(model.evaluator->scratch_size(), 0.0);
    if (tapes_ != nullptr) {
      const ModelTapes& p = tapes_->tapes();
      for (const Tape* tape : {&p.terms, &p.position_residual, &p.velocity_residual}) {
        values_.emplace_back(static_cast<std::size_t>(tape->registers()), 0.0);
        tape->execute(t, q.data(), v.data(), values_.back().data());
      }
      std::size_t largest = 0;
      for (const std::vector<double>& r : values_) largest = std::max(largest, r.size());
      tangents_.assign(largest, 0.0);
    }
  }

  DerivativeMethod method() const { return tapes_ != nullptr ? DerivativeMethod::tangent : DerivativeMethod::richardson; }

  // The flat vector at (t, q, v).
  void evaluate(double t, const Vector& q, const Vector& v, Vector& out) {
    out.resize(layout_.size());
    const TermsOut terms{out.data() + layout_.A(), out.data() + layout_.Q(), out.data() + layout_.G(),
                         out.data() + layout_.b(), out.data() + layout_.b0()};
    model_.evaluator->terms(t, q.data(), v.data(), scratch_.data(), terms);
    if (layout_.p > 0) model_.evaluator->position_residual(t, q.data(), scratch_.data(), out.data() + layout_.phi());
    if (layout_.r > 0)
      model_.evaluator->velocity_residual(t, q.data(), v.data(), scratch_.data(), out.data() + layout_.f());
  }

  // d(flat)/d(input): exact by the tangent mode, or Richardson-extrapolated central differences
  // (error O(h^4) + round-off / h with h = 1e-3 max(1, |x|)).
  void derivative(int input, Vector& out) {
    const int n = layout_.n;
    out.setZero(layout_.size());
    if (tapes_ != nullptr) {
      dq_.setZero(n);
      dv_.setZero(n);
      double dt = 0.0;
      if (input == 0)
        dt = 1.0;
      else if (input <= n)
        dq_(input - 1) = 1.0;
      else
        dv_(input - 1 - n) = 1.0;
      const ModelTapes& p = tapes_->tapes();
      if (const TermsSparsity* sparsity = tapes_->sparsity()) {
        // A tape compiled sparse writes only the nonzeros of A and b (model/sparsity.hpp):
        // its tangent comes in that layout and is scattered into the dense one of Layout.
        const int a_nz = sparsity->A.nonzeros(), b_nz = sparsity->b.nonzeros();
        sparse_tangent_.resize(static_cast<std::size_t>(a_nz + 2 * n + b_nz + layout_.s));
        run_tangent(p.terms, values_[0].data(), dt, dq_.data(), dv_.data(), tangents_.data(), sparse_tangent_.data());
        const double* a_values = sparse_tangent_.data();
        const double* qg_values = a_values + a_nz;
        const double* b_values = qg_values + 2 * n;
        const double* b0_values = b_values + b_nz;
        scatter(sparsity->A, a_values, out.data() + layout_.A());
        std::copy(qg_values, qg_values + 2 * n, out.data() + layout_.Q());
        scatter(sparsity->b, b_values, out.data() + layout_.b());
        std::copy(b0_values, b0_values + layout_.s, out.data() + layout_.b0());
      } else {
        run_tangent(p.terms, values_[0].data(), dt, dq_.data(), dv_.data(), tangents_.data(), out.data());
      }
      if (layout_.p > 0)
        run_tangent(p.position_residual, values_[1].data(), dt, dq_.data(), nullptr, tangents_.data(),
                    out.data() + layout_.phi());
      if (layout_.r > 0)
        run_tangent(p.velocity_residual, values_[2].data(), dt, dq_.data(), dv_.data(), tangents_.data(),
                    out.data() + layout_.f());
      return;
    }
    const double x = input == 0 ? t_ : input <= n ? q_(input - 1) : v_(input - 1 - n);
    const double h = 1e-3 * std::max(1.0, std::abs(x));
    const Vector d1 = central(input, h), d2 = central(input, h / 2);
    out = (4.0 * d2 - d1) / 3.0;
  }

 private:
  Vector central(int input, double h) {
    const int n = layout_.n;
    double t = t_;
    Vector q = q_, v = v_;
    Vector plus, minus;
    const auto shift = [&](double by) {
      t = t_;
      q = q_;
      v = v_;
      if (input == 0)
        t += by;
      else if (input <= n)
        q(input - 1) += by;
      else
        v(input - 1 - n) += by;
    };
    shift(h);
    evaluate(t, q, v, plus);
    shift(-h);
    evaluate(t, q, v, minus);
    return (plus - minus) / (2.0 * h);
  }

  // The values of a compressed-column pattern into a dense column-major matrix (zero elsewhere).
  static void scatter(const SparsityPattern& pattern, const double* values, double* dense) {
    const Index rows = pattern.rows;
    std::fill(dense, dense + rows * pattern.cols, 0.0);
    for (int j = 0; j < pattern.cols; ++j)
      for (int k = pattern.outer[static_cast<std::size_t>(j)]; k < pattern.outer[static_cast<std::size_t>(j) + 1]; ++k)
        dense[j * rows + pattern.inner[static_cast<std::size_t>(k)]] = values[k];
  }

  const Model& model_;
  Layout layout_;
  double t_;
  Vector q_, v_;
  const TapeEvaluator* tapes_ = nullptr;
  std::vector<double> scratch_;
  std::vector<std::vector<double>> values_;
  std::vector<double> tangents_;
  std::vector<double> sparse_tangent_;  // the tangent of a terms tape compiled sparse
  Vector dq_, dv_;
};

// Which inputs the terms and residuals depend on: structurally for compiled tapes, else by
// differences at the state and at two shifted values of the input (a hand-written model).
std::vector<char> find_dependence(const Model& model, const Layout& layout, Differentiator& diff, const Vector& q,
                                  const Vector& v) {
  const int n = layout.n;
  std::vector<char> depends(static_cast<std::size_t>(1 + 2 * n), 0);
  if (const auto* pe = dynamic_cast<const TapeEvaluator*>(model.evaluator.get())) {
    const ModelTapes& p = pe->tapes();
    // Time: any tape. Coordinates: the terms and the velocity residuals only — a position
    // residual may depend on a coordinate whose gradient is constant (x - r theta), and what the
    // linearization needs of it, its gradient, is a row of b, which the terms carry.
    const std::vector<char> terms = calc_input_dependence(p.terms);
    const std::vector<char> velocity = calc_input_dependence(p.velocity_residual);
    const std::vector<char> position = calc_input_dependence(p.position_residual);
    for (std::size_t i = 0; i < depends.size(); ++i) depends[i] = terms[i] || velocity[i];
    depends[0] = depends[0] || position[0];
    return depends;
  }
  Vector base, d;
  diff.evaluate(model.t0, q, v, base);
  const double scale = 1e-9 * std::max(1.0, base.head(layout.terms()).lpNorm<Eigen::Infinity>());
  for (int input = 0; input <= n; ++input) {  // t and the coordinates
    for (double offset : {0.0, 0.7, -1.3}) {
      Vector qs = q;
      double t = model.t0;
      if (input == 0)
        t += offset;
      else
        qs(input - 1) += offset;
      Differentiator shifted(model, layout, t, qs, v);
      shifted.derivative(input, d);
      // The residual values themselves may move with a cyclic coordinate; their gradient is in b.
      if (d.head(layout.terms()).lpNorm<Eigen::Infinity>() > scale ||
          (layout.r > 0 && d.segment(layout.f(), layout.r).lpNorm<Eigen::Infinity>() > scale) ||
          (input == 0 && layout.p > 0 && d.segment(layout.phi(), layout.p).lpNorm<Eigen::Infinity>() > scale))
        depends[static_cast<std::size_t>(input)] = 1;
    }
  }
  return depends;
}

int find_coordinate(const Model& model, const std::string& name, const char* option) {
  for (int i = 0; i < model.n(); ++i)
    if (model.coordinates[static_cast<std::size_t>(i)] == name) return i;
  std::string list;
  for (const std::string& c : model.coordinates) list += (list.empty() ? "" : ", ") + c;
  throw InputError(fmt::format("{}: '{}' is not a coordinate of model '{}'; its coordinates are: {}", option, name,
                               model.name, list));
}

int rank_of(const Matrix& m) {
  if (m.rows() == 0 || m.cols() == 0) return 0;
  Eigen::ColPivHouseholderQR<Matrix> qr(m);
  qr.setThreshold(1e-10);
  return static_cast<int>(qr.rank());
}

// The columns of `m` in the order a column-pivoted QR takes them (best conditioned first).
std::vector<int> pivot_order(const Matrix& m) {
  std::vector<int> order;
  if (m.cols() == 0) return order;
  if (m.rows() == 0) {
    for (Index j = 0; j < m.cols(); ++j) order.push_back(static_cast<int>(j));
    return order;
  }
  Eigen::ColPivHouseholderQR<Matrix> qr(m);
  const auto& perm = qr.colsPermutation().indices();
  for (Index j = 0; j < perm.size(); ++j) order.push_back(perm(j));
  return order;
}

Matrix columns(const Matrix& m, const std::vector<int>& cols) {
  Matrix out(m.rows(), static_cast<Index>(cols.size()));
  for (std::size_t j = 0; j < cols.size(); ++j) out.col(static_cast<Index>(j)) = m.col(cols[j]);
  return out;
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& s : names) out += (out.empty() ? "" : ", ") + s;
  return out.empty() ? "(none)" : out;
}

}  // namespace

const char* derivative_method_name(DerivativeMethod method) {
  return method == DerivativeMethod::tangent ? "exact (tangent mode of the compiled tapes)"
                                             : "Richardson-extrapolated central differences (hand-written model)";
}

void sort_eigenvalues(std::vector<std::complex<double>>& eigenvalues) {
  std::sort(eigenvalues.begin(), eigenvalues.end(), [](const std::complex<double>& a, const std::complex<double>& b) {
    if (a.real() != b.real()) return a.real() > b.real();
    return a.imag() > b.imag();
  });
}

namespace {

// --- cyclic coordinates, named and found; explicit time dependence ---------------------------
// Marks the cyclic coordinates (named, and found when options.detect_cyclic), names them in
// out.cyclic and returns the flags; throws when the model reads t explicitly.
std::vector<char> find_cyclic(const Model& model, const Layout& layout, Differentiator& diff,
                              const LinearizationOptions& options, Linearization& out) {
  const int n = layout.n;
  std::vector<char> cyclic(static_cast<std::size_t>(n), 0);
  for (const std::string& c : options.cyclic) cyclic[static_cast<std::size_t>(find_coordinate(model, c, "--cyclic"))] = 1;
  const std::vector<char> depends = find_dependence(model, layout, diff, model.q0, model.v0);
  if (depends[0])
    throw ModelError(fmt::format("model '{}' depends on time t explicitly (its terms or constraints read t), so a "
                                 "motion of it has no constant linearization; describe it in coordinates in which "
                                 "it is autonomous (a rotating frame for a prescribed rotation, say)",
                                 model.name));
  if (options.detect_cyclic)
    for (int i = 0; i < n; ++i)
      if (!depends[static_cast<std::size_t>(1 + i)]) cyclic[static_cast<std::size_t>(i)] = 1;
  for (int i = 0; i < n; ++i)
    if (cyclic[static_cast<std::size_t>(i)]) out.cyclic.push_back(model.coordinates[static_cast<std::size_t>(i)]);
  return cyclic;
}

// --- the state: constraints, then q'' and the multipliers from the KKT form ----------------
// Throws when the terms and residuals `base` at the initial state show a violated constraint.
void require_constraints_met(const Model& model, const Layout& layout, const Vector& base, double tol) {
  const Vector& v = model.v0;
  int pos = 0, vel = 0;
  for (int i = 0; i < layout.s; ++i) {
    const Constraint& c = model.constraints[static_cast<std::size_t>(i)];
    if (c.level == ConstraintLevel::acceleration) continue;
    if (c.level == ConstraintLevel::position) {
      const double r = base(layout.phi() + pos++);
      if (!(std::abs(r) <= tol))
        throw ModelError(fmt::format("the initial state violates the constraint '{}' at position level by {:.3e} "
                                     "(tolerance {:g}); a steady motion must satisfy the constraints: correct the "
                                     "initial state (or simulate with --fix-initial to see the nearest one)",
                                     c.name, r, tol));
    }
    const double r = base(layout.f() + vel++);
    if (!(std::abs(r) <= tol * std::max(1.0, v.lpNorm<Eigen::Infinity>())))
      throw ModelError(fmt::format("the initial state violates the constraint '{}' at velocity level by {:.3e} "
                                   "(tolerance {:g}); a steady motion must satisfy the constraints: correct the "
                                   "initial velocities",
                                   c.name, r, tol));
  }
}

// The KKT form [A b^T; b 0] (q'', mu) = (Q + G, -b0) at the initial state, factored once: its
// solution gives q'' (into out.qdd) and the multipliers mu; its factors serve the derivatives.
struct KktSolution {
  Eigen::FullPivLU<Matrix> kkt;
  Vector mu;  // s, A q'' + b^T mu = Q + G
};

KktSolution solve_kkt(const Model& model, const Layout& layout, const Vector& base, Linearization& out) {
  const int n = layout.n, s = layout.s;
  const Eigen::Map<const Matrix> A(base.data() + layout.A(), n, n);
  const Eigen::Map<const Vector> Q(base.data() + layout.Q(), n), G(base.data() + layout.G(), n);
  const Eigen::Map<const Matrix> b(base.data() + layout.b(), s, n);
  const Eigen::Map<const Vector> b0(base.data() + layout.b0(), s);
  Matrix K = Matrix::Zero(n + s, n + s);
  K.topLeftCorner(n, n) = A;
  K.topRightCorner(n, s) = b.transpose();
  K.bottomLeftCorner(s, n) = b;
  KktSolution out_kkt{Eigen::FullPivLU<Matrix>(K), Vector()};
  if (!out_kkt.kkt.isInvertible())
    throw ModelError(fmt::format("model '{}': the KKT matrix [A b^T; b 0] is singular at the initial state (A not "
                                 "positive definite on the constraints, or dependent constraints)",
                                 model.name));
  // The inertia test simulate applies (formulation/diagnosis.hpp): a regular KKT matrix with an A
  // indefinite on the constraints gave the eigenvalues of a motion that does not exist, and in a
  // sweep, an eigenvalue through the pole where A turns singular reported as a crossing of zero.
  if (double smallest = 0.0; !inertia_positive_on_constraints(A, b, smallest))
    throw ModelError(fmt::format("model '{}': the inertia matrix A is not positive definite at the initial state, not even "
                                 "on the velocities the constraints allow (smallest eigenvalue {:.6g}): check the kinetic "
                                 "energy, its masses and inertias",
                                 model.name, smallest));
  Vector rhs(n + s);
  rhs.head(n) = Q + G;
  rhs.tail(s) = -b0;
  const Vector sol = out_kkt.kkt.solve(rhs);
  out.qdd = sol.head(n);
  out_kkt.mu = sol.tail(s);
  return out_kkt;
}

// --- steady? every non-cyclic velocity and every acceleration zero -----------------------------
// Sets out.steady_residual; throws naming the largest violation when it is over the tolerance.
void require_steady(const Model& model, const Layout& layout, const Vector& base, const std::vector<int>& nc,
                    const LinearizationOptions& options, Linearization& out) {
  const int n = layout.n;
  const Vector& v = model.v0;
  const auto name = [&](int i) { return model.coordinates[static_cast<std::size_t>(i)]; };
  const Eigen::Map<const Matrix> A(base.data() + layout.A(), n, n);
  const Eigen::Map<const Vector> Q(base.data() + layout.Q(), n), G(base.data() + layout.G(), n);
  double accel_scale = 1.0;
  for (int i = 0; i < n; ++i)
    if (A(i, i) > 0.0) accel_scale = std::max(accel_scale, std::abs(Q(i) + G(i)) / A(i, i));
  const double vel_scale = std::max(1.0, v.lpNorm<Eigen::Infinity>());
  struct Violation {
    std::string what;
    double value, ratio;
  };
  std::vector<Violation> bad;
  for (int i : nc) {
    const double ratio = std::abs(v(i)) / vel_scale;
    out.steady_residual = std::max(out.steady_residual, ratio);
    if (ratio > options.steady_tolerance)
      bad.push_back({fmt::format("velocity {}' = {:.6g} (a non-cyclic coordinate must be at rest)", name(i), v(i)),
                     v(i), ratio});
  }
  for (int i = 0; i < n; ++i) {
    const double ratio = std::abs(out.qdd(i)) / accel_scale;
    out.steady_residual = std::max(out.steady_residual, ratio);
    if (ratio > options.steady_tolerance)
      bad.push_back({fmt::format("acceleration {}'' = {:.6g}", name(i), out.qdd(i)), out.qdd(i), ratio});
  }
  if (bad.empty()) return;
  std::stable_sort(bad.begin(), bad.end(), [](const Violation& a, const Violation& b) { return a.ratio > b.ratio; });
  std::string list;
  for (const Violation& x : bad) list += "; " + x.what;
  throw ModelError(fmt::format(
      "the initial state of model '{}' is not a steady motion: the largest violation is {} (tolerance {:g} x "
      "scale {:.3g}){}. A steady motion keeps every non-cyclic coordinate at rest and every velocity constant "
      "(cyclic coordinates: {}); set the initial state to one (--set), or name the coordinates that may move "
      "steadily with --cyclic",
      model.name, bad.front().what, options.steady_tolerance,
      bad.front().what.starts_with("velocity") ? vel_scale : accel_scale,
      bad.size() > 1 ? " (all violations: " + list.substr(2) + ")" : std::string(), join(out.cyclic)));
}

// --- derivatives: dq''/dq, dq''/dq' and the constraint Jacobians --------------------------------
// The Jacobians of the position residuals (p x n) and of the velocity residuals (r x n, by q and
// by q'); dq''/dq and dq''/dq' go into out.Fq and out.Fv.
struct ConstraintJacobians {
  Matrix Jphi, Cq, Cv;
};

ConstraintJacobians differentiate(const Model& model, const Layout& layout, Differentiator& diff,
                                  const KktSolution& solved, Linearization& out) {
  const int n = layout.n, s = layout.s;
  out.Fq.setZero(n, n);
  out.Fv.setZero(n, n);
  ConstraintJacobians jac{Matrix::Zero(layout.p, n), Matrix::Zero(layout.r, n), Matrix::Zero(layout.r, n)};
  Vector d, drhs(n + s);
  for (int input = 1; input <= 2 * n; ++input) {
    diff.derivative(input, d);
    const Eigen::Map<const Matrix> dA(d.data() + layout.A(), n, n);
    const Eigen::Map<const Vector> dQ(d.data() + layout.Q(), n), dG(d.data() + layout.G(), n);
    const Eigen::Map<const Matrix> db(d.data() + layout.b(), s, n);
    const Eigen::Map<const Vector> db0(d.data() + layout.b0(), s);
    // K d(q'', mu) = d(rhs) - dK (q'', mu): docs/linearization.md (2).
    drhs.head(n) = dQ + dG - dA * out.qdd - db.transpose() * solved.mu;
    drhs.tail(s) = -db0 - db * out.qdd;
    const Vector dsol = solved.kkt.solve(drhs);
    const bool coordinate = input <= n;
    const int j = coordinate ? input - 1 : input - 1 - n;
    (coordinate ? out.Fq : out.Fv).col(j) = dsol.head(n);
    if (coordinate && layout.p > 0) jac.Jphi.col(j) = d.segment(layout.phi(), layout.p);
    if (layout.r > 0) (coordinate ? jac.Cq : jac.Cv).col(j) = d.segment(layout.f(), layout.r);
  }
  if (!out.Fq.allFinite() || !out.Fv.allFinite())
    throw ModelError(fmt::format("model '{}': the derivatives of q'' are not finite at the initial state", model.name));
  return jac;
}

// --- perturbations y = (dq_nc, dv) on the linearized constraints C y = 0 ----------------------
// Which non-cyclic coordinates (flags indexed into nc) are dependent: those not named by
// --independent, else the first rank_p columns of Jp in pivoted-QR order.
std::vector<char> choose_dependent_coordinates(const Model& model, const LinearizationOptions& options,
                                               const std::vector<int>& nc, const Matrix& Jp, int rank_p,
                                               const Linearization& out) {
  const int m = static_cast<int>(nc.size());
  std::vector<char> dep_coord(static_cast<std::size_t>(m), 0);
  if (!options.independent.empty()) {
    std::vector<char> named(static_cast<std::size_t>(m), 0);
    for (const std::string& x : options.independent) {
      const int i = find_coordinate(model, x, "--independent");
      const auto it = std::find(nc.begin(), nc.end(), i);
      if (it == nc.end())
        throw InputError(fmt::format("--independent: '{}' is cyclic (cyclic coordinates: {}), so it is not part of "
                                     "the state; name non-cyclic coordinates",
                                     x, join(out.cyclic)));
      char& flag = named[static_cast<std::size_t>(it - nc.begin())];
      if (flag) throw InputError(fmt::format("--independent: '{}' is named twice", x));
      flag = 1;
    }
    if (static_cast<int>(options.independent.size()) != m - rank_p)
      throw InputError(fmt::format("--independent names {} coordinate(s), but the state has {} independent "
                                   "coordinate(s) ({} non-cyclic coordinates, {} independent position constraints)",
                                   options.independent.size(), m - rank_p, m, rank_p));
    for (int a = 0; a < m; ++a) dep_coord[static_cast<std::size_t>(a)] = !named[static_cast<std::size_t>(a)];
  } else {
    const std::vector<int> order = pivot_order(Jp);
    for (int k = 0; k < rank_p; ++k) dep_coord[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = 1;
  }
  return dep_coord;
}

// Which speeds (flags indexed by coordinate) are dependent: those not named by --speeds, else
// rank_v of them chosen greedily.
std::vector<char> choose_dependent_speeds(const Model& model, const LinearizationOptions& options,
                                          const std::vector<char>& cyclic, const Matrix& Cv, int rank_v) {
  const int n = model.n();
  std::vector<char> dep_speed(static_cast<std::size_t>(n), 0);
  if (!options.speeds.empty()) {
    std::vector<char> named(static_cast<std::size_t>(n), 0);
    for (const std::string& x : options.speeds) {
      const int i = find_coordinate(model, x.ends_with("'") ? x.substr(0, x.size() - 1) : x, "--speeds");
      char& flag = named[static_cast<std::size_t>(i)];
      if (flag) throw InputError(fmt::format("--speeds: '{}' is named twice", x));
      flag = 1;
    }
    if (static_cast<int>(options.speeds.size()) != n - rank_v)
      throw InputError(fmt::format("--speeds names {} speed(s), but the state has {} independent speed(s) ({} "
                                   "coordinates, {} independent velocity-level constraints)",
                                   options.speeds.size(), n - rank_v, n, rank_v));
    for (int i = 0; i < n; ++i) dep_speed[static_cast<std::size_t>(i)] = !named[static_cast<std::size_t>(i)];
  } else {
    // Greedy: cyclic velocities first (they feed nothing back), each group in pivoted-QR order.
    std::vector<int> candidates;
    for (int group = 0; group < 2; ++group) {
      std::vector<int> members;
      for (int i = 0; i < n; ++i)
        if ((cyclic[static_cast<std::size_t>(i)] != 0) == (group == 0)) members.push_back(i);
      for (int k : pivot_order(columns(Cv, members))) candidates.push_back(members[static_cast<std::size_t>(k)]);
    }
    std::vector<int> chosen;
    for (int c : candidates) {
      if (static_cast<int>(chosen.size()) == rank_v) break;
      chosen.push_back(c);
      if (rank_of(columns(Cv, chosen)) < static_cast<int>(chosen.size())) chosen.pop_back();
    }
    for (int c : chosen) dep_speed[static_cast<std::size_t>(c)] = 1;
  }
  return dep_speed;
}

// T with y_dep = T y_ind on C y = 0 (C's columns split into CD, dependent, and CI); `names` are the
// dependent entries' names, for the messages.
Matrix express_dependent(const Matrix& CD, const Matrix& CI, const std::vector<std::string>& names) {
  Eigen::ColPivHouseholderQR<Matrix> qr(CD);
  qr.setThreshold(1e-10);
  if (qr.rank() < CD.cols())
    throw InputError(fmt::format("the dependent coordinates and speeds ({}) cannot be expressed through the "
                                 "independent ones: the constraints do not fix them; name other independent "
                                 "coordinates (--independent) or speeds (--speeds)",
                                 join(names)));
  Matrix T = qr.solve(Matrix(-CI));
  const double defect = (CD * T + CI).lpNorm<Eigen::Infinity>();
  if (!(defect <= 1e-8 * std::max(1.0, CI.lpNorm<Eigen::Infinity>())))
    throw InputError(fmt::format("the linearized constraints cannot be satisfied with the dependent coordinates "
                                 "and speeds ({}) alone (defect {:.3e}); name other independent coordinates or "
                                 "speeds",
                                 join(names), defect));
  return T;
}

// The state matrix of the independent perturbations, their names and its eigenvalues (into
// out), from dq''/dq and dq''/dq' (out.Fq, out.Fv) and the constraint Jacobians.
void reduce_to_independent(const Model& model, const LinearizationOptions& options, const std::vector<char>& cyclic,
                           const std::vector<int>& nc, const ConstraintJacobians& jac, Linearization& out) {
  const int n = model.n();
  const int p = static_cast<int>(jac.Jphi.rows()), r = static_cast<int>(jac.Cv.rows());
  const auto name = [&](int i) { return model.coordinates[static_cast<std::size_t>(i)]; };
  const int m = static_cast<int>(nc.size());
  const int N = m + n;
  const int rows = p + r;
  Matrix C = Matrix::Zero(rows, N);
  for (int a = 0; a < m; ++a) {
    if (p > 0) C.block(0, a, p, 1) = jac.Jphi.col(nc[static_cast<std::size_t>(a)]);
    if (r > 0) C.block(p, a, r, 1) = jac.Cq.col(nc[static_cast<std::size_t>(a)]);
  }
  if (r > 0) C.block(p, m, r, n) = jac.Cv;
  Matrix J = Matrix::Zero(N, N);
  for (int a = 0; a < m; ++a) {
    J(a, m + nc[static_cast<std::size_t>(a)]) = 1.0;
    J.block(m, a, n, 1) = out.Fq.col(nc[static_cast<std::size_t>(a)]);
  }
  J.block(m, m, n, n) = out.Fv;

  // Dependent coordinates (indices into nc) and speeds (coordinate indices).
  Matrix Jp = Matrix::Zero(p, m);
  for (int a = 0; a < m; ++a)
    if (p > 0) Jp.col(a) = jac.Jphi.col(nc[static_cast<std::size_t>(a)]);
  const int rank_p = rank_of(Jp);
  const int rank_v = rank_of(jac.Cv);
  const std::vector<char> dep_coord = choose_dependent_coordinates(model, options, nc, Jp, rank_p, out);
  const std::vector<char> dep_speed = choose_dependent_speeds(model, options, cyclic, jac.Cv, rank_v);

  std::vector<int> ind, dep;  // into y
  for (int a = 0; a < m; ++a) (dep_coord[static_cast<std::size_t>(a)] ? dep : ind).push_back(a);
  for (int i = 0; i < n; ++i) (dep_speed[static_cast<std::size_t>(i)] ? dep : ind).push_back(m + i);
  const Matrix CD = columns(C, dep), CI = columns(C, ind);
  Matrix T = Matrix::Zero(static_cast<Index>(dep.size()), static_cast<Index>(ind.size()));
  if (!dep.empty()) {
    std::vector<std::string> names;
    for (int y : dep) names.push_back(y < m ? name(nc[static_cast<std::size_t>(y)]) : name(y - m) + "'");
    T = express_dependent(CD, CI, names);
  } else if (rows > 0 && rank_of(C) > 0) {
    throw InputError("the linearized constraints leave no dependent coordinate or speed; name fewer independent ones");
  }
  const Index k = static_cast<Index>(ind.size());
  Matrix E = Matrix::Zero(N, k);
  for (Index j = 0; j < k; ++j) E(ind[static_cast<std::size_t>(j)], j) = 1.0;
  for (std::size_t row = 0; row < dep.size(); ++row) E.row(dep[row]) = T.row(static_cast<Index>(row));
  Matrix JE = J * E;
  out.state_matrix.resize(k, k);
  for (Index j = 0; j < k; ++j) out.state_matrix.row(j) = JE.row(ind[static_cast<std::size_t>(j)]);
  for (int y : ind) {
    if (y < m) {
      out.independent.push_back(name(nc[static_cast<std::size_t>(y)]));
      out.state.push_back(out.independent.back());
    } else {
      out.speeds.push_back(name(y - m));
      out.state.push_back(out.speeds.back() + "'");
    }
  }
  if (k > 0) {
    Eigen::EigenSolver<Matrix> eigen(out.state_matrix, false);
    if (eigen.info() != Eigen::Success)
      throw ModelError(fmt::format("model '{}': the eigenvalues of the state matrix did not converge", model.name));
    for (Index j = 0; j < k; ++j) out.eigenvalues.push_back(eigen.eigenvalues()(j));
    sort_eigenvalues(out.eigenvalues);
  }
}

}  // namespace

Linearization calc_linearization(const Model& model, const LinearizationOptions& options) {
  check_model_shape(model);
  require_fewer_constraints(model, "a linearization");
  if (model.m() > 0)
    throw InputError(fmt::format("model '{}' has programs ([[programs]]); linearization does not take their actuator "
                                 "forces into account: remove the programs to linearize the free system",
                                 model.name));
  const int n = model.n();
  Layout layout;
  layout.n = n;
  layout.s = model.s();
  layout.p = model.position_constraints();
  layout.r = model.velocity_constraints();
  if (!(options.steady_tolerance > 0.0) || !std::isfinite(options.steady_tolerance))
    throw InputError(fmt::format("the steady-motion tolerance must be a positive number, not {}", options.steady_tolerance));

  Differentiator diff(model, layout, model.t0, model.q0, model.v0);
  Linearization out;
  out.derivatives = diff.method();
  const std::vector<char> cyclic = find_cyclic(model, layout, diff, options, out);
  std::vector<int> nc;  // the non-cyclic coordinates
  for (int i = 0; i < n; ++i)
    if (!cyclic[static_cast<std::size_t>(i)]) nc.push_back(i);

  Vector base;
  diff.evaluate(model.t0, model.q0, model.v0, base);
  if (!base.allFinite())
    throw ModelError(fmt::format("model '{}': a term or residual is not finite at the initial state", model.name));
  require_constraints_met(model, layout, base, options.steady_tolerance);
  const KktSolution solved = solve_kkt(model, layout, base, out);
  require_steady(model, layout, base, nc, options, out);
  const ConstraintJacobians jac = differentiate(model, layout, diff, solved, out);
  reduce_to_independent(model, options, cyclic, nc, jac, out);
  return out;
}

}  // namespace nhdyn
