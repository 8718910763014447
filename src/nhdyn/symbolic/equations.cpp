#include "nhdyn/symbolic/equations.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "nhdyn/core/join.hpp"
#include "nhdyn/symbolic/simplify.hpp"

namespace nhdyn::symbolic {
namespace {

using GiNaC::ex;

// ---------------------------------------------------------------------------------------------
// Names

const std::map<std::string, std::string>& greek() {
  static const std::map<std::string, std::string> table = {
      {"alpha", "\\alpha"},     {"beta", "\\beta"},       {"gamma", "\\gamma"},   {"delta", "\\delta"},
      {"epsilon", "\\varepsilon"}, {"zeta", "\\zeta"},    {"eta", "\\eta"},       {"theta", "\\theta"},
      {"iota", "\\iota"},       {"kappa", "\\kappa"},     {"lambda", "\\lambda"}, {"mu", "\\mu"},
      {"nu", "\\nu"},           {"xi", "\\xi"},           {"rho", "\\rho"},       {"sigma", "\\sigma"},
      {"tau", "\\tau"},         {"upsilon", "\\upsilon"}, {"phi", "\\varphi"},    {"chi", "\\chi"},
      {"psi", "\\psi"},         {"omega", "\\omega"},     {"Gamma", "\\Gamma"},   {"Delta", "\\Delta"},
      {"Theta", "\\Theta"},     {"Lambda", "\\Lambda"},   {"Xi", "\\Xi"},         {"Pi", "\\Pi"},
      {"Sigma", "\\Sigma"},     {"Upsilon", "\\Upsilon"}, {"Phi", "\\Phi"},       {"Psi", "\\Psi"},
      {"Omega", "\\Omega"},     {"varphi", "\\varphi"},   {"vartheta", "\\vartheta"}};
  return table;
}

std::string latex_escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    if (c == '_' || c == '&' || c == '%' || c == '$' || c == '#' || c == '{' || c == '}') out += '\\';
    out += c;
  }
  return out;
}

std::string latex_word(const std::string& word) {
  if (const auto it = greek().find(word); it != greek().end()) return it->second;
  if (word.size() == 1) return word;
  if (std::all_of(word.begin(), word.end(), [](char c) { return c >= '0' && c <= '9'; })) return word;
  return "\\mathrm{" + latex_escape(word) + "}";
}

// A name as LaTeX, with `dots` dots over its head: theta_2 -> \theta_{2}, x1 -> x_{1},
// phi with one dot -> \dot{\varphi}.
std::string latex_name(const std::string& name, int dots = 0) {
  std::string head = name, sub;
  if (const std::size_t underscore = name.find('_'); underscore != std::string::npos && underscore > 0) {
    head = name.substr(0, underscore);
    sub = name.substr(underscore + 1);
  } else if (const std::size_t last = name.find_last_not_of("0123456789");
             last != std::string::npos && last + 1 < name.size()) {
    head = name.substr(0, last + 1);
    sub = name.substr(last + 1);
  }
  std::string out = latex_word(head);
  if (dots == 1) out = "\\dot{" + out + "}";
  if (dots == 2) out = "\\ddot{" + out + "}";
  if (!sub.empty()) out += "_{" + latex_word(sub) + "}";
  return out;
}

// ---------------------------------------------------------------------------------------------
// The printer: terms and factors in an order that depends on names only, and every sign choice
// made on printed text. GiNaC's term order follows its hashes, which change from process to
// process, and with it the sign GiNaC gives a sum inside a product ((a - b) x or -(b - a) x); the
// printer decides such signs itself, bottom-up: a sum that is a factor or the base of an integer
// power gets the sign that makes its first printed term positive, so the text is the same in
// every process (docs/design.md, "Reproducibility").

bool power_of_ten(const GiNaC::numeric& q) {
  std::ostringstream s;
  s << q;
  const std::string text = s.str();
  return text.size() > 1 && text[0] == '1' && text.find_first_not_of('0', 1) == std::string::npos;
}

