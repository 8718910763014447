#include "nhdyn/symbolic/simplify.hpp"

#include <algorithm>
#include <optional>
#ifdef NHDYN_CHECK_SIMPLIFY_SHORTCUT
#include <cstdlib>
#include <iostream>
#endif
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace nhdyn::symbolic {
namespace {

using GiNaC::ex;

bool is_function(const ex& e, const char* name) {
  return GiNaC::is_a<GiNaC::function>(e) && GiNaC::ex_to<GiNaC::function>(e).get_name() == name;
}

// Number of nodes of the expression tree: the measure of "shorter".
std::size_t size_of(const ex& e) {
  std::size_t n = 1;
  for (std::size_t i = 0; i < e.nops(); ++i) n += size_of(e.op(i));
  return n;
}

// A half-integer power of a quotient with a number above or below the line, (n / d)^k, split into
// n^k d^-k with that number made positive: sqrt(-1/P) becomes (-P)^(-1/2). Valid because the
// root is real (its argument positive: mechanics takes square roots of lengths), so the number and
// the other side share a sign. Without it GiNaC's normal() writes a root of a quotient as
// (b/a)^x and keeps both that and a^-x as separate unknowns; on such a mixture its gcd fails,
// depending on its term order ("heur_gcd: not an integer polynomial"), i.e. in some runs only.
ex split_root(const ex& base, const GiNaC::numeric& k) {
  const ex nd = base.numer_denom();
  ex n = nd.op(0), d = nd.op(1);
  const bool numeric_above = GiNaC::is_a<GiNaC::numeric>(n);
  if (!(numeric_above || GiNaC::is_a<GiNaC::numeric>(d))) return GiNaC::pow(base, k);
  const GiNaC::numeric number = GiNaC::ex_to<GiNaC::numeric>(numeric_above ? n : d);
  if (number.is_negative()) {
    n = GiNaC::expand(-n);
    d = GiNaC::expand(-d);
  }
  // Each side simplified on its own, so that a root of P and a root of 1/P share one form of P.
  return GiNaC::pow(simplify(n), k) * GiNaC::pow(simplify(d), -k);
}

// Bottom-up: every function argument is simplified on its own; tan and tanh become quotients;
// square roots of quotients are split (split_root).
struct Rewrite : GiNaC::map_function {
  ex operator()(const ex& e) override {
    if (GiNaC::is_a<GiNaC::power>(e) && GiNaC::is_a<GiNaC::numeric>(e.op(1))) {
      const GiNaC::numeric k = GiNaC::ex_to<GiNaC::numeric>(e.op(1));
      if (k.is_rational() && !k.is_integer() && k.denom() == 2) return split_root(simplify(e.op(0)), k);
    }
    if (GiNaC::is_a<GiNaC::function>(e)) {
      struct Arguments : GiNaC::map_function {
        ex operator()(const ex& arg) override { return simplify(arg); }
      } arguments;
      const ex f = e.map(arguments);
      if (is_function(f, "tan")) return GiNaC::sin(f.op(0)) / GiNaC::cos(f.op(0));
      if (is_function(f, "tanh")) return GiNaC::sinh(f.op(0)) / GiNaC::cosh(f.op(0));
      return f;
    }
    return e.map(*this);
  }
};


struct Fraction {
  ex numerator;
  ex denominator;
};

// An argument normal() leaves as it is: a symbol, an integer or a sum of integer multiples of
// symbols (a rational multiple, x/2 + y, it would write as (x + 2 y)/2).
bool is_plain_argument(const ex& a) {
  const auto plain_term = [](const ex& t) {
    if (GiNaC::is_exactly_a<GiNaC::symbol>(t)) return true;
    if (GiNaC::is_exactly_a<GiNaC::numeric>(t)) return t.info(GiNaC::info_flags::integer);
    return GiNaC::is_exactly_a<GiNaC::mul>(t) && t.nops() == 2 && GiNaC::is_exactly_a<GiNaC::symbol>(t.op(0)) &&
           GiNaC::is_exactly_a<GiNaC::numeric>(t.op(1)) && t.op(1).info(GiNaC::info_flags::integer);
  };
  if (!GiNaC::is_exactly_a<GiNaC::add>(a)) return plain_term(a);
  for (std::size_t i = 0; i < a.nops(); ++i)
    if (!plain_term(a.op(i))) return false;
  return true;
}

// A polynomial with rational coefficients in symbols and in calls (other than tan and tanh) of
// plain arguments: no denominator, root or floating-point number. Its normal form is its
// expansion, and simplify() leaves its function arguments as they are; the common entry of a
// large model (m a cos(theta1) theta1', -sin(theta2) x2' theta2') is one, and expand() costs a
// fraction of normal(), which replaces every call by a symbol and back and adds term by term.
bool is_plain_polynomial(const ex& e) {
  if (GiNaC::is_exactly_a<GiNaC::symbol>(e)) return true;
  if (GiNaC::is_exactly_a<GiNaC::numeric>(e)) return e.info(GiNaC::info_flags::rational);
  if (GiNaC::is_exactly_a<GiNaC::power>(e))
    return GiNaC::is_exactly_a<GiNaC::numeric>(e.op(1)) && e.op(1).info(GiNaC::info_flags::posint) &&
           is_plain_polynomial(e.op(0));
  if (GiNaC::is_exactly_a<GiNaC::add>(e) || GiNaC::is_exactly_a<GiNaC::mul>(e)) {
    for (std::size_t i = 0; i < e.nops(); ++i)
      if (!is_plain_polynomial(e.op(i))) return false;
    return true;
  }
  if (GiNaC::is_exactly_a<GiNaC::function>(e)) {
    if (is_function(e, "tan") || is_function(e, "tanh")) return false;
    for (std::size_t i = 0; i < e.nops(); ++i)
      if (!is_plain_argument(e.op(i))) return false;
    return true;
  }
  return false;
}

// numerator / denominator, both expanded and coprime, with a unit fixed independently of GiNaC's
// term order: the denominator has integer coefficients without common factor, and its first term
// (by canonical_key) a positive coefficient.
Fraction normal_fraction_of_any(const ex& e);

// normal_fraction() of a plain polynomial.
Fraction plain_fraction(const ex& e) {
  // Build with -DNHDYN_CHECK_SIMPLIFY_SHORTCUT to compare with normal() on every call.
  const Fraction out{GiNaC::expand(e), 1};
#ifdef NHDYN_CHECK_SIMPLIFY_SHORTCUT
  const Fraction full = normal_fraction_of_any(e);
  if (!full.numerator.is_equal(out.numerator) || !full.denominator.is_equal(out.denominator)) {
    std::cerr << "NORMAL SHORTCUT MISMATCH " << e << " : " << full.numerator << " / " << full.denominator
              << " vs " << out.numerator << std::endl;
    std::abort();
  }
#endif
  return out;
}

Fraction normal_fraction(const ex& e) { return is_plain_polynomial(e) ? plain_fraction(e) : normal_fraction_of_any(e); }

Fraction normal_fraction_of_any(const ex& e) {
  const ex nd = GiNaC::normal(e).numer_denom();
  ex n = GiNaC::expand(nd.op(0));
  ex d = GiNaC::expand(nd.op(1));
  if (n.is_zero()) return {0, 1};
  const GiNaC::numeric content = GiNaC::ex_to<GiNaC::numeric>(d.integer_content());
  GiNaC::numeric unit = content.is_zero() ? GiNaC::numeric(1) : content;
  const ex first = [&] {
    if (!GiNaC::is_a<GiNaC::add>(d)) return d;
    std::size_t best = 0;
    std::string best_key;
    for (std::size_t i = 0; i < d.nops(); ++i) {
      const std::string key = canonical_key(split_coefficient(d.op(i)).second);
      if (i == 0 || key < best_key) {
        best = i;
        best_key = key;
      }
    }
    return d.op(best);
  }();
  if (split_coefficient(first).first.is_negative()) unit = -unit;
  if (unit != 1) {
    n = GiNaC::expand(n / unit);
    d = GiNaC::expand(d / unit);
  }
  return {n, d};
}

ex assemble(const Fraction& f) {
  if (f.denominator.is_equal(1)) return f.numerator;
  // A single product below the line reads best distributed: a/c + b/c, not (a + b)/c.
  if (!GiNaC::is_a<GiNaC::add>(f.denominator)) return GiNaC::expand(f.numerator / f.denominator);
  return f.numerator / f.denominator;
}

// A pair of functions tied by a quadratic relation, at one argument: sin/cos or sinh/cosh.
struct Family {
  bool hyperbolic = false;
  ex argument;
  std::string key;
};

void collect_families(const ex& e, std::vector<Family>& out) {
  if (GiNaC::is_a<GiNaC::function>(e)) {
    const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
    const bool trig = name == "sin" || name == "cos";
    const bool hyperbolic = name == "sinh" || name == "cosh";
    if (trig || hyperbolic) {
      Family family{hyperbolic, e.op(0), (hyperbolic ? "h:" : "t:") + canonical_key(e.op(0))};
      const bool known = std::any_of(out.begin(), out.end(),
                                     [&](const Family& f) { return f.key == family.key; });
      if (!known) out.push_back(std::move(family));
    }
    return;  // arguments were simplified on their own
  }
  for (std::size_t i = 0; i < e.nops(); ++i) collect_families(e.op(i), out);
}

// Replaces every power with a non-integer exponent (a square root, say) by a symbol of its own, so
// that the reduction below sees a polynomial: GiNaC's degree() refuses sqrt(1 - sin(u)^2) in u.
// Such powers are left as they are (their inside is not reduced); `back` undoes the replacement.
struct Freeze : GiNaC::map_function {
  GiNaC::lst back;
  std::vector<std::pair<ex, GiNaC::symbol>> seen;
  ex operator()(const ex& e) override {
    if (GiNaC::is_a<GiNaC::power>(e) && !e.op(1).info(GiNaC::info_flags::integer)) {
      for (const auto& [power, symbol] : seen)
        if (power.is_equal(e)) return symbol;
      const GiNaC::symbol symbol;
      seen.emplace_back(e, symbol);
      back.append(symbol == e);
      return symbol;
    }
    if (GiNaC::is_a<GiNaC::function>(e)) return e;
    return e.map(*this);
  }
};

// What one power of a family function becomes: x^2 -> square. x is the call itself, or the
// symbol that stands for it.
struct Rule {
  ex x;
  ex square;
};

// The factor x^k of a term with x^k -> x^(k mod 2) square^(k div 2) where a rule applies and k >= 2;
// false when the factor is not what a term of an expanded polynomial holds (a rational number, a
// symbol or call to a nonnegative integer power, or a power with another exponent, which the
// reduction does not look into).
bool reduce_factor(const ex& f, const std::vector<Rule>& rules, ex& out, bool& changed) {
  out = f;
  if (GiNaC::is_exactly_a<GiNaC::numeric>(f)) return f.info(GiNaC::info_flags::rational);
  if (GiNaC::is_exactly_a<GiNaC::symbol>(f) || GiNaC::is_a<GiNaC::function>(f)) return true;
  if (!GiNaC::is_exactly_a<GiNaC::power>(f)) return false;
  const ex& base = f.op(0);
  if (!f.op(1).info(GiNaC::info_flags::integer)) return true;
  if (!f.op(1).info(GiNaC::info_flags::nonnegint)) return false;
  if (!GiNaC::is_exactly_a<GiNaC::symbol>(base) && !GiNaC::is_a<GiNaC::function>(base)) return false;
  const int k = GiNaC::ex_to<GiNaC::numeric>(f.op(1)).to_int();
  for (const Rule& rule : rules) {
    if (!base.is_equal(rule.x)) continue;
    out = GiNaC::pow(rule.x, k % 2) * GiNaC::pow(rule.square, k / 2);
    changed = true;
    break;
  }
  return true;
}

// The rules applied to every term of the expanded polynomial q at once and the sum expanded once:
// the polynomial of degree at most 1 in each x that the family-by-family reduction below reaches
// (the remainder modulo the relations, which is unique: their leading powers x^2 share no symbol),
// so expand() writes both alike. Empty when a term is not a product of the factors reduce_factor()
// takes; in particular a floating-point coefficient, whose sums depend on the order of the
// additions, leaves the reduction to the family-by-family one.
std::optional<ex> reduce_terms(const ex& q, const std::vector<Rule>& rules) {
  const bool sum = GiNaC::is_exactly_a<GiNaC::add>(q);
  GiNaC::exvector terms;
  terms.reserve(sum ? q.nops() : 1);
  bool changed = false;
  for (std::size_t i = 0; i < (sum ? q.nops() : 1); ++i) {
    const ex& term = sum ? q.op(i) : q;
    if (!GiNaC::is_exactly_a<GiNaC::mul>(term)) {
      ex out;
      if (!reduce_factor(term, rules, out, changed)) return std::nullopt;
      terms.push_back(out);
      continue;
    }
    GiNaC::exvector factors;
    factors.reserve(term.nops());
    bool term_changed = false;
    for (std::size_t j = 0; j < term.nops(); ++j) {
      ex out;
      if (!reduce_factor(term.op(j), rules, out, term_changed)) return std::nullopt;
      factors.push_back(out);
    }
    // A term without a square to replace is kept as the object it is: expand() knows it expanded.
    terms.push_back(term_changed ? ex(GiNaC::mul(factors)) : term);
    changed = changed || term_changed;
  }
  if (!changed) return q;
  return GiNaC::expand(GiNaC::add(terms));
}

// reduce_polynomial() for any polynomial: its calls and roots replaced by symbols, expanded, reduced
// and substituted back.
ex reduce_polynomial_by_symbols(const ex& p, const std::vector<Family>& families, bool eliminate_first) {
  std::vector<GiNaC::symbol> first(families.size()), second(families.size());
  GiNaC::lst to_symbols, back;
  for (std::size_t i = 0; i < families.size(); ++i) {
    const ex& u = families[i].argument;
    const ex f = families[i].hyperbolic ? GiNaC::sinh(u) : GiNaC::sin(u);
    const ex g = families[i].hyperbolic ? GiNaC::cosh(u) : GiNaC::cos(u);
    to_symbols.append(f == first[i]);
    to_symbols.append(g == second[i]);
    back.append(first[i] == f);
    back.append(second[i] == g);
  }
  Freeze freeze;
  // no_pattern: the keys hold no wildcard, so a lookup per node finds them; GiNaC's default tries
  // every key as a pattern at every node.
  ex q = GiNaC::expand(freeze(p).subs(to_symbols, GiNaC::subs_options::no_pattern));
  std::vector<Rule> rules;
  for (std::size_t i = 0; i < families.size(); ++i) {
    const GiNaC::symbol& s = first[i];
    const GiNaC::symbol& c = second[i];
    if (!families[i].hyperbolic)
      rules.push_back({eliminate_first ? s : c, 1 - GiNaC::pow(eliminate_first ? c : s, 2)});
    else
      rules.push_back({eliminate_first ? s : c, eliminate_first ? GiNaC::pow(c, 2) - 1 : 1 + GiNaC::pow(s, 2)});
  }
  if (const std::optional<ex> at_once = reduce_terms(q, rules)) {
    q = *at_once;
  } else {
    for (const Rule& rule : rules) {
      const int degree = q.degree(rule.x);
      if (degree < 2 || q.ldegree(rule.x) < 0) continue;
      ex reduced = 0;
      for (int k = 0; k <= degree; ++k) {
        const ex coefficient = q.coeff(rule.x, k);
        if (coefficient.is_zero()) continue;
        reduced += coefficient * GiNaC::pow(rule.x, k % 2) * GiNaC::pow(rule.square, k / 2);
      }
      q = GiNaC::expand(reduced);
    }
  }
  return q.subs(back, GiNaC::subs_options::no_pattern).subs(freeze.back, GiNaC::subs_options::no_pattern);
}

// Reduces a polynomial modulo the relations of the families: with s, c the two functions of a
// family, eliminate_first replaces s^2 by 1 - c^2 (sinh^2 by cosh^2 - 1), otherwise c^2 by
// 1 - s^2 (cosh^2 by 1 + sinh^2). The result has degree at most 1 in the eliminated function.
// p is expanded (reduce() passes the parts of a normal fraction): its terms are reduced as they
// are, on the calls themselves, which gives the polynomial that replacing the calls and roots by
// symbols, expanding, reducing and substituting back gives (expand() of what is expanded already
// writes it again, and the substitutions are undone one for one), and p itself where nothing is
// reduced, without those passes over all of p.
ex reduce_polynomial(const ex& p, const std::vector<Family>& families, bool eliminate_first) {
  std::vector<Rule> on_calls;
  for (const Family& family : families) {
    const ex& u = family.argument;
    const ex f = family.hyperbolic ? GiNaC::sinh(u) : GiNaC::sin(u);
    const ex g = family.hyperbolic ? GiNaC::cosh(u) : GiNaC::cos(u);
    if (!family.hyperbolic)
      on_calls.push_back({eliminate_first ? f : g, 1 - GiNaC::pow(eliminate_first ? g : f, 2)});
    else
      on_calls.push_back({eliminate_first ? f : g, eliminate_first ? GiNaC::pow(g, 2) - 1 : 1 + GiNaC::pow(f, 2)});
  }
  if (const std::optional<ex> direct = reduce_terms(p, on_calls)) return *direct;
  return reduce_polynomial_by_symbols(p, families, eliminate_first);
}

// True when a power of a sine, cosine, sinh or cosh occurs anywhere in e (inside roots and
// function arguments too, so that the test errs on the side of reducing). Without one, no family
// function has degree 2 or more and reduce() gives back its input: the common case of a large
// model's entries (cos(theta1), -sin(theta2) theta2'^2 f), which this spares three normal()s each.
bool has_family_power(const ex& e) {
  if (GiNaC::is_a<GiNaC::power>(e)) {
    const ex& base = e.op(0);
    if (is_function(base, "sin") || is_function(base, "cos") || is_function(base, "sinh") || is_function(base, "cosh"))
      return true;
  }
  for (std::size_t i = 0; i < e.nops(); ++i)
    if (has_family_power(e.op(i))) return true;
  return false;
}

Fraction reduce(const Fraction& start, const std::vector<Family>& families, bool eliminate_first) {
  Fraction f = start;
  // Cancelling common factors cannot raise the degree in the eliminated function, so one round
  // usually suffices; a few more make sure a fixpoint is reached.
  // normal_fraction() gives the same result for the same expression, and its result written as a
  // quotient is usually its argument again: the round that confirms the fixpoint then hands it the
  // argument of the round before, and takes that round's result instead of normalizing again.
  ex argument;
  Fraction result;
  for (int round = 0; round < 4; ++round) {
    const ex n = reduce_polynomial(f.numerator, families, eliminate_first);
    const ex d = reduce_polynomial(f.denominator, families, eliminate_first);
    const ex quotient = n / d;
    const bool known = round > 0 && quotient.is_equal(argument);
    if (!known) {
      argument = quotient;
      result = normal_fraction(quotient);
    }
    const Fraction next = result;
    const bool same = next.numerator.is_equal(f.numerator) && next.denominator.is_equal(f.denominator);
    f = next;
    if (same || f.numerator.is_zero()) break;
  }
  return f;
}

}  // namespace

std::pair<GiNaC::numeric, ex> split_coefficient(const ex& term) {
  if (GiNaC::is_a<GiNaC::numeric>(term)) return {GiNaC::ex_to<GiNaC::numeric>(term), 1};
  if (GiNaC::is_a<GiNaC::mul>(term)) {
    GiNaC::numeric c = 1;
    ex rest = 1;
    for (std::size_t i = 0; i < term.nops(); ++i) {
      if (GiNaC::is_a<GiNaC::numeric>(term.op(i)))
        c *= GiNaC::ex_to<GiNaC::numeric>(term.op(i));
      else
        rest *= term.op(i);
    }
    return {c, rest};
  }
  return {1, term};
}

std::string canonical_key(const ex& e) {
  auto operands = [&](const char* tag, bool sorted) {
    std::vector<std::string> keys;
    for (std::size_t i = 0; i < e.nops(); ++i) keys.push_back(canonical_key(e.op(i)));
    if (sorted) std::sort(keys.begin(), keys.end());
    std::string out = tag;
    out += '(';
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (i > 0) out += ',';
      out += keys[i];
    }
    out += ')';
    return out;
  };
  if (GiNaC::is_a<GiNaC::symbol>(e)) return GiNaC::ex_to<GiNaC::symbol>(e).get_name();
  if (GiNaC::is_a<GiNaC::add>(e)) return operands("+", true);
  if (GiNaC::is_a<GiNaC::mul>(e)) return operands("*", true);
  if (GiNaC::is_a<GiNaC::power>(e)) return operands("^", false);
  if (GiNaC::is_a<GiNaC::function>(e))
    return operands(GiNaC::ex_to<GiNaC::function>(e).get_name().c_str(), false);
  std::ostringstream out;
  out << e;
  return out.str();
}

