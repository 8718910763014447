#include "nhdyn/symbolic/derivation.hpp"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/symbolic/detail/derivative.hpp"
#include "nhdyn/symbolic/detail/occurrence.hpp"
#include "nhdyn/symbolic/detail/pairs.hpp"
#include "nhdyn/symbolic/contact_modes.hpp"
#include "nhdyn/symbolic/rolling_contact.hpp"
#include "nhdyn/symbolic/simplify.hpp"

namespace nhdyn::symbolic {
namespace {

std::string prefix(const SourceLocation& where) {
  const std::string location = where.describe();
  return location.empty() ? "" : location + ": ";
}

std::string printed(const GiNaC::ex& e) {
  std::ostringstream out;
  out << e;
  return out.str();
}

// The total time derivative of an expression in (t, q, q') along the motion, without the terms
// in q'': sum_i (de/dq_i) q'_i + de/dt. (The q'' terms are sum_i (de/dq'_i) q''_i.) Only the
// coordinates that e contains are differentiated by.
GiNaC::ex convective_derivative(const GiNaC::ex& e, const SymbolTable& symbols, const SymbolIndex& index) {
  const Contained o = index.find(e);
  GiNaC::ex out = o.time ? detail::derivative_of_container(e, symbols.time()) : GiNaC::ex(0);
  for (int i : o.q) out += detail::derivative_of_container(e, symbols.coordinate(i)) * symbols.velocity(i);
  return out;
}

// The terms of a sum (or the expression itself): each is differentiated only by what it contains.
// A product with one long sum among its factors, as a user writes T = m/2 * (x1'^2 + ... + xN'^2),
// is distributed first: left whole, it would be one term containing every velocity, and each of
// the n derivatives would walk all of it (n^2). Short sums (under kDistributeFrom terms) stay as
// written, so small models derive exactly as before.
constexpr std::size_t kDistributeFrom = 16;

void append_terms(const GiNaC::ex& e, std::vector<GiNaC::ex>& out) {
  if (GiNaC::is_exactly_a<GiNaC::add>(e)) {
    for (std::size_t i = 0; i < e.nops(); ++i) append_terms(e.op(i), out);
    return;
  }
  if (GiNaC::is_exactly_a<GiNaC::mul>(e)) {
    int sum_factor = -1;
    int sums = 0;
    for (std::size_t i = 0; i < e.nops(); ++i)
      if (GiNaC::is_exactly_a<GiNaC::add>(e.op(i))) {
        ++sums;
        sum_factor = static_cast<int>(i);
      }
    if (sums == 1 && e.op(static_cast<std::size_t>(sum_factor)).nops() >= kDistributeFrom) {
      GiNaC::ex rest = 1;
      for (std::size_t i = 0; i < e.nops(); ++i)
        if (static_cast<int>(i) != sum_factor) rest *= e.op(i);
      const GiNaC::ex sum = e.op(static_cast<std::size_t>(sum_factor));
      for (std::size_t i = 0; i < sum.nops(); ++i) append_terms(rest * sum.op(i), out);
      return;
    }
  }
  if (!e.is_zero()) out.push_back(e);
}

std::vector<GiNaC::ex> terms_of(const GiNaC::ex& e) {
  std::vector<GiNaC::ex> out;
  append_terms(e, out);
  return out;
}

// A sum split into its terms, with the terms that contain each coordinate and each velocity:
// d/dq_i of the sum is the sum of d/dq_i of those terms alone.
struct SplitSum {
  std::vector<GiNaC::ex> terms;
  std::vector<Contained> occurrences;        // per term
  std::vector<std::vector<int>> with_q, with_v;  // per coordinate: the terms containing q_i, q'_i