std::string number(const GiNaC::numeric& x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// p / 10^k as a decimal.
std::string decimal(const GiNaC::numeric& p, const GiNaC::numeric& q) {
  std::string digits = number(GiNaC::abs(p));
  const std::size_t k = number(q).size() - 1;
  if (digits.size() <= k) digits = std::string(k + 1 - digits.size(), '0') + digits;
  return digits.substr(0, digits.size() - k) + "." + digits.substr(digits.size() - k);
}

// A term as printed: its coefficient and its factors' texts above and below the line, in order.
struct TermText {
  GiNaC::numeric coefficient = 1;
  std::vector<std::string> up, down;
};

// +1 for an even function (f(-x) = f(x)), -1 for an odd one (f(-x) = -f(x)), 0 otherwise.
int function_parity(const std::string& name) {
  if (name == "cos" || name == "cosh" || name == "abs") return 1;
  if (name == "sin" || name == "tan" || name == "sinh" || name == "tanh" || name == "asin" || name == "atan" ||
      name == "asinh" || name == "atanh")
    return -1;
  return 0;
}

struct Printed {
  std::string text;       // the magnitude
  bool negative = false;  // the sign in front
  bool fraction = false;  // something below the line
};

class EquationPrinter {
 public:
  EquationPrinter(const Spec& spec, EquationFormat format) : latex_(format == EquationFormat::latex) {
    for (std::size_t p = 0; p < spec.parameters.size(); ++p) {
      const std::string& name = spec.parameters[p].name;
      symbols_[name] = {0, static_cast<int>(p), name, latex_name(name)};
    }
    symbols_["t"] = {4, 0, "t", "t"};
    for (std::size_t i = 0; i < spec.coordinates.size(); ++i) {
      const std::string& c = spec.coordinates[i];
      const int order = static_cast<int>(i);
      symbols_[c] = {3, order, c, latex_name(c)};
      symbols_[c + "'"] = {5, order, c + "'", latex_name(c, 1)};
      symbols_[c + "''"] = {6, order, c + "''", latex_name(c, 2)};
    }
  }

  bool latex() const { return latex_; }

  std::string symbol(const std::string& name) const {
    const auto it = symbols_.find(name);
    if (it != symbols_.end()) return latex_ ? it->second.latex : it->second.text;
    return latex_ ? latex_name(name) : name;
  }

  std::string paren(const std::string& s) const { return latex_ ? "\\left(" + s + "\\right)" : "(" + s + ")"; }

  // A whole expression (not simplified here).
  std::string expression(const ex& e) const { return joined(terms_of(e)); }

  // Sum of coefficient * symbol, in the given order, followed by the terms of `rest`.
  std::string combination(const std::vector<std::pair<ex, std::string>>& products, const ex& rest) const {
    std::vector<Printed> terms;
    for (const auto& [coefficient, name] : products) {
      if (coefficient.is_zero()) continue;
      if (GiNaC::is_a<GiNaC::add>(coefficient)) {
        const std::string sum = expression(coefficient);
        if (sum != "0") terms.push_back({paren(sum) + " " + name, false, false});
        continue;
      }
      Printed p = term(coefficient);
      if (p.text == "0") continue;
      if (p.text == "1")
        p.text = name;
      else if (p.fraction && !latex_)
        p.text = "(" + p.text + ") " + name;
      else
        p.text += " " + name;
      terms.push_back(p);
    }
    if (!rest.is_zero()) {
      const std::vector<Printed> others = terms_of(rest);
      terms.insert(terms.end(), others.begin(), others.end());
    }
    return joined(terms);
  }

 private:
  struct SymbolInfo {
    int category = 7;  // parameters, pi, functions, coordinates, t, velocities, accelerations, other
    int order = 0;
    std::string text, latex;
  };

  static void sort(std::vector<Printed>& terms) {
    std::sort(terms.begin(), terms.end(), [](const Printed& a, const Printed& b) {
      return a.text != b.text ? a.text < b.text : a.negative < b.negative;
    });
  }

  static std::string joined(const std::vector<Printed>& terms) {
    if (terms.empty()) return "0";
    std::string out = terms[0].negative ? "-" + terms[0].text : terms[0].text;
    for (std::size_t i = 1; i < terms.size(); ++i) out += (terms[i].negative ? " - " : " + ") + terms[i].text;
    return out;
  }

  // The terms of e (one unless e is a sum), printed and sorted. Terms that print alike apart from
  // their coefficient are merged: GiNaC keeps x (a - b) and x (b - a) apart, the printer does not.
  std::vector<Printed> terms_of(const ex& e) const {
    std::vector<Printed> out;
    if (!GiNaC::is_a<GiNaC::add>(e)) {
      out.push_back(term(e));
      return out;
    }
    std::map<std::pair<std::vector<std::string>, std::vector<std::string>>, GiNaC::numeric> merged;
    for (std::size_t i = 0; i < e.nops(); ++i) {
      TermText t = decompose(e.op(i));
      auto [it, fresh] = merged.try_emplace({std::move(t.up), std::move(t.down)}, t.coefficient);
      if (!fresh) it->second += t.coefficient;
    }
    for (const auto& [factors, coefficient] : merged)
      if (!coefficient.is_zero()) out.push_back(render({coefficient, factors.first, factors.second}));
    sort(out);
    return out;
  }

  Printed term(const ex& e) const { return render(decompose(e)); }

  // Where a factor goes among the others: parameters, constants, functions, coordinates, ... by
  // the table of names, then by its text.
  std::pair<int, int> factor_rank(const ex& base) const {
    if (GiNaC::is_a<GiNaC::symbol>(base)) {
      const auto it = symbols_.find(GiNaC::ex_to<GiNaC::symbol>(base).get_name());
      if (it != symbols_.end()) return {it->second.category, it->second.order};
      return {7, 0};
    }
    if (GiNaC::is_a<GiNaC::constant>(base)) return {1, 0};
    if (GiNaC::is_a<GiNaC::function>(base)) return {2, 0};
    if (GiNaC::is_a<GiNaC::add>(base)) return {9, 0};
    return {8, 0};
  }

  // sin(u)^p / cos(u)^r -> tan(u)^min(p, r) ... (and the hyperbolic ones), for display only.
  void fold_tangents(std::vector<std::pair<ex, ex>>& factors, const char* s, const char* c,
                     ex (*tangent)(const ex&)) const {
    const auto named = [](const ex& e, const char* name) {
      return GiNaC::is_a<GiNaC::function>(e) && GiNaC::ex_to<GiNaC::function>(e).get_name() == name;
    };
    const auto integer = [](const ex& e) {
      return GiNaC::is_a<GiNaC::numeric>(e) && GiNaC::ex_to<GiNaC::numeric>(e).is_integer();
    };
    std::vector<std::pair<ex, ex>> added;
    for (auto& [up, p] : factors) {
      if (!named(up, s) || !integer(p) || !GiNaC::ex_to<GiNaC::numeric>(p).is_positive()) continue;
      for (auto& [down, r] : factors) {
        if (!named(down, c) || !integer(r) || !GiNaC::ex_to<GiNaC::numeric>(r).is_negative()) continue;
        // The same argument as printed: GiNaC may hold one sum in two signs.
        if (!up.op(0).is_equal(down.op(0)) && expression(up.op(0)) != expression(down.op(0))) continue;
        const GiNaC::numeric m = std::min(GiNaC::ex_to<GiNaC::numeric>(p), -GiNaC::ex_to<GiNaC::numeric>(r));
        added.emplace_back(tangent(up.op(0)), m);
        p = p - m;
        r = r + m;
        break;
      }
    }
    factors.insert(factors.end(), added.begin(), added.end());
    factors.erase(std::remove_if(factors.begin(), factors.end(), [](const auto& f) { return f.second.is_zero(); }),
                  factors.end());
  }

  static ex make_tan(const ex& u) { return GiNaC::tan(u); }
  static ex make_tanh(const ex& u) { return GiNaC::tanh(u); }

  TermText decompose(const ex& e) const {
    TermText t;
    std::vector<std::pair<ex, ex>> factors;
    const auto add_factor = [&](const ex& f) {
      if (GiNaC::is_a<GiNaC::numeric>(f))
        t.coefficient *= GiNaC::ex_to<GiNaC::numeric>(f);
      else if (GiNaC::is_a<GiNaC::power>(f))
        factors.emplace_back(f.op(0), f.op(1));
      else
        factors.emplace_back(f, 1);
    };
    if (GiNaC::is_a<GiNaC::mul>(e))
      for (std::size_t i = 0; i < e.nops(); ++i) add_factor(e.op(i));
    else
      add_factor(e);
    // cos(-x) = cos(x), sin(-x)^n = (-1)^n sin(x)^n: GiNaC keeps the sign of a negated argument
    // (the bicycle's rotation by -lambda gives cos(-lambda) cos(lambda)). Decided on the printed
    // argument, like the sign of a sum: GiNaC holds sin(x (a - b)) as sin(-x (b - a)) in some
    // processes, which prints as sin(x (a - b)) too, while sin(x (b - a)) prints with a '-'.
    for (auto& [base, exponent] : factors) {
      if (!GiNaC::is_a<GiNaC::function>(base) || base.nops() != 1) continue;
      const int parity = function_parity(GiNaC::ex_to<GiNaC::function>(base).get_name());
      const bool integer =
          GiNaC::is_a<GiNaC::numeric>(exponent) && GiNaC::ex_to<GiNaC::numeric>(exponent).is_integer();
      if (parity == 0 || (parity < 0 && !integer)) continue;
      const ex& argument = base.op(0);
      if (expression(argument).rfind('-', 0) != 0) continue;
      if (parity < 0 && GiNaC::ex_to<GiNaC::numeric>(exponent).is_odd()) t.coefficient = -t.coefficient;
      base = GiNaC::function(GiNaC::ex_to<GiNaC::function>(base).get_serial(), -argument);
    }
    // Like factors (cos(lambda) cos(lambda) after the above) become one power. Functions are alike
    // when they print alike: cos(x (a - b)) may be held as cos(-x (b - a)) next to cos(x (a - b)).
    std::vector<std::string> function_text(factors.size());
    for (std::size_t i = 0; i < factors.size(); ++i)
      if (GiNaC::is_a<GiNaC::function>(factors[i].first)) function_text[i] = function(factors[i].first);
    for (std::size_t i = 0; i < factors.size(); ++i) {
      for (std::size_t j = i + 1; j < factors.size();) {
        auto& [base, exponent] = factors[i];
        const bool alike = base.is_equal(factors[j].first) ||
                           (!function_text[i].empty() && function_text[i] == function_text[j]);
        if (GiNaC::is_a<GiNaC::numeric>(exponent) && GiNaC::is_a<GiNaC::numeric>(factors[j].second) && alike) {
          exponent = exponent + factors[j].second;
          factors.erase(factors.begin() + static_cast<std::ptrdiff_t>(j));
          function_text.erase(function_text.begin() + static_cast<std::ptrdiff_t>(j));
        } else {
          ++j;
        }
      }
    }
    factors.erase(std::remove_if(factors.begin(), factors.end(), [](const auto& f) { return f.second.is_zero(); }),
                  factors.end());
    // Folding the tangent back is skipped for expressions with an explicit tan left in them.
    fold_tangents(factors, "sin", "cos", &make_tan);
    fold_tangents(factors, "sinh", "cosh", &make_tanh);
    struct Placed {
      std::pair<int, int> rank;
      std::string text;
      bool operator<(const Placed& o) const { return rank != o.rank ? rank < o.rank : text < o.text; }
    };
    std::vector<Placed> up, down;
    for (const auto& [base, exponent] : factors) {
      const bool below =
          GiNaC::is_a<GiNaC::numeric>(exponent) && GiNaC::ex_to<GiNaC::numeric>(exponent).is_negative();
      const ex power = below ? ex(-exponent) : exponent;
      std::optional<std::string> sum;
      if (GiNaC::is_a<GiNaC::add>(base) && GiNaC::is_a<GiNaC::numeric>(power) &&
          GiNaC::ex_to<GiNaC::numeric>(power).is_integer()) {
        // (b - a)^n = (-1)^n (a - b)^n: the sign whose first printed term is positive.
        std::vector<Printed> terms = terms_of(base);
        if (!terms.empty() && terms[0].negative) {
          for (Printed& p : terms) p.negative = !p.negative;
          sort(terms);
          if (GiNaC::ex_to<GiNaC::numeric>(power).is_odd()) t.coefficient = -t.coefficient;
        }
        sum = joined(terms);
        // A sum whose terms cancel (x (a - b) + x (b - a)) is 0, and so is a term it multiplies.
        if (terms.empty() && !below) return TermText{0, {}, {}};
      }
      (below ? down : up).push_back({factor_rank(base), factor(base, power, sum ? &*sum : nullptr)});
    }
    std::sort(up.begin(), up.end());
    std::sort(down.begin(), down.end());
    for (Placed& p : up) t.up.push_back(std::move(p.text));
    for (Placed& p : down) t.down.push_back(std::move(p.text));
    return t;
  }

  Printed render(const TermText& t) const {
    Printed out;
    GiNaC::numeric c = t.coefficient;
    if (c.is_real() && c.is_negative()) {
      out.negative = true;
      c = -c;
    }
    std::vector<std::string> up, down;
    if (c.is_zero()) {
      out.text = "0";
      return out;
    }
    // A complex coefficient (sqrt(-4) = 2 I): an imaginary one as a real one times I, any other
    // in parentheses (1+2*I x would read 1 + 2 I x).
    const bool imaginary = !c.is_real() && c.real().is_zero();
    if (imaginary) {
      c = c.imag();
      out.negative = c.is_negative();
      if (out.negative) c = -c;
    }
    if (!c.is_real()) {
      up.push_back(paren(number_or_print(c)));
    } else if (c.is_rational()) {
      const GiNaC::numeric p = c.numer(), q = c.denom();
      if (q != 1 && power_of_ten(q)) {
        up.push_back(decimal(p, q));
      } else {
        if (p != 1) up.push_back(number(p));
        if (q != 1) down.push_back(number(q));
      }
    } else {
      up.push_back(number(c));
    }
    if (imaginary) up.push_back(latex_ ? "i" : "I");
    up.insert(up.end(), t.up.begin(), t.up.end());
    down.insert(down.end(), t.down.begin(), t.down.end());
    const std::string top = up.empty() ? "1" : join(up, " ");
    out.fraction = !down.empty();
    if (down.empty())
      out.text = top;
    else if (latex_)
      out.text = "\\frac{" + top + "}{" + join(down, " ") + "}";
    else
      out.text = top + "/" + (down.size() == 1 ? down[0] : "(" + join(down, " ") + ")");
    return out;
  }

  static bool is_number(const ex& e, int p, int q = 1) {
    return GiNaC::is_a<GiNaC::numeric>(e) && GiNaC::ex_to<GiNaC::numeric>(e) == GiNaC::numeric(p, q);
  }

  // base^exponent; `sum`, when given, is the base (a sum) already printed.
  std::string factor(const ex& base, const ex& exponent, const std::string* sum = nullptr) const {
    if (is_number(exponent, 1, 2))
      return latex_ ? "\\sqrt{" + expression(base) + "}" : "sqrt(" + expression(base) + ")";
    std::string base_atom = sum ? paren(*sum) : atom(base);
    // e^{x} takes no second superscript: (e^{x})^{2}.
    if (latex_ && GiNaC::is_a<GiNaC::function>(base) && GiNaC::ex_to<GiNaC::function>(base).get_name() == "exp" &&
        !is_number(exponent, 1))
      base_atom = paren(base_atom);
    if (is_number(exponent, 1)) return base_atom;
    const bool integer =
        GiNaC::is_a<GiNaC::numeric>(exponent) && GiNaC::ex_to<GiNaC::numeric>(exponent).is_pos_integer();
    std::string power;
    if (integer)
      power = number(GiNaC::ex_to<GiNaC::numeric>(exponent));
    else if (GiNaC::is_a<GiNaC::numeric>(exponent))
      power = latex_ ? number(GiNaC::ex_to<GiNaC::numeric>(exponent)) : "(" + number(GiNaC::ex_to<GiNaC::numeric>(exponent)) + ")";
    else if (latex_ || GiNaC::is_a<GiNaC::symbol>(exponent))
      power = expression(exponent);
    else
      power = "(" + expression(exponent) + ")";
    if (latex_ && integer && GiNaC::is_a<GiNaC::function>(base)) {
      // \sin^{2}(\varphi)
      const std::string name = GiNaC::ex_to<GiNaC::function>(base).get_name();
      if (const std::string command = latex_operator(name); !command.empty())
        return command + "^{" + power + "}" + latex_argument(base.op(0));
    }
    return latex_ ? base_atom + "^{" + power + "}" : base_atom + "^" + power;
  }

  // A base or factor: symbols, constants, functions and positive numbers as they are, anything
  // else in parentheses.
  std::string atom(const ex& e) const {
    if (GiNaC::is_a<GiNaC::symbol>(e)) return symbol(GiNaC::ex_to<GiNaC::symbol>(e).get_name());
    if (GiNaC::is_a<GiNaC::constant>(e)) {
      if (e.is_equal(GiNaC::Pi)) return latex_ ? "\\pi" : "pi";
      return number_or_print(e);
    }
    if (GiNaC::is_a<GiNaC::function>(e)) return function(e);
    if (GiNaC::is_a<GiNaC::numeric>(e)) {
      const GiNaC::numeric& n = GiNaC::ex_to<GiNaC::numeric>(e);
      if (n.is_pos_integer()) return number(n);
      return paren(expression(e));
    }
    if (GiNaC::is_a<GiNaC::add>(e) || GiNaC::is_a<GiNaC::mul>(e) || GiNaC::is_a<GiNaC::power>(e))
      return paren(expression(e));
    return number_or_print(e);
  }

  std::string number_or_print(const ex& e) const {
    std::ostringstream s;
    if (latex_) s << GiNaC::latex;
    s << e;
    return s.str();
  }

  static std::string latex_operator(const std::string& name) {
    static const std::map<std::string, std::string> table = {
        {"sin", "\\sin"},       {"cos", "\\cos"},       {"tan", "\\tan"},   {"sinh", "\\sinh"},
        {"cosh", "\\cosh"},     {"tanh", "\\tanh"},     {"log", "\\ln"},    {"asin", "\\arcsin"},
        {"acos", "\\arccos"},   {"atan", "\\arctan"}};
    const auto it = table.find(name);
    return it == table.end() ? "" : it->second;
  }

  std::string latex_argument(const ex& argument) const {
    if (GiNaC::is_a<GiNaC::symbol>(argument) || GiNaC::is_a<GiNaC::constant>(argument) ||
        (GiNaC::is_a<GiNaC::numeric>(argument) && GiNaC::ex_to<GiNaC::numeric>(argument).is_pos_integer()))
      return "(" + atom(argument) + ")";  // \cos(\varphi): a bare \cos \varphi x reads ambiguously
    return "\\left(" + expression(argument) + "\\right)";
  }

  std::string function(const ex& e) const {
    const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
    std::vector<std::string> arguments;
    for (std::size_t i = 0; i < e.nops(); ++i) arguments.push_back(expression(e.op(i)));
    if (!latex_) return name + "(" + join(arguments, ", ") + ")";
    if (const std::string command = latex_operator(name); !command.empty()) return command + latex_argument(e.op(0));
    if (name == "exp") return "e^{" + arguments[0] + "}";
    if (name == "abs") return "\\left|" + arguments[0] + "\\right|";
    return "\\operatorname{" + latex_escape(name) + "}\\left(" + join(arguments, ", ") + "\\right)";
  }

  bool latex_;
  std::map<std::string, SymbolInfo> symbols_;
};

// ---------------------------------------------------------------------------------------------
// What is shown, computed once for both formats.

struct ConstraintView {
  std::string name;
  ConstraintLevel level;
  ex expression;
  std::vector<ex> b;
  ex b0;
};

// A program (docs/derivations/program-motion.md): shown like a constraint, with its actuator.
struct ProgramView {
  ConstraintView constraint;
  std::string actuator_text;  // as written: "delta" or "[0, 0, 1]"
};

struct Content {
  ex T, V;
  GiNaC::matrix A, Q, G;
  std::vector<ConstraintView> constraints;
  std::vector<ProgramView> programs;       // m of them
  GiNaC::matrix B = GiNaC::matrix(0, 0);   // n x m, the actuator matrix
  std::optional<GiNaC::matrix> DB;         // k x m, D B: how the actuators enter the reduced equations
  std::optional<GiNaC::matrix> D;
  // too_large: the terms are too large to look for a partition symbolically (entries of more than
  // kSimplifyLimit nodes; the Whipple bicycle).
  enum class Origin { analytic, independent, none_constraints, fallback, unavailable, too_large, modes } origin =
      Origin::unavailable;
  std::vector<std::string> independent;  // names, for independent and fallback
  std::optional<GiNaC::matrix> A0, C;
  std::optional<ex> energy;
};

// Whether every entry of D is a finite number at the model's initial state (t0, q0, q0', the
// parameters' values): a partition singular there (x independent, D = [1, -x/y], for a pendulum
// that starts at y = 0) would fail at once if the model took it.
bool regular_at_start(const Spec& spec, const GiNaC::matrix& D) {
  try {
    GiNaC::lst at = spec.parameter_values();
    at.append(spec.symbols.time() == GiNaC::numeric(spec.t0));
    for (int i = 0; i < spec.n(); ++i) {
      const std::size_t u = static_cast<std::size_t>(i);
      if (u >= spec.q0.size() || u >= spec.v0.size()) return false;
      at.append(spec.symbols.coordinate(i) == spec.q0[u].subs(spec.parameter_values()));
      at.append(spec.symbols.velocity(i) == spec.v0[u].subs(spec.parameter_values()));
    }
    for (unsigned r = 0; r < D.rows(); ++r)
      for (unsigned c = 0; c < D.cols(); ++c) {
        const ex value = GiNaC::evalf(D(r, c).subs(at));
        if (!GiNaC::is_a<GiNaC::numeric>(value) || !GiNaC::ex_to<GiNaC::numeric>(value).is_real() ||
            !std::isfinite(GiNaC::ex_to<GiNaC::numeric>(value).to_double()))
          return false;
      }
    return true;
  } catch (const std::exception&) {  // a division by zero there (GiNaC throws)
    return false;
  }
}

// The first choice of k independent coordinates (in lexicographic order of their indices) for
// which the partitioned D exists, preferring one regular at the initial state; at most `budget`
// choices are tried.
std::optional<std::pair<std::vector<int>, GiNaC::matrix>> first_partition(const Spec& spec, const GiNaC::matrix& b,
                                                                         int n, int k) {
  std::vector<int> choice(static_cast<std::size_t>(k));
  for (int i = 0; i < k; ++i) choice[static_cast<std::size_t>(i)] = i;
  std::optional<std::pair<std::vector<int>, GiNaC::matrix>> first;
  for (int budget = 200; budget > 0; --budget) {
    if (std::optional<GiNaC::matrix> D = partitioned_complement(b, choice)) {
      if (regular_at_start(spec, *D)) return std::make_pair(choice, *D);
      if (!first) first = std::make_pair(choice, *D);
    }
    int i = k - 1;
    while (i >= 0 && choice[static_cast<std::size_t>(i)] == n - k + i) --i;
    if (i < 0) break;
    ++choice[static_cast<std::size_t>(i)];
    for (int j = i + 1; j < k; ++j) choice[static_cast<std::size_t>(j)] = choice[static_cast<std::size_t>(j - 1)] + 1;
  }
  return first;
}

// Whether some entry of m has more than kSimplifyLimit nodes (simplify_moderate leaves it as is).
// The count stops at the limit, so a large entry costs no more than a small one.
bool has_large_entry(const GiNaC::matrix& m) {
  for (unsigned i = 0; i < m.rows(); ++i)
    for (unsigned j = 0; j < m.cols(); ++j) {
      std::size_t count = 0;
      std::vector<ex> stack{m(i, j)};
      while (!stack.empty() && count <= kSimplifyLimit) {
        const ex e = stack.back();
        stack.pop_back();
        ++count;
        for (std::size_t o = 0; o < e.nops(); ++o) stack.push_back(e.op(o));
      }
      if (count > kSimplifyLimit) return true;
    }
  return false;
}

// The partitioned D shown when the model gives none inverts b_d symbolically, whose cost grows
// steeply with its entries: an egg's implicit contact (b of 851 nodes, s = 6) took GiNaC's gcd more
// than ten minutes. Beyond this many nodes of b in all, no partition is looked for (the examples
// with one have at most 135: the torus wheel).
constexpr std::size_t kPartitionNodeLimit = 400;

// The nodes of all entries of m together, counted up to `cap` (and one beyond it).
std::size_t total_nodes(const GiNaC::matrix& m, std::size_t cap) {
  std::size_t count = 0;
  std::vector<ex> stack;
  for (unsigned i = 0; i < m.rows(); ++i)
    for (unsigned j = 0; j < m.cols(); ++j) stack.push_back(m(i, j));
  while (!stack.empty() && count <= cap) {
    const ex e = stack.back();
    stack.pop_back();
    ++count;
    for (std::size_t o = 0; o < e.nops(); ++o) stack.push_back(e.op(o));
  }
  return count;
}

Content make_content(const Spec& spec, const Derivation& d) {
  Content c;
  const int n = spec.n(), s = spec.s(), k = n - s;
  // A large model (the Whipple bicycle) is shown with its large entries as derived: simplifying
  // them, inverting b_dep symbolically or multiplying out D A would take minutes.
  const bool large = has_large_entry(d.A) || has_large_entry(d.G) || has_large_entry(d.b) || has_large_entry(d.b0);
  const auto tidy = [large](const ex& e) { return large ? simplify_moderate(e) : simplify(e); };
  const auto tidy_matrix = [&](const GiNaC::matrix& m) {
    GiNaC::matrix out(m.rows(), m.cols());
    for (unsigned i = 0; i < m.rows(); ++i)
      for (unsigned j = 0; j < m.cols(); ++j) out(i, j) = tidy(m(i, j));
    return out;
  };
  c.T = tidy(spec.kinetic_energy);
  c.V = tidy(spec.potential_energy);
  c.A = tidy_matrix(d.A);
  c.Q = tidy_matrix(d.Q);
  c.G = tidy_matrix(d.G);
  for (unsigned r = 0; r < static_cast<unsigned>(s); ++r) {
    ConstraintView view{spec.constraints[r].name, spec.constraints[r].level, tidy(spec.constraints[r].expression),
                        {}, tidy(d.b0(r, 0))};
    for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) view.b.push_back(tidy(d.b(r, j)));
    c.constraints.push_back(std::move(view));
  }
  const int m = spec.m();
  for (unsigned r = 0; r < static_cast<unsigned>(m); ++r) {
    const SpecProgram& program = spec.programs[r];
    ProgramView view{{program.constraint.name, program.constraint.level, tidy(program.constraint.expression), {},
                      tidy(d.b_p0(r, 0))},
                     program.actuator_text};
    for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) view.constraint.b.push_back(tidy(d.b_p(r, j)));
    c.programs.push_back(std::move(view));
  }
  if (m > 0) c.B = tidy_matrix(d.B);
  Derivation with_d = d;
  if (d.D) {
    c.origin = spec.complement ? Content::Origin::analytic : Content::Origin::independent;
    if (!spec.complement) {
      for (const std::string& name : spec.coordinates)
        if (std::find(spec.independent.begin(), spec.independent.end(), name) != spec.independent.end())
          c.independent.push_back(name);
    }
  } else if (s >= n) {
    c.origin = Content::Origin::modes;  // contacts never all held: a D for each set of modes, in the run
  } else if (s == 0) {
    c.origin = Content::Origin::none_constraints;
    with_d.D = GiNaC::ex_to<GiNaC::matrix>(GiNaC::unit_matrix(static_cast<unsigned>(n)));
  } else if (large || total_nodes(d.b, kPartitionNodeLimit) > kPartitionNodeLimit) {
    c.origin = Content::Origin::too_large;
  } else if (const auto partition = first_partition(spec, d.b, n, k)) {
    c.origin = Content::Origin::fallback;
    for (const int i : partition->first) c.independent.push_back(spec.coordinates[static_cast<std::size_t>(i)]);
    with_d.D = partition->second;
  }
  if (with_d.D) {
    c.D = tidy_matrix(*with_d.D);
    if (large) {
      c.A0 = tidy_matrix(with_d.D->mul(d.A));
      c.C = tidy_matrix(with_d.D->mul(d.Q.add(d.G)));
    } else {
      c.A0 = reduced_inertia(with_d);
      c.C = reduced_forces(with_d);
    }
    if (m > 0) c.DB = tidy_matrix(with_d.D->mul(d.B));
  }
  if (d.energy) c.energy = tidy(*d.energy);
  return c;
}