namespace {

// The smallest of base and its two reductions (simplify() after the families are known).
ex reduced_form(const Fraction& base, std::vector<Family>& families) {
  std::sort(families.begin(), families.end(),
            [](const Family& a, const Family& b) { return a.key < b.key; });

  // The canonical form first: an identity reduces to 0 here.
  const Fraction first = reduce(base, families, true);
  if (first.numerator.is_zero()) return 0;
  const Fraction second = reduce(base, families, false);
  ex best = assemble(base);
  std::size_t best_size = size_of(best);
  for (const Fraction* candidate : {&first, &second}) {
    const ex form = assemble(*candidate);
    const std::size_t size = size_of(form);
    if (size < best_size) {
      best = form;
      best_size = size;
    }
  }
  return best;
}

}  // namespace

GiNaC::ex simplify(const GiNaC::ex& e) {
  if (GiNaC::is_a<GiNaC::numeric>(e) || GiNaC::is_a<GiNaC::symbol>(e)) return e;
  Rewrite rewrite;
  // A plain polynomial's function arguments are simplified already (is_plain_argument).
  const Fraction base = is_plain_polynomial(e) ? plain_fraction(e) : normal_fraction(rewrite(e));
#ifdef NHDYN_CHECK_SIMPLIFY_SHORTCUT
  if (is_plain_polynomial(e)) {
    const Fraction full = normal_fraction_of_any(rewrite(e));
    if (!full.numerator.is_equal(base.numerator) || !full.denominator.is_equal(base.denominator)) {
      std::cerr << "REWRITE SHORTCUT MISMATCH " << e << std::endl;
      std::abort();
    }
  }
#endif
  if (base.numerator.is_zero()) return 0;
  // Without a power of a family function the reduction gives back its input (the common entry of a
  // large model), whatever the families are: they are collected only when there is one.
  if (!has_family_power(base.numerator) && !has_family_power(base.denominator)) {
    // Build with -DNHDYN_CHECK_SIMPLIFY_SHORTCUT to compare the shortcut with the full reduction on
    // every call (done over every example and `nhdyn equations` when the shortcut was added).
#ifdef NHDYN_CHECK_SIMPLIFY_SHORTCUT
    std::vector<Family> families;
    collect_families(base.numerator, families);
    collect_families(base.denominator, families);
    if (!families.empty() && !reduced_form(base, families).is_equal(assemble(base))) {
      std::cerr << "SHORTCUT MISMATCH " << e << " : " << reduced_form(base, families) << " vs " << assemble(base) << std::endl;
      std::abort();
    }
#endif
    return assemble(base);
  }
  std::vector<Family> families;
  collect_families(base.numerator, families);
  collect_families(base.denominator, families);
  if (families.empty()) return assemble(base);
  return reduced_form(base, families);
}