  SplitSum(const GiNaC::ex& e, const SymbolIndex& index, int n)
      : terms(terms_of(e)), with_q(static_cast<std::size_t>(n)), with_v(static_cast<std::size_t>(n)) {
    for (std::size_t j = 0; j < terms.size(); ++j) {
      occurrences.push_back(index.find(terms[j]));
      for (int i : occurrences.back().q) with_q[static_cast<std::size_t>(i)].push_back(static_cast<int>(j));
      for (int i : occurrences.back().v) with_v[static_cast<std::size_t>(i)].push_back(static_cast<int>(j));
    }
  }
  // The first index of `kind` (a, v...) that some term contains, or -1.
  template <class Member>
  int first(Member member) const {
    int out = -1;
    for (const Contained& o : occurrences)
      if (!(o.*member).empty() && (out < 0 || (o.*member).front() < out)) out = (o.*member).front();
    return out;
  }
  GiNaC::ex diff(const std::vector<std::vector<int>>& with, int i, const GiNaC::symbol& x) const {
    GiNaC::ex out = 0;
    for (int j : with[static_cast<std::size_t>(i)])
      out += detail::derivative_of_container(terms[static_cast<std::size_t>(j)], x);
    return out;
  }
};

// Terms of large models are simplified only up to a size (simplify_moderate, simplify.hpp).
GiNaC::ex tidy(const GiNaC::ex& e) { return simplify_moderate(e); }

// An analytic D must satisfy D b^T = 0 and make [D; b] invertible; checked at the initial state
// with the parameter values (a wrong D otherwise gives a wrong motion with no error). Entries that
// do not evaluate to finite reals there skip the check (they fail later, with their own message).
void require_complement_at_initial_state(const Spec& spec, const GiNaC::matrix& b, const GiNaC::matrix& D) {
  const unsigned k = D.rows(), n = D.cols(), s = b.rows();
  const GiNaC::lst values = spec.parameter_values();
  GiNaC::exmap at;
  at[spec.symbols.time()] = GiNaC::numeric(spec.t0);
  for (unsigned i = 0; i < n; ++i) {
    if (i < spec.q0.size()) at[spec.symbols.coordinate(static_cast<int>(i))] = spec.q0[i].subs(values);
    if (i < spec.v0.size()) at[spec.symbols.velocity(static_cast<int>(i))] = spec.v0[i].subs(values);
  }
  const auto value = [&](const GiNaC::ex& e, double& out) {
    try {
      const GiNaC::ex x = e.subs(at, GiNaC::subs_options::no_pattern).subs(values).subs(values).evalf();
      if (!GiNaC::is_a<GiNaC::numeric>(x) || !GiNaC::ex_to<GiNaC::numeric>(x).is_real()) return false;
      out = GiNaC::ex_to<GiNaC::numeric>(x).to_double();
      return std::isfinite(out);
    } catch (const std::exception&) {
      return false;
    }
  };
  Eigen::MatrixXd stacked(k + s, n);
  for (unsigned r = 0; r < k + s; ++r)
    for (unsigned j = 0; j < n; ++j)
      if (!value(r < k ? D(r, j) : b(r - k, j), stacked(r, j))) return;
  const Eigen::MatrixXd Dm = stacked.topRows(k), bm = stacked.bottomRows(s);
  const std::string where = prefix(spec.complement_where);
  if (s > 0) {
    const Eigen::MatrixXd residual = Dm * bm.transpose();
    Eigen::Index row = 0, col = 0;
    const double worst = residual.cwiseAbs().maxCoeff(&row, &col);
    const double scale = std::max(Dm.norm() * bm.norm(), 1e-300);
    if (worst > 1e-9 * scale)
      throw ModelError(fmt::format(
          "{}complement D: D b^T is not zero at the initial state: row {} of D against constraint '{}' gives {:.3g} "
          "(|D| |b| = {:.3g}); the rows of D must span the velocities the constraints allow (D b^T = 0): check D",
          where, row + 1,
          static_cast<std::size_t>(col) < spec.constraints.size() ? spec.constraints[static_cast<std::size_t>(col)].name
                                                                  : fmt::format("{}", col + 1),
          residual(row, col), scale));
  }
  const Eigen::VectorXd sigma = Eigen::JacobiSVD<Eigen::MatrixXd>(stacked).singularValues();
  if (sigma.size() > 0 && !(sigma(sigma.size() - 1) > 1e-10 * sigma(0)))
    throw ModelError(fmt::format(
        "{}complement D: D is rank deficient at the initial state: the stacked matrix [D; b] ({} x {}) has a "
        "singular value {:.3g} against the largest {:.3g}; the k = {} rows of D must be independent of each other "
        "and of the constraints: check D",
        where, k + s, n, sigma(sigma.size() - 1), sigma(0), k));
}

// The degree of `e` as a polynomial in the velocities, whatever its other factors; -1 when a
// velocity stands elsewhere than in sums, products and powers with a whole exponent (in a
// function's argument, a root, a denominator). GiNaC's degree() after q' -> lambda q' is at most
// this (it reads the same structure; terms may cancel).
int polynomial_velocity_degree(const GiNaC::ex& e, const SymbolIndex& index) {
  if (GiNaC::is_exactly_a<GiNaC::symbol>(e)) return index.is_velocity(e) ? 1 : 0;
  if (GiNaC::is_exactly_a<GiNaC::numeric>(e)) return 0;
  const bool sum = GiNaC::is_exactly_a<GiNaC::add>(e);
  if (sum || GiNaC::is_exactly_a<GiNaC::mul>(e)) {
    int out = 0;
    for (const GiNaC::expair& p : detail::Pairs::of(e)) {
      int d = polynomial_velocity_degree(p.rest, index);
      if (d < 0) return -1;
      if (!sum && d > 0) {  // a factor rest^k
        if (!p.coeff.info(GiNaC::info_flags::nonnegint)) return -1;
        d *= GiNaC::ex_to<GiNaC::numeric>(p.coeff).to_int();
      }
      out = sum ? std::max(out, d) : out + d;
    }
    return out;
  }
  if (GiNaC::is_exactly_a<GiNaC::power>(e)) {
    const int base = polynomial_velocity_degree(e.op(0), index);
    if (base < 0) return -1;
    if (GiNaC::is_exactly_a<GiNaC::numeric>(e.op(1)) && e.op(1).info(GiNaC::info_flags::nonnegint))
      return base * GiNaC::ex_to<GiNaC::numeric>(e.op(1)).to_int();
    return base == 0 && polynomial_velocity_degree(e.op(1), index) == 0 ? 0 : -1;
  }
  for (std::size_t i = 0; i < e.nops(); ++i)
    if (polynomial_velocity_degree(e.op(i), index) != 0) return -1;
  return 0;
}

// A kinetic energy of degree above 2 in the velocities is refused before its Hessian is formed:
// for a power such as (x'^2 + y'^2 + x + y)^40 the Hessian takes minutes to expand. degree() reads
// the unexpanded expression (a power's degree is its base's times the exponent), and a numeric
// third difference of T(lambda q') at a rational point confirms it, so that terms that cancel
// once multiplied out are not refused.
void require_at_most_quadratic(const Spec& spec, const SymbolIndex& index, const std::string& model) {
  // What the test below concludes for a polynomial of degree 2 or less, without the substitution
  // into all of T (a fortieth of a long chain's start-up).
  if (const int d = polynomial_velocity_degree(spec.kinetic_energy, index); d >= 0 && d <= 2) return;
  const SymbolTable& symbols = spec.symbols;
  const GiNaC::symbol lambda("velocity_scale");
  GiNaC::exmap scaled;
  for (int i = 0; i < spec.n(); ++i) scaled[symbols.velocity(i)] = lambda * symbols.velocity(i);
  int degree = 0;
  try {
    // no_pattern: the keys are symbols, so a map lookup per node finds them; GiNaC's default tries
    // every key as a pattern at every node, n times the size of T (minutes for a long chain).
    degree = spec.kinetic_energy.subs(scaled, GiNaC::subs_options::no_pattern).degree(lambda);
  } catch (const std::exception&) {
    return;  // not a polynomial in lambda: left to the derivation's own check
  }
  if (degree <= 2) return;
  GiNaC::exmap point;
  for (int i = 0; i < spec.n(); ++i) {
    point[symbols.coordinate(i)] = GiNaC::numeric(i % 7 + 1, 11);
    point[symbols.velocity(i)] = GiNaC::numeric(i % 5 + 2, 13);
  }
  point[symbols.time()] = GiNaC::numeric(1, 17);
  const GiNaC::lst values = spec.parameter_values();
  std::vector<double> f;
  try {
    const GiNaC::ex at = spec.kinetic_energy.subs(scaled, GiNaC::subs_options::no_pattern)
                             .subs(point, GiNaC::subs_options::no_pattern)
                             .subs(values)
                             .subs(values);
    for (int k = 0; k < 4; ++k) {
      const GiNaC::ex x = at.subs(lambda == k).evalf();
      if (!GiNaC::is_a<GiNaC::numeric>(x) || !GiNaC::ex_to<GiNaC::numeric>(x).is_real()) return;
      f.push_back(GiNaC::ex_to<GiNaC::numeric>(x).to_double());
    }
  } catch (const std::exception&) {
    return;
  }
  const double third = f[3] - 3.0 * f[2] + 3.0 * f[1] - f[0];
  const double size = std::max({std::abs(f[0]), std::abs(f[1]), std::abs(f[2]), std::abs(f[3])});
  if (!(std::abs(third) > 1e-8 * size)) return;
  throw ModelError(model + fmt::format("the kinetic energy T is not quadratic in the velocities: it is a polynomial "
                                       "of degree {} in them; T must be at most quadratic in q' (A = d2T/dq'2 may "
                                       "depend on q and t only)",
                                       degree));
}

// The rows of b and b0 of `constraints` (b q'' + b0 = 0, docs/notation.md (2.5)), with their
// position and velocity residuals; `kind` ("constraint" or "program") names them in errors.
void constraint_rows(const Spec& spec, const std::vector<SpecConstraint>& constraints, const char* kind,
                     const SymbolIndex& index, ExMatrix& b, GiNaC::matrix& b0_out, std::vector<GiNaC::ex>& phi,
                     std::vector<GiNaC::ex>& f) {
  const SymbolTable& symbols = spec.symbols;
  const int n = spec.n();
  const auto un = static_cast<unsigned>(n), us = static_cast<unsigned>(constraints.size());
  const auto q = [&](int i) { return symbols.coordinate(i); };
  const auto v = [&](int i) { return symbols.velocity(i); };
  const auto a = [&](int i) { return symbols.acceleration(i); };
  const auto name = [&](int i) { return spec.coordinates[static_cast<std::size_t>(i)]; };
  b = ExMatrix(us, un);
  b0_out = GiNaC::matrix(us, 1);
  for (unsigned r = 0; r < us; ++r) {
    const SpecConstraint& c = constraints[r];
    const std::string where = fmt::format("{}{} '{}'", prefix(c.where), kind, c.name);
    const GiNaC::ex& e = c.expression;
    const Contained o = index.find(e);
    GiNaC::ex b0;
    // The nonzero entries of this row: (column, derivative), columns ascending. A dense row per
    // constraint would cost n s for a model whose rows hold a few entries each.
    std::vector<std::pair<int, GiNaC::ex>> row;
    const char* involve = "the velocities";
    switch (c.level) {
      case ConstraintLevel::position: {
        if (!o.v.empty())
          throw ModelError(where + fmt::format(" is given at position level but contains the velocity {}'",
                                               name(o.v.front())));
        if (!o.a.empty())
          throw ModelError(where + fmt::format(" is given at position level but contains the acceleration {}''",
                                               name(o.a.front())));
        // phi' = phi_q q' + phi_t; phi'' = b q'' + b0 with b = phi_q and
        // b0 = (d/dq (phi_q q')) q' + 2 phi_qt q' + phi_tt, the q''-free part of d/dt phi'.
        // phidot as convective_derivative(e) builds it, from the partial derivatives of the row.
        GiNaC::ex phidot = o.time ? detail::derivative_of_container(e, symbols.time()) : GiNaC::ex(0);
        for (int j : o.q) {
          row.emplace_back(j, detail::derivative_of_container(e, q(j)));
          phidot += row.back().second * symbols.velocity(j);
        }
        b0 = convective_derivative(phidot, symbols, index);
        phi.push_back(e);
        f.push_back(tidy(phidot));
        break;
      }
      case ConstraintLevel::velocity: {
        if (!o.a.empty())
          throw ModelError(where + fmt::format(" is given at velocity level but contains the acceleration {}''",
                                               name(o.a.front())));
        // f' = (df/dq') q'' + (df/dq) q' + df/dt.
        for (int j : o.v) row.emplace_back(j, detail::derivative_of_container(e, v(j)));
        b0 = convective_derivative(e, symbols, index);
        f.push_back(e);
        break;
      }
      case ConstraintLevel::acceleration: {
        involve = "the accelerations";
        GiNaC::lst at_rest;
        for (int j : o.a) {
          row.emplace_back(j, detail::derivative(e, a(j)));
          at_rest.append(a(j) == 0);
        }
        for (const auto& [i, entry] : row)
          for (int j : o.a)
            if (!symbolic::is_zero(detail::derivative(entry, a(j))))
              throw ModelError(where + fmt::format(" must be linear in the accelerations, but it is not linear in "
                                                   "{}'' (its derivative by {}'' depends on {}'')",
                                                   name(i), name(i), name(j)));
        b0 = e.subs(at_rest);
        break;
      }
    }
    bool zero = true;
    for (const auto& [j, entry] : row) {
      if (entry.is_zero()) continue;
      const auto uj = static_cast<unsigned>(j);
      b(r, uj) = smaller_form(entry);
      zero = zero && b(r, uj).is_zero();
    }
    if (zero)
      throw ModelError(where + fmt::format(" does not involve {} after differentiation: its row of b is zero "
                                           "(a {}-level {} must depend on {})",
                                           involve,
                                           c.level == ConstraintLevel::position   ? "position"
                                           : c.level == ConstraintLevel::velocity ? "velocity"
                                                                                  : "acceleration",
                                           kind,
                                           c.level == ConstraintLevel::position   ? "the coordinates"
                                           : c.level == ConstraintLevel::velocity ? "the velocities"
                                                                                  : "the accelerations"));
    b0_out(r, 0) = smaller_form(b0);
  }

}

}  // namespace

std::optional<GiNaC::matrix> partitioned_complement(const GiNaC::matrix& b, const std::vector<int>& independent) {
  const unsigned s = b.rows(), n = b.cols();
  const auto k = static_cast<unsigned>(independent.size());
  std::vector<unsigned> dependent;
  for (unsigned j = 0; j < n; ++j)
    if (std::find(independent.begin(), independent.end(), static_cast<int>(j)) == independent.end())
      dependent.push_back(j);
  GiNaC::matrix D(k, n);
  for (unsigned r = 0; r < k; ++r) D(r, static_cast<unsigned>(independent[r])) = 1;
  if (s == 0) return D;
  GiNaC::matrix bd(s, s), bi(s, k);
  for (unsigned i = 0; i < s; ++i) {
    for (unsigned j = 0; j < s; ++j) bd(i, j) = b(i, dependent[j]);
    for (unsigned j = 0; j < k; ++j) bi(i, j) = b(i, static_cast<unsigned>(independent[j]));
  }
  if (symbolic::is_zero(bd.determinant())) return std::nullopt;
  GiNaC::matrix inverse;
  try {
    inverse = bd.inverse();
  } catch (const std::exception&) {
    return std::nullopt;
  }
  // X = -b_d^-1 b_i (s x k); D's dependent columns are X^T.
  const GiNaC::matrix X = inverse.mul(bi).mul_scalar(-1);
  for (unsigned r = 0; r < k; ++r)
    for (unsigned j = 0; j < s; ++j) D(r, dependent[j]) = simplify(X(j, r));
  return D;
}

namespace {

// A = d2T/dq'2 (docs/notation.md (2.4)); T must be quadratic in q' so that A does not depend on q'.
// Only the pairs of velocities that occur in a common term of T can give a nonzero entry. Tv
// receives dT/dq'_i, which G needs too.
void derive_inertia(const Spec& spec, const SplitSum& Ts, const SymbolIndex& index, const std::string& model,
                    Derivation& d, std::vector<GiNaC::ex>& Tv) {
  const SymbolTable& symbols = spec.symbols;
  const int n = spec.n();
  const auto un = static_cast<unsigned>(n);
  const auto v = [&](int i) { return symbols.velocity(i); };
  const auto name = [&](int i) { return spec.coordinates[static_cast<std::size_t>(i)]; };
  d.A = ExMatrix(un, un);
  Tv.assign(un, GiNaC::ex());
  bool moving = false;
  for (int i = 0; i < n; ++i) {
    const auto ui = static_cast<unsigned>(i);
    Tv[ui] = Ts.diff(Ts.with_v, i, v(i));
    std::vector<int> partners;
    for (int j : Ts.with_v[ui]) {
      const std::vector<int>& vs = Ts.occurrences[static_cast<std::size_t>(j)].v;
      partners.insert(partners.end(), vs.begin(), vs.end());
    }
    std::sort(partners.begin(), partners.end());
    partners.erase(std::unique(partners.begin(), partners.end()), partners.end());
    for (int jj : partners) {
      if (jj < i) continue;
      const auto uj = static_cast<unsigned>(jj);
      const GiNaC::ex entry = tidy(detail::derivative(Tv[ui], v(jj)));
      if (const Contained o = index.find(entry); !o.v.empty())
        throw ModelError(model + fmt::format("the kinetic energy T is not quadratic in the velocities: "
                                             "A = d2T/dq'2 depends on {}' (entry ({}, {}) is {})",
                                             name(o.v.front()), name(i), name(jj), printed(entry)));
      d.A(ui, uj) = d.A(uj, ui) = entry;
      moving = moving || !entry.is_zero();
    }
  }
  if (!moving) throw ModelError(model + "the kinetic energy T does not depend on the velocities");
}

// G = dT/dq - (d2T/dq'dq) q' - d2T/dq'dt and Q = -dV/dq + forces (docs/notation.md section 1).
void derive_forces(const Spec& spec, const SplitSum& Ts, const SplitSum& Vs, const std::vector<GiNaC::ex>& Tv,
                   const SymbolIndex& index, const std::string& model, Derivation& d) {
  const SymbolTable& symbols = spec.symbols;
  const int n = spec.n();
  const auto un = static_cast<unsigned>(n);
  const auto q = [&](int i) { return symbols.coordinate(i); };
  const auto name = [&](int i) { return spec.coordinates[static_cast<std::size_t>(i)]; };
  d.G = GiNaC::matrix(un, 1);
  d.Q = GiNaC::matrix(un, 1);
  for (int i = 0; i < n; ++i) {
    const auto ui = static_cast<unsigned>(i);
    d.G(ui, 0) = tidy(Ts.diff(Ts.with_q, i, q(i)) - convective_derivative(Tv[ui], symbols, index));
    const GiNaC::ex force = ui < spec.forces.size() ? spec.forces[ui] : GiNaC::ex(0);
    if (const Contained o = index.find(force); !o.a.empty())
      throw ModelError(model + fmt::format("the force on '{}' contains the acceleration {}''", name(i),
                                           name(o.a.front())));
    d.Q(ui, 0) = tidy(-Vs.diff(Vs.with_q, i, q(i)) + force);
  }
}

// The programs as the constraints, b_p q'' + b_p0 = 0, and their actuators' columns of B
// (docs/derivations/program-motion.md section 1).
void derive_programs(const Spec& spec, const SymbolIndex& index, Derivation& d) {
  const auto un = static_cast<unsigned>(spec.n());
  std::vector<SpecConstraint> programs;
  for (const SpecProgram& p : spec.programs) programs.push_back(p.constraint);
  ExMatrix b_p;
  constraint_rows(spec, programs, "program", index, b_p, d.b_p0, d.phi_p, d.f_p);
  d.b_p = b_p.dense();
  const auto um = static_cast<unsigned>(spec.m());
  d.B = GiNaC::matrix(un, um);
  for (unsigned j = 0; j < um; ++j) {
    const SpecProgram& p = spec.programs[j];
    bool zero = true;
    for (unsigned i = 0; i < un && i < p.actuator.size(); ++i) {
      d.B(i, j) = tidy(p.actuator[i]);
      zero = zero && symbolic::is_zero(d.B(i, j));
    }
    if (zero)
      throw ModelError(fmt::format("{}program '{}': its actuator direction ({}) is zero, so it exerts no force; "
                                   "give the coordinate the actuator acts on or a nonzero direction",
                                   prefix(p.actuator_where.line > 0 ? p.actuator_where : p.constraint.where),
                                   p.constraint.name, p.actuator_text));
  }
}

// D: analytic, or partitioned for the named independent coordinates.
void derive_complement(const Spec& spec, const std::string& model, Derivation& d) {
  const int n = spec.n(), s = spec.s(), k = n - s;
  const auto name = [&](int i) { return spec.coordinates[static_cast<std::size_t>(i)]; };
  if (spec.complement) {
    const GiNaC::matrix& D = *spec.complement;
    if (static_cast<int>(D.rows()) != k || static_cast<int>(D.cols()) != n)
      throw ModelError(fmt::format("{}complement D: D is {} x {} but must be k x n = {} x {}",
                                   prefix(spec.complement_where), D.rows(), D.cols(), k, n));
    require_complement_at_initial_state(spec, d.b, D);
    d.D = D;
  } else if (!spec.independent.empty()) {
    std::vector<int> independent;
    for (const std::string& coordinate : spec.independent) {
      const auto it = std::find(spec.coordinates.begin(), spec.coordinates.end(), coordinate);
      if (it == spec.coordinates.end())
        throw ModelError(model + fmt::format("independent coordinate '{}' is not a coordinate", coordinate));
      independent.push_back(static_cast<int>(it - spec.coordinates.begin()));
    }
    std::sort(independent.begin(), independent.end());
    if (std::adjacent_find(independent.begin(), independent.end()) != independent.end() ||
        static_cast<int>(independent.size()) != k)
      throw ModelError(model + fmt::format("independent coordinates ({}): k = n - s = {} distinct coordinates are "
                                           "needed",
                                           join(spec.independent), k));
    d.D = partitioned_complement(d.b, independent);
    if (!d.D) {
      std::vector<std::string> dependent;
      for (int j = 0; j < n; ++j)
        if (!std::binary_search(independent.begin(), independent.end(), j)) dependent.push_back(name(j));
      throw ModelError(model + fmt::format("cannot keep {} independent: the columns of b for the dependent "
                                           "coordinates ({}) form a singular matrix; choose other independent "
                                           "coordinates",
                                           join(spec.independent), join(dependent)));
    }
  }
}

// The degree of `e` as a homogeneous polynomial in the velocities `v` (the few a term contains),
// whatever its other factors; -1 when it is not one (a velocity inside a function, a root or a
// denominator, or a sum of terms of unlike degrees). Degree 0 means that e contains no velocity.
int velocity_degree(const GiNaC::ex& e, const std::vector<GiNaC::ex>& v) {
  if (GiNaC::is_exactly_a<GiNaC::symbol>(e))
    return std::any_of(v.begin(), v.end(), [&](const GiNaC::ex& x) { return x.is_equal(e); }) ? 1 : 0;
  if (GiNaC::is_exactly_a<GiNaC::numeric>(e)) return 0;
  const bool sum = GiNaC::is_exactly_a<GiNaC::add>(e), product = GiNaC::is_exactly_a<GiNaC::mul>(e);
  if (GiNaC::is_exactly_a<GiNaC::power>(e)) {
    const int base = velocity_degree(e.op(0), v);
    if (base < 0) return -1;
    const GiNaC::ex& k = e.op(1);
    if (GiNaC::is_exactly_a<GiNaC::numeric>(k) && k.info(GiNaC::info_flags::nonnegint))
      return base * GiNaC::ex_to<GiNaC::numeric>(k).to_int();
    return base == 0 && velocity_degree(k, v) == 0 ? 0 : -1;
  }
  int out = 0;
  for (std::size_t i = 0; i < e.nops(); ++i) {
    const int d = velocity_degree(e.op(i), v);
    if (d < 0) return -1;
    if (product) {
      out += d;
    } else if (sum) {
      if (i > 0 && d != out) return -1;
      out = d;
    } else if (d != 0) {
      return -1;  // a velocity inside a function's argument
    }
  }
  return out;
}

// The energy balance (docs/derivations/energy-balance.md). Simplifying a sum costs more than
// linearly in its number of terms (every trigonometric argument is reduced across all of them):
// a large model's expressions are kept as written, which computes the same values.
void derive_energy_balance(const Spec& spec, const SplitSum& Ts, Derivation& d) {
  const SymbolTable& symbols = spec.symbols;
  const GiNaC::symbol& t = symbols.time();
  const auto v = [&](int i) { return symbols.velocity(i); };
  const GiNaC::ex& T = spec.kinetic_energy;
  const GiNaC::ex& V = spec.potential_energy;
  constexpr std::size_t kSimplifiedTerms = 64;
  const auto kept = [](const GiNaC::ex& e) { return e.nops() <= kSimplifiedTerms ? tidy(e) : e; };
  const GiNaC::ex energy = T + V;
  d.energy = kept(energy);
  // h = q' . dT/dq' - T + V, term by term of T: a term homogeneous of degree 2 in the velocities
  // (Euler: q' . dterm/dq' = 2 term) contributes itself, as in E; only the others need the sum.
  // Collected and summed once: adding term by term rebuilds the growing sum at every step,
  // quadratic in the number of terms (30 000 for 10 000 free particles).
  GiNaC::exvector h_terms{V};
  bool h_is_energy = true;
  for (std::size_t j = 0; j < Ts.terms.size(); ++j) {
    const GiNaC::ex& term = Ts.terms[j];
    // A term that is a homogeneous quadratic in the velocities needs no check: Euler's identity
    // holds for it as polynomials, which expand() below would confirm at great cost for the
    // nested products of a multibody model's rotations (two fifths of the bicycle's start-up).
    std::vector<GiNaC::ex> velocities;
    for (int i : Ts.occurrences[j].v) velocities.push_back(v(i));
    if (!velocities.empty() && velocity_degree(term, velocities) == 2) {
      h_terms.push_back(term);
      continue;
    }
    GiNaC::ex rate = 0;
    for (int i : Ts.occurrences[j].v) rate += v(i) * detail::derivative(term, v(i));
    // Expanding settles the usual term (a polynomial in the velocities) at a small fraction of
    // the cost of simplifying it, which matters for the thousands of terms of a long chain.
    const GiNaC::ex euler = (rate - 2 * term).expand();
    if (!Ts.occurrences[j].v.empty() && (euler.is_zero() || symbolic::is_zero(euler))) {
      h_terms.push_back(term);
    } else {
      h_terms.push_back(rate - term);
      h_is_energy = false;
    }
  }
  if (!h_is_energy) d.energy_function = kept(GiNaC::add(h_terms));
  GiNaC::ex power_forces = 0;
  for (std::size_t i = 0; i < spec.forces.size(); ++i)
    if (!symbolic::is_zero(spec.forces[i])) power_forces += spec.forces[i] * v(static_cast<int>(i));
  d.power_forces = tidy(power_forces);
  d.power_time = tidy(detail::derivative(V, t) - detail::derivative(T, t));
  d.conservative = symbolic::is_zero(d.power_forces) && symbolic::is_zero(d.power_time);
}

}  // namespace

Derivation derive(const Spec& spec) {
  const int n = spec.n(), s = spec.s();
  const std::string model = fmt::format("{}model '{}': ", prefix(spec.where), spec.name);
  if (n == 0) throw ModelError(model + "no coordinates");
  if (constraints_always_held(spec) >= n)
    throw ModelError(model + fmt::format("{} constraints for {} coordinates, {} of them held whatever the contacts' "
                                         "modes: fewer than n must hold at any time",
                                         s, n, constraints_always_held(spec)));
  const auto name = [&](int i) { return spec.coordinates[static_cast<std::size_t>(i)]; };

  const GiNaC::ex& T = spec.kinetic_energy;
  const GiNaC::ex& V = spec.potential_energy;
  const SymbolIndex index(spec.symbols);
  const SplitSum Ts(T, index, n), Vs(V, index, n);
  if (Ts.first(&Contained::a) >= 0 || Vs.first(&Contained::a) >= 0)
    throw ModelError(model + "the kinetic and potential energies may not contain accelerations");
  if (const int i = Vs.first(&Contained::v); i >= 0)
    throw ModelError(model + fmt::format("the potential energy V contains the velocity {}'", name(i)));
  require_at_most_quadratic(spec, index, model);
  check_contact_convexity(spec);  // an implicit rolling shape must be convex where the run starts
  check_contact_watches_at_start(spec);  // a wheel neither flat nor turned over where it starts

  Derivation d;
  std::vector<GiNaC::ex> Tv;
  {
    // dT/dq'_i holds the parts of T that do not contain q'_i as they are, and they are
    // differentiated again for A's entries and for G (detail/derivative.hpp, DerivativeMemo). The
    // constraints' rows share little and are many in a large model: the memo would only grow.
    const detail::DerivativeMemo memo;
    derive_inertia(spec, Ts, index, model, d, Tv);
    derive_forces(spec, Ts, Vs, Tv, index, model, d);
  }
  // Every constraint at acceleration level, b q'' + b0 = 0 (docs/notation.md (2.5)).
  constraint_rows(spec, spec.constraints, "constraint", index, d.b, d.b0, d.phi, d.f);
  derive_programs(spec, index, d);
  derive_complement(spec, model, d);
  derive_energy_balance(spec, Ts, d);
  return d;
}

GiNaC::matrix reduced_inertia(const Derivation& derivation) {
  if (!derivation.D)
    throw ModelError("A0 = D A needs a complement D: name the independent coordinates or give an analytic D");
  return simplify(derivation.D->mul(derivation.A));
}

GiNaC::matrix reduced_forces(const Derivation& derivation) {
  if (!derivation.D)
    throw ModelError("C = D (Q + G) needs a complement D: name the independent coordinates or give an analytic D");
  return simplify(derivation.D->mul(derivation.Q.add(derivation.G)));
}

}  // namespace nhdyn::symbolic