// Every acceleration symbol as printed, in the order of q.
std::vector<std::string> accelerations(const Spec& spec, const EquationPrinter& p) {
  std::vector<std::string> out;
  for (const std::string& c : spec.coordinates) out.push_back(p.symbol(c + "''"));
  return out;
}

std::string parameter_list(const Spec& spec) {
  std::vector<std::string> items;
  for (const SpecParameter& p : spec.parameters)
    items.push_back(fmt::format("{} = {}{}", p.name, p.value, p.unit.empty() ? "" : " " + p.unit));
  return join(items, ", ");
}

std::string independent_hint(const std::vector<std::string>& names) {
  std::vector<std::string> quoted;
  for (const std::string& name : names) quoted.push_back("\"" + name + "\"");
  return "independent = [" + join(quoted, ", ") + "]";
}

// ---------------------------------------------------------------------------------------------
// Text

std::string text_matrix(const EquationPrinter& p, const GiNaC::matrix& m, const std::string& indent) {
  std::vector<std::vector<std::string>> cells(m.rows());
  std::vector<std::size_t> width(m.cols(), 0);
  for (unsigned i = 0; i < m.rows(); ++i)
    for (unsigned j = 0; j < m.cols(); ++j) {
      cells[i].push_back(p.expression(m(i, j)));
      width[j] = std::max(width[j], cells[i].back().size());
    }
  std::string out;
  for (unsigned i = 0; i < m.rows(); ++i) {
    out += indent + "[ ";
    for (unsigned j = 0; j < m.cols(); ++j) {
      out += cells[i][j] + std::string(width[j] - cells[i][j].size(), ' ');
      if (j + 1 < m.cols()) out += "  ";
    }
    out += " ]\n";
  }
  return out;
}