GiNaC::matrix simplify(const GiNaC::matrix& m) {
  GiNaC::matrix out(m.rows(), m.cols());
  for (unsigned i = 0; i < m.rows(); ++i)
    for (unsigned j = 0; j < m.cols(); ++j) out(i, j) = simplify(m(i, j));
  return out;
}

namespace {

// Node count of the expression tree, counted no further than `limit`.
std::size_t capped_size(const ex& e, std::size_t limit) {
  std::size_t n = 1;
  for (std::size_t i = 0; i < e.nops() && n <= limit; ++i) n += capped_size(e.op(i), limit - n);
  return n;
}

// The symbols and functions written in the tree, each occurrence counted, and numbers not: a
// measure of size that GiNaC's sign choices (x - y in one process, -(y - x) in another: the -1 is
// a number) do not change.
// In a product, the powers of one base count the base once: GiNaC merges S^(1/2) (-S) into
// -S^(3/2) in the processes where it writes -S as S, and the compiler merges them in every one
// (compile.cpp, merge_powers), so the count must not see the difference either.
std::size_t symbol_count(const ex& e, std::size_t limit) {
  if (GiNaC::is_a<GiNaC::numeric>(e)) return 0;
  if (GiNaC::is_a<GiNaC::symbol>(e)) return 1;
  std::size_t n = GiNaC::is_a<GiNaC::function>(e) ? 1 : 0;
  if (GiNaC::is_a<GiNaC::mul>(e)) {
    // Only sums can stand twice (as S and -S): GiNaC merges other equal bases itself.
    const auto sum_base = [](const ex& f) {
      const ex& base = GiNaC::is_a<GiNaC::power>(f) ? f.op(0) : f;
      return GiNaC::is_a<GiNaC::add>(base);
    };
    std::size_t sums = 0;
    for (std::size_t i = 0; i < e.nops(); ++i) sums += sum_base(e.op(i)) ? 1 : 0;
    std::vector<std::string> bases;  // each sum base's key, the same for S and -S
    for (std::size_t i = 0; i < e.nops() && n <= limit; ++i) {
      const ex& f = e.op(i);
      const bool power = GiNaC::is_a<GiNaC::power>(f);
      const ex& base = power ? f.op(0) : f;
      if (power) n += symbol_count(f.op(1), limit - n);
      if (sums > 1 && sum_base(f)) {
        std::string key = std::min(canonical_key(base), canonical_key(GiNaC::expand(-base)));
        if (std::find(bases.begin(), bases.end(), key) != bases.end()) continue;
        bases.push_back(std::move(key));
      }
      n += symbol_count(base, limit - n);
    }
    return n;
  }
  for (std::size_t i = 0; i < e.nops() && n <= limit; ++i) n += symbol_count(e.op(i), limit - n);
  return n;
}

}  // namespace

GiNaC::ex smaller_form(const GiNaC::ex& e) {
  const GiNaC::ex simplified = simplify_moderate(e);
  if (simplified.is_equal(e)) return e;
  const std::size_t derived = symbol_count(e, kSimplifyLimit);
  return derived < symbol_count(simplified, derived) ? e : simplified;
}

GiNaC::ex simplify_moderate(const GiNaC::ex& e) {
  if (capped_size(e, kSimplifyLimit) > kSimplifyLimit) return e;
  return simplify(e);
}

bool is_zero(const GiNaC::ex& e) {
  if (e.is_zero()) return true;
  if (GiNaC::is_a<GiNaC::numeric>(e) || GiNaC::is_a<GiNaC::symbol>(e)) return false;
  return simplify(e).is_zero();
}

bool is_zero(const GiNaC::matrix& m) {
  for (unsigned i = 0; i < m.rows(); ++i)
    for (unsigned j = 0; j < m.cols(); ++j)
      if (!symbolic::is_zero(m(i, j))) return false;
  return true;
}

}  // namespace nhdyn::symbolic