std::string text_vector(const EquationPrinter& p, const std::string& name, const GiNaC::matrix& v,
                        const std::vector<std::string>& labels) {
  std::size_t width = 0;
  for (const std::string& label : labels) width = std::max(width, label.size());
  std::string out;
  for (unsigned i = 0; i < v.rows(); ++i) {
    const std::string& label = labels[i];
    out += fmt::format("  {}_{}{} = {}\n", name, label, std::string(width - label.size(), ' '), p.expression(v(i, 0)));
  }
  return out;
}

std::string format_text(const Spec& spec, const Content& c) {
  const EquationPrinter p(spec, EquationFormat::text);
  const int n = spec.n(), s = spec.s(), k = n - s;
  std::string out = fmt::format("Model {}{}\n", spec.name, spec.description.empty() ? "" : ": " + spec.description);
  out += s >= n ? fmt::format("  q = ({}); n = {} coordinates, s = {} constraint{}, never all held (contact modes)\n",
                              join(spec.coordinates, ", "), n, s, s == 1 ? "" : "s")
                : fmt::format("  q = ({}); n = {} coordinates, s = {} constraint{}, k = n - s = {}\n",
                              join(spec.coordinates, ", "), n, s, s == 1 ? "" : "s", k);
  if (!spec.parameters.empty()) out += "  parameters: " + parameter_list(spec) + "\n";

  out += "\nKinetic energy\n  T = " + p.expression(c.T) + "\n";
  out += "Potential energy\n  V = " + p.expression(c.V) + "\n";
  out += "\nInertia matrix A = d2T/dq'2\n" + text_matrix(p, c.A, "  ");
  out += "Generalized forces Q = -dV/dq + forces\n" + text_vector(p, "Q", c.Q, spec.coordinates);
  out += "Velocity terms G = dT/dq - (d2T/dq'dq) q' - d2T/dq'dt\n" + text_vector(p, "G", c.G, spec.coordinates);

  if (s > 0) {
    out += "\nConstraints, at acceleration level b q'' + b0 = 0\n";
    for (const ConstraintView& v : c.constraints) {
      out += fmt::format("  {} ({} level): {} = 0\n", v.name, level_name(v.level), p.expression(v.expression));
      GiNaC::matrix row(1, static_cast<unsigned>(n));
      for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) row(0, j) = v.b[j];
      out += "    b  = " + text_matrix(p, row, "");
      out += "    b0 = " + p.expression(v.b0) + "\n";
    }
  }
  if (!c.programs.empty()) {
    const int m = static_cast<int>(c.programs.size());
    out += fmt::format("\nPrograms (m = {}), at acceleration level b_p q'' + b_p0 = 0, each realized by its actuator\n", m);
    for (const ProgramView& v : c.programs) {
      out += fmt::format("  {} ({} level, actuator {}): {} = 0\n", v.constraint.name, level_name(v.constraint.level),
                         v.actuator_text, p.expression(v.constraint.expression));
      GiNaC::matrix row(1, static_cast<unsigned>(n));
      for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) row(0, j) = v.constraint.b[j];
      out += "    b_p  = " + text_matrix(p, row, "");
      out += "    b_p0 = " + p.expression(v.constraint.b0) + "\n";
    }
    std::vector<std::string> columns;
    for (const ProgramView& v : c.programs) columns.push_back("u_" + v.constraint.name);
    out += fmt::format("Actuator matrix B ({} x {}): the generalized force B u, u = ({})\n", n, m, join(columns, ", "));
    out += text_matrix(p, c.B, "  ");
  }

  out += "\n";
  switch (c.origin) {
    case Content::Origin::analytic: out += fmt::format("Complement D ({} x {}), analytic (given with the model)\n", k, n); break;
    case Content::Origin::independent:
      out += fmt::format("Complement D ({} x {}), partitioned with {} independent\n", k, n, join(c.independent, ", "));
      break;
    case Content::Origin::none_constraints: out += "Complement D: no constraints, D = I\n"; break;
    case Content::Origin::fallback:
      out += fmt::format("Complement D: none in the model (no independent coordinates, no analytic D)\n"
                         "  The solver chooses the dependent coordinates numerically at each step. Shown here is the\n"
                         "  partitioned D ({} x {}) with {} independent; add {} to the model to use it:\n",
                         k, n, join(c.independent, ", "), independent_hint(c.independent));
      break;
    case Content::Origin::unavailable:
      out += fmt::format("Complement D: the model gives none (no independent coordinates, no analytic D), and no "
                         "choice of {} independent coordinates gives a regular partition symbolically\n",
                         k);
      break;
    case Content::Origin::too_large:
      out += fmt::format("Complement D: the model gives none (no independent coordinates, no analytic D), and its "
                         "terms are too large (an entry of more than {} nodes, or b of more than {} in all) to look for "
                         "a partition symbolically; the solver chooses D numerically at each step\n",
                         kSimplifyLimit, kPartitionNodeLimit);
      break;
    case Content::Origin::modes:
      out += fmt::format("Complement D: none for all {} rows at once (s >= n: the contacts are never all held); the run "
                         "keeps the rows of the contacts touching, r < n, and takes D (n - r rows) for them "
                         "(docs/contact-modes.md, \"More contacts than freedom\")\n",
                         s);
      break;
  }
  if (c.origin == Content::Origin::modes) {
    // Nothing reduced to show: the reduced system changes with the modes.
  } else if (!c.D || !c.A0 || !c.C) {
    out += fmt::format("Reduced inertia A0 = D A and reduced forces C = D (Q + G): unavailable without D; add "
                       "`independent = [...]` with k = {} coordinate names to the model\n",
                       k);
  } else {
    if (c.origin != Content::Origin::none_constraints) out += text_matrix(p, *c.D, "  ");
    out += "Reduced inertia A0 = D A\n" + text_matrix(p, *c.A0, "  ");
    std::vector<std::string> rows;
    for (int i = 1; i <= k; ++i) rows.push_back(std::to_string(i));
    out += "Reduced forces C = D (Q + G)\n" + text_vector(p, "C", *c.C, rows);
    const bool programs = !c.programs.empty() && c.DB;
    if (programs) out += "Reduced actuator matrix D B\n" + text_matrix(p, *c.DB, "  ");
    out += programs ? "\nEquations of motion A0 q'' - D B u = C" : "\nEquations of motion A0 q'' = C";
    out += s > 0 ? ", b q'' + b0 = 0" : "";
    out += programs ? ", b_p q'' + b_p0 = 0 (unknowns q'' and u)\n" : "\n";
    const std::vector<std::string> names = accelerations(spec, p);
    for (unsigned i = 0; i < static_cast<unsigned>(k); ++i) {
      std::vector<std::pair<ex, std::string>> products;
      for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) products.emplace_back((*c.A0)(i, j), names[j]);
      if (programs)
        for (unsigned j = 0; j < c.programs.size(); ++j)
          products.emplace_back(-(*c.DB)(i, j), "u_" + c.programs[j].constraint.name);
      out += "  " + p.combination(products, 0) + " = " + p.expression((*c.C)(i, 0)) + "\n";
    }
    for (const ConstraintView& v : c.constraints) {
      std::vector<std::pair<ex, std::string>> products;
      for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) products.emplace_back(v.b[j], names[j]);
      out += "  " + p.combination(products, v.b0) + " = 0   (" + v.name + ")\n";
    }
    for (const ProgramView& v : c.programs) {
      std::vector<std::pair<ex, std::string>> products;
      for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) products.emplace_back(v.constraint.b[j], names[j]);
      out += "  " + p.combination(products, v.constraint.b0) + " = 0   (program " + v.constraint.name + ")\n";
    }
  }
  if (c.energy) out += "\nEnergy E = T + V\n  E = " + p.expression(*c.energy) + "\n";
  return out;
}

// ---------------------------------------------------------------------------------------------
// LaTeX

std::string latex_matrix(const EquationPrinter& p, const GiNaC::matrix& m) {
  std::vector<std::string> rows;
  for (unsigned i = 0; i < m.rows(); ++i) {
    std::vector<std::string> cells;
    for (unsigned j = 0; j < m.cols(); ++j) cells.push_back(p.expression(m(i, j)));
    rows.push_back(join(cells, " & "));
  }
  return "\\begin{pmatrix} " + join(rows, " \\\\ ") + " \\end{pmatrix}";
}

std::string format_latex(const Spec& spec, const Content& c) {
  const EquationPrinter p(spec, EquationFormat::latex);
  const int n = spec.n(), s = spec.s(), k = n - s;
  std::vector<std::string> names;
  for (const std::string& coordinate : spec.coordinates) names.push_back(p.symbol(coordinate));
  std::string out = fmt::format("% Equations of motion of the model '{}' in the form of Do Sanh, by nhdyn.\n", spec.name);
  if (!spec.description.empty()) out += "% " + spec.description + "\n";
  if (!spec.parameters.empty()) out += "% Parameters: " + parameter_list(spec) + "\n";
  out += "% Needs \\usepackage{amsmath}.\n";

  std::vector<std::string> rows;
  rows.push_back("q &= \\left(" + join(names, ", ") + "\\right)");
  rows.push_back("T &= " + p.expression(c.T));
  rows.push_back("V &= " + p.expression(c.V));
  rows.push_back("A &= \\frac{\\partial^2 T}{\\partial \\dot{q}^2} = " + latex_matrix(p, c.A));
  rows.push_back("Q &= -\\frac{\\partial V}{\\partial q} + F = " + latex_matrix(p, c.Q));
  rows.push_back("G &= \\frac{\\partial T}{\\partial q} - \\frac{\\partial^2 T}{\\partial \\dot{q}\\, \\partial q} "
                 "\\dot{q} - \\frac{\\partial^2 T}{\\partial \\dot{q}\\, \\partial t} = " +
                 latex_matrix(p, c.G));
  for (const ConstraintView& v : c.constraints) {
    const std::string name = latex_escape(v.name);
    rows.push_back(fmt::format("\\intertext{{Constraint \\texttt{{{}}}, given at {} level:}}", name, level_name(v.level)) +
                   p.expression(v.expression) + " &= 0");
    GiNaC::matrix row(1, static_cast<unsigned>(n));
    for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) row(0, j) = v.b[j];
    rows.push_back("b_{\\text{" + name + "}} &= " + latex_matrix(p, row) + ", \\qquad b_{0,\\text{" + name +
                   "}} = " + p.expression(v.b0));
  }
  for (const ProgramView& program : c.programs) {
    const ConstraintView& v = program.constraint;
    const std::string name = latex_escape(v.name);
    rows.push_back(fmt::format("\\intertext{{Program \\texttt{{{}}}, given at {} level, realized by the actuator "
                               "\\texttt{{{}}}:}}",
                               name, level_name(v.level), latex_escape(program.actuator_text)) +
                   p.expression(v.expression) + " &= 0");
    GiNaC::matrix row(1, static_cast<unsigned>(n));
    for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) row(0, j) = v.b[j];
    rows.push_back("b_{p,\\text{" + name + "}} &= " + latex_matrix(p, row) + ", \\qquad b_{p0,\\text{" + name +
                   "}} = " + p.expression(v.b0));
  }
  if (!c.programs.empty()) rows.push_back("\\intertext{Actuator matrix (the generalized force $B u$):}B &= " + latex_matrix(p, c.B));
  std::vector<std::string> independent;
  for (const std::string& name : c.independent)
    independent.push_back(p.symbol(name));
  std::string heading;
  switch (c.origin) {
    case Content::Origin::analytic: heading = "Complement $D$, analytic (given with the model):"; break;
    case Content::Origin::independent:
      heading = "Complement $D$, partitioned with $" + join(independent, ", ") + "$ independent:";
      break;
    case Content::Origin::none_constraints: heading = "No constraints: $D = I$."; break;
    case Content::Origin::fallback:
      heading = "The model gives no complement $D$; the solver picks the dependent coordinates numerically. "
                "With $" + join(independent, ", ") + "$ independent (add \\texttt{" +
                latex_escape(independent_hint(c.independent)) + "} to the model to fix this choice):";
      break;
    case Content::Origin::unavailable:
      heading = fmt::format("The model gives no complement $D$ and no choice of {} independent coordinates gives a "
                            "regular partition symbolically.",
                            k);
      break;
    case Content::Origin::too_large:
      heading = fmt::format("The model gives no complement $D$, and its terms are too large (an entry of more than {} "
                            "nodes, or $b$ of more than {} in all) to look for a partition symbolically.",
                            kSimplifyLimit, kPartitionNodeLimit);
      break;
    case Content::Origin::modes:
      heading = "No complement $D$ for all the rows at once ($s \\ge n$: the contacts are never all held); the run "
                "keeps the rows of the contacts touching and takes $D$ for them.";
      break;
  }
  if (c.origin == Content::Origin::modes) {
    rows.push_back("\\intertext{" + heading + "}");
  } else if (!c.D || !c.A0 || !c.C) {
    rows.push_back("\\intertext{" + heading +
                   fmt::format(" $A_0 = D A$ and $C = D (Q + G)$ are unavailable without $D$; add "
                               "\\texttt{{independent = [...]}} with $k = {}$ coordinate names to the model.}}",
                               k) +
                   "k &= n - s = " + std::to_string(k));
  } else {
    const std::string d_row = c.origin == Content::Origin::none_constraints ? "D &= I" : "D &= " + latex_matrix(p, *c.D);
    rows.push_back("\\intertext{" + heading + "}" + d_row);
    rows.push_back("A_0 &= D A = " + latex_matrix(p, *c.A0));
    rows.push_back("C &= D (Q + G) = " + latex_matrix(p, *c.C));
    const bool programs = !c.programs.empty() && c.DB;
    if (programs) rows.push_back("D B &= " + latex_matrix(p, *c.DB));
    const std::vector<std::string> accelerations_ = accelerations(spec, p);
    bool first = true;
    for (unsigned i = 0; i < static_cast<unsigned>(k); ++i) {
      std::vector<std::pair<ex, std::string>> products;
      for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) products.emplace_back((*c.A0)(i, j), accelerations_[j]);
      if (programs)
        for (unsigned j = 0; j < c.programs.size(); ++j)
          products.emplace_back(-(*c.DB)(i, j), "u_{\\text{" + latex_escape(c.programs[j].constraint.name) + "}}");
      std::string row = p.combination(products, 0) + " &= " + p.expression((*c.C)(i, 0));
      if (first) row = std::string("\\intertext{Equations of motion $A_0 \\ddot{q}") + (programs ? " - D B u" : "") +
                       " = C$" + (s > 0 ? ", $b \\ddot{q} + b_0 = 0$" : "") +
                       (programs ? ", $b_p \\ddot{q} + b_{p0} = 0$ (unknowns $\\ddot{q}$ and $u$)" : "") + ":}" + row;
      first = false;
      rows.push_back(row);
    }
    for (const ConstraintView& v : c.constraints) {
      std::vector<std::pair<ex, std::string>> products;
      for (unsigned j = 0; j < static_cast<unsigned>(n); ++j) products.emplace_back(v.b[j], accelerations_[j]);
      rows.push_back(p.combination(products, v.b0) + " &= 0");
    }
    for (const ProgramView& program : c.programs) {
      std::vector<std::pair<ex, std::string>> products;
      for (unsigned j = 0; j < static_cast<unsigned>(n); ++j)
        products.emplace_back(program.constraint.b[j], accelerations_[j]);
      rows.push_back(p.combination(products, program.constraint.b0) + " &= 0");
    }
  }
  if (c.energy) rows.push_back("\\intertext{Energy:}E &= T + V = " + p.expression(*c.energy));
  out += "\\begin{align*}\n  " + join(rows, " \\\\\n  ") + "\n\\end{align*}\n";
  return out;
}

}  // namespace

std::string format_expression(const Spec& spec, const GiNaC::ex& e, EquationFormat format) {
  return EquationPrinter(spec, format).expression(simplify(e));
}

std::string format_equations(const Spec& spec, const Derivation& derivation, EquationFormat format) {
  const Content content = make_content(spec, derivation);
  return format == EquationFormat::latex ? format_latex(spec, content) : format_text(spec, content);
}

}  // namespace nhdyn::symbolic
