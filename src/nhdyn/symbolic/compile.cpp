// Compilation of GiNaC expressions into straight-line programs (model/program.hpp).
//
// Parameters stay symbols: each becomes a `parameter` instruction, which the evaluator binds to
// the Model's current values (so a parameter changes without recompiling). The constants (pi) are
// made numeric, and in a product the factors that depend on parameters only are gathered into one
// subexpression, which the evaluator computes once per parameter change (its parameter stage)
// instead of at every call. The expression DAG is then walked from the outputs, every
// subexpression memoized by structural equality, so that a subexpression shared by several terms
// (sin(phi) in A, G, b, b0) is computed once. The walk never depends on GiNaC's internal term
// order, which follows symbol serial numbers and addresses: the operands of sums and products are
// sorted by a structural hash of our own (canonical_key), so the program — and the generated code
// printed from it — is the same in every process.
#include "nhdyn/symbolic/compile.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/model/program.hpp"

namespace nhdyn::symbolic {
namespace {

constexpr const char* kSupportedFunctions =
    "sin, cos, tan, exp, log, abs, sqrt, asin, acos, atan, atan2, sinh, cosh, tanh";

std::string to_text(const GiNaC::ex& e) {
  std::ostringstream out;
  out << e;
  return out.str();
}

std::uint64_t mix(std::uint64_t h, std::uint64_t x) {
  // splitmix64 finaliser over the running hash: order-dependent, well spread.
  std::uint64_t z = h ^ (x + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2));
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

std::uint64_t hash_string(const std::string& s) {
  std::uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a
  for (unsigned char ch : s) {
    h ^= ch;
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::uint64_t hash_double(double x) {
  if (x == 0.0) x = 0.0;  // -0 and +0 alike
  std::uint64_t bits = 0;
  std::memcpy(&bits, &x, sizeof bits);
  return bits;
}

double numeric_value(const GiNaC::numeric& x) { return x.to_double(); }

// Splits a term of a sum into (rest, coefficient): 3.5*x*y -> (x*y, 3.5), x -> (x, 1).
std::pair<GiNaC::ex, double> split_coefficient(const GiNaC::ex& term) {
  if (GiNaC::is_exactly_a<GiNaC::mul>(term)) {
    const std::size_t n = term.nops();
    const GiNaC::ex last = term.op(n - 1);
    if (GiNaC::is_exactly_a<GiNaC::numeric>(last) && GiNaC::ex_to<GiNaC::numeric>(last).is_real()) {
      GiNaC::exvector factors;
      factors.reserve(n - 1);
      for (std::size_t i = 0; i + 1 < n; ++i) factors.push_back(term.op(i));
      return {GiNaC::mul(factors), numeric_value(GiNaC::ex_to<GiNaC::numeric>(last))};
    }
  }
  return {term, 1.0};
}

// A power with a negative real numeric exponent: it belongs to the denominator of a product.
bool is_reciprocal(const GiNaC::ex& e) {
  if (!GiNaC::is_exactly_a<GiNaC::power>(e)) return false;
  const GiNaC::ex exponent = e.op(1);
  return GiNaC::is_exactly_a<GiNaC::numeric>(exponent) && GiNaC::ex_to<GiNaC::numeric>(exponent).is_real() &&
         GiNaC::ex_to<GiNaC::numeric>(exponent).is_negative();
}

// The translation of expressions of one spec into one Program.
class ProgramCompiler {
 public:
  explicit ProgramCompiler(const Spec& spec)
      : spec_(spec), program_(spec.n(), static_cast<int>(spec.parameters.size())) {
    for (std::size_t i = 0; i < spec.parameters.size(); ++i)
      parameters_.emplace(spec.symbols.parameter(spec.parameters[i].name), static_cast<int>(i));
    const SymbolTable& symbols = spec.symbols;
    variables_.emplace(symbols.time(), Program::time_register());
    for (int i = 0; i < symbols.coordinates(); ++i) {
      variables_.emplace(symbols.coordinate(i), program_.coordinate_register(i));
      variables_.emplace(symbols.velocity(i), program_.velocity_register(i));
    }
  }

  // Compiles `e` (parameters still symbolic) into the next output; `what` names it in errors.
  void add_output(const GiNaC::ex& e, const std::string& what) {
    if (e.is_zero()) {
      program_.add_constant_output(0.0);
      return;
    }
    what_ = what;
    original_ = e;
    GiNaC::ex numeric_form;
    try {
      numeric_form = with_values(e);
    } catch (const std::exception& error) {
      fail(fmt::format("cannot be evaluated ({})", error.what()));
    }
    if (GiNaC::is_exactly_a<GiNaC::numeric>(numeric_form)) {
      const GiNaC::numeric& x = GiNaC::ex_to<GiNaC::numeric>(numeric_form);
      if (!x.is_real()) emit_numeric(x);  // throws
      program_.add_constant_output(numeric_value(x));
    } else {
      program_.add_output(emit(numeric_form));
    }
  }

  // `e` with the constants (pi) replaced by their values, every distinct node once: derived terms
  // share large subexpressions (a bicycle's entries of A and G), which GiNaC's subs() and evalf()
  // would walk once per path to them. Numeric operands fold as GiNaC rebuilds each node (sums,
  // products, powers and functions of floats evaluate).
  GiNaC::ex with_values(const GiNaC::ex& e) {
    if (GiNaC::is_a<GiNaC::symbol>(e)) {
      const auto found = values_.find(e);
      return found == values_.end() ? e : found->second;
    }
    if (GiNaC::is_exactly_a<GiNaC::constant>(e)) return e.evalf();
    if (e.nops() == 0) return e;
    const GiNaC::basic* node = &GiNaC::ex_to<GiNaC::basic>(e);
    const auto found = with_values_memo_.find(node);
    if (found != with_values_memo_.end()) return found->second.second;
    struct Children : GiNaC::map_function {
      ProgramCompiler& self;
      explicit Children(ProgramCompiler& compiler) : self(compiler) {}
      GiNaC::ex operator()(const GiNaC::ex& x) override { return self.with_values(x); }
    } children(*this);
    GiNaC::ex out = e.map(children);
    // The node itself is kept in the memo so that its address cannot be reused by another.
    with_values_memo_.emplace(node, std::make_pair(e, out));
    return out;
  }

  // An output that is NaN at every call (an expression that cannot be evaluated).
  void add_nan_output() { program_.add_constant_output(std::numeric_limits<double>::quiet_NaN()); }

  // The finished program, with each sin(x), cos(x) pair fused into one sincos.
  Program finish() const { return fuse_sincos(program_); }

 private:
  [[noreturn]] void fail(const std::string& message) const {
    throw ModelError(fmt::format("model '{}': {} = {} {}", spec_.name, what_, to_text(original_), message));
  }

  int emit(const GiNaC::ex& e) {
    const auto found = memo_.find(e);
    if (found != memo_.end()) return found->second;
    const int r = emit_new(e);
    memo_.emplace(e, r);
    return r;
  }

  int emit_new(const GiNaC::ex& e) {
    if (GiNaC::is_exactly_a<GiNaC::numeric>(e)) return emit_numeric(GiNaC::ex_to<GiNaC::numeric>(e));
    if (GiNaC::is_a<GiNaC::symbol>(e)) return emit_symbol(GiNaC::ex_to<GiNaC::symbol>(e));
    if (GiNaC::is_exactly_a<GiNaC::constant>(e)) {
      const GiNaC::ex value = e.evalf();
      if (GiNaC::is_exactly_a<GiNaC::numeric>(value)) return emit_numeric(GiNaC::ex_to<GiNaC::numeric>(value));
      fail(fmt::format("contains the constant '{}', which has no numeric value", to_text(e)));
    }
    if (GiNaC::is_exactly_a<GiNaC::add>(e)) return emit_add(e);
    if (GiNaC::is_exactly_a<GiNaC::mul>(e)) return emit_mul(e);
    if (GiNaC::is_exactly_a<GiNaC::power>(e)) return emit_power(e.op(0), e.op(1));
    if (GiNaC::is_a<GiNaC::function>(e)) return emit_function(e);
    fail(fmt::format("contains '{}' (a GiNaC {}), which is not a scalar expression the compiler handles",
                     to_text(e), GiNaC::ex_to<GiNaC::basic>(e).class_name()));
  }

  int emit_numeric(const GiNaC::numeric& x) {
    if (!x.is_real())
      fail(fmt::format("contains the complex number {}; every quantity must be real", to_text(x)));
    return constant(numeric_value(x));
  }

  int constant(double value) {
    const auto found = constants_.find(hash_double(value));
    if (found != constants_.end()) return found->second;
    const int r = program_.push_constant(value);
    constants_.emplace(hash_double(value), r);
    return r;
  }

  int emit_symbol(const GiNaC::symbol& x) {
    const auto found = variables_.find(x);
    if (found != variables_.end()) return found->second;
    const auto parameter = parameters_.find(x);
    if (parameter != parameters_.end()) {
      const int r = program_.push_parameter(parameter->second);
      variables_.emplace(x, r);
      return r;
    }
    const std::string name = x.get_name();
    for (int i = 0; i < spec_.symbols.coordinates(); ++i)
      if (x.is_equal(spec_.symbols.acceleration(i)))
        fail(fmt::format("contains the acceleration {}; the terms may depend on t, q and q' only", name));
    fail(fmt::format("contains the symbol '{}', which is neither t, a coordinate nor a velocity once the "
                     "parameter values are set: declare it as a parameter with a value",
                     name));
  }

  int emit_add(const GiNaC::ex& e) {
    double offset = 0.0;
    std::vector<std::pair<GiNaC::ex, double>> terms;
    for (std::size_t i = 0; i < e.nops(); ++i) {
      const GiNaC::ex term = e.op(i);
      if (GiNaC::is_exactly_a<GiNaC::numeric>(term)) {
        const GiNaC::numeric& x = GiNaC::ex_to<GiNaC::numeric>(term);
        if (!x.is_real()) emit_numeric(x);  // throws
        offset += numeric_value(x);
      } else {
        terms.push_back(split_coefficient(term));
      }
    }
    sort_canonically(terms, [](const auto& term) -> const GiNaC::ex& { return term.first; });
    // Start from a term with coefficient 1 when there is one, to save a negation or a scaling.
    const auto first = std::find_if(terms.begin(), terms.end(), [](const auto& term) { return term.second == 1.0; });
    if (first != terms.end()) std::rotate(terms.begin(), first, first + 1);

    // The first term with its coefficient folded into its last multiplication; each further term
    // c * h * f folded into one muladd, mulsub or mulk_muladd (h: the product of its other factors),
    // unless the whole product is needed elsewhere anyway.
    int acc;
    if (auto factors = fusable_factors(terms[0].first)) {
      acc = product(*factors, terms[0].second);
    } else {
      acc = scaled(emit(terms[0].first), terms[0].second);
    }
    for (std::size_t i = 1; i < terms.size(); ++i) {
      const auto& [rest, c] = terms[i];
      if (auto factors = fusable_factors(rest)) {
        const GiNaC::ex last = factors->back();
        factors->pop_back();
        const int h = factors->size() == 1 ? emit(factors->front()) : emit(GiNaC::mul(*factors));
        const int f = emit(last);
        if (c == 1.0)
          acc = program_.push(Op::muladd, h, f, acc);
        else if (c == -1.0)
          acc = program_.push(Op::mulsub, h, f, acc);
        else
          acc = program_.push(Op::mulk_muladd, h, f, acc, c);
      } else if (c == 1.0 || c == -1.0) {
        acc = program_.push(c == 1.0 ? Op::add : Op::sub, acc, emit(rest));
      } else {
        acc = program_.push(Op::mulk_add, emit(rest), acc, 0, c);
      }
    }
    if (offset != 0.0) acc = program_.push(Op::add_k, acc, 0, 0, offset);
    return acc;
  }

  // The factors of a product (or square) that is not computed yet and has no denominator, in
  // canonical order: a sum folds its last multiplication into the accumulation.
  std::optional<std::vector<GiNaC::ex>> fusable_factors(const GiNaC::ex& e) {
    if (memo_.count(e) > 0) return std::nullopt;
    if (GiNaC::is_exactly_a<GiNaC::power>(e) && e.op(1).is_equal(GiNaC::ex(2))) {
      // x^2 = x * x: the square folds into the sum too.
      return std::vector<GiNaC::ex>{e.op(0), e.op(0)};
    }
    if (!GiNaC::is_exactly_a<GiNaC::mul>(e)) return std::nullopt;
    std::vector<GiNaC::ex> factors;
    for (std::size_t i = 0; i < e.nops(); ++i) {
      const GiNaC::ex factor = e.op(i);
      if (GiNaC::is_exactly_a<GiNaC::numeric>(factor) || is_reciprocal(factor)) return std::nullopt;
      factors.push_back(factor);
    }
    sort_canonically(factors, [](const GiNaC::ex& x) -> const GiNaC::ex& { return x; });
    parameters_first(factors);
    return factors;
  }

  // The factors of parameters only first (in their order), so that their products come first and
  // the evaluator's parameter stage computes them once.
  void parameters_first(std::vector<GiNaC::ex>& factors) {
    std::stable_partition(factors.begin(), factors.end(), [this](const GiNaC::ex& x) { return parameters_only(x); });
  }

  int scaled(int r, double c) {
    if (c == 1.0) return r;
    if (c == -1.0) return program_.push(Op::neg, r);
    return program_.push(Op::mul_k, r, 0, 0, c);
  }

  // c * f1 * f2 * ... as ((f1 f2) ...) with the coefficient folded into the last multiplication
  // (k (a b), exact for k = -1 too).
  int product(std::vector<GiNaC::ex>& factors, double c = 1.0) {
    sort_canonically(factors, [](const GiNaC::ex& x) -> const GiNaC::ex& { return x; });
    parameters_first(factors);
    int acc = emit(factors[0]);
    for (std::size_t i = 1; i < factors.size(); ++i) {
      const int next = emit(factors[i]);
      if (i + 1 == factors.size() && c != 1.0) return program_.push(Op::mulk, acc, next, 0, c);
      acc = program_.push(Op::mul, acc, next);
    }
    return scaled(acc, c);
  }

  // Whether `e` depends on parameters and numbers only (not on t, q, q' or an unknown symbol).
  bool parameters_only(const GiNaC::ex& e) {
    if (GiNaC::is_a<GiNaC::symbol>(e)) return parameters_.count(e) > 0;
    if (e.nops() == 0) return true;
    const auto found = parameters_only_.find(e);
    if (found != parameters_only_.end()) return found->second;
    bool only = true;
    for (std::size_t i = 0; i < e.nops() && only; ++i) only = parameters_only(e.op(i));
    parameters_only_.emplace(e, only);
    return only;
  }

  int emit_mul(const GiNaC::ex& e) {
    {
      // k * s, k the factors of parameters only (the parameter stage computes it once) and s the
      // others, when the product has both.
      GiNaC::exvector k, rest;
      bool has_parameter = false;
      for (std::size_t i = 0; i < e.nops(); ++i) {
        const GiNaC::ex factor = e.op(i);
        const bool only = parameters_only(factor);
        has_parameter = has_parameter || (only && !GiNaC::is_exactly_a<GiNaC::numeric>(factor));
        (only ? k : rest).push_back(factor);
      }
      if (has_parameter && !rest.empty()) {
        const int stage = emit(GiNaC::mul(k));
        return program_.push(Op::mul, stage, emit(GiNaC::mul(rest)));
      }
    }
    double c = 1.0;
    std::vector<GiNaC::ex> numerator, denominator;
    for (std::size_t i = 0; i < e.nops(); ++i) {
      const GiNaC::ex factor = e.op(i);
      if (GiNaC::is_exactly_a<GiNaC::numeric>(factor)) {
        const GiNaC::numeric& x = GiNaC::ex_to<GiNaC::numeric>(factor);
        if (!x.is_real()) emit_numeric(x);  // throws
        c *= numeric_value(x);
      } else if (is_reciprocal(factor)) {
        denominator.push_back(GiNaC::pow(factor.op(0), -factor.op(1)));
      } else {
        numerator.push_back(factor);
      }
    }
    if (numerator.empty() && denominator.empty()) return constant(c);
    if (numerator.empty()) return program_.push(Op::div_k, product(denominator), 0, 0, c);
    if (denominator.empty()) return product(numerator, c);
    const int r = program_.push(Op::div, product(numerator), product(denominator));
    return scaled(r, c);
  }

  // base^n for an integer n != 0, from the register of base.
  int integer_power(int base, int n) {
    if (n < 0) return program_.push(Op::div_k, integer_power(base, -n), 0, 0, 1.0);
    if (n == 1) return base;
    if (n == 2) return program_.push(Op::square, base);
    if (n == 3) return program_.push(Op::cube, base);
    return program_.push(Op::powi, base, 0, 0, n);
  }

  int emit_power(const GiNaC::ex& base, const GiNaC::ex& exponent) {
    if (GiNaC::is_exactly_a<GiNaC::numeric>(exponent) && GiNaC::ex_to<GiNaC::numeric>(exponent).is_real()) {
      const double p = numeric_value(GiNaC::ex_to<GiNaC::numeric>(exponent));
      constexpr double kLargest = 1 << 20;
      if (p == std::trunc(p) && std::abs(p) <= kLargest) {
        const int n = static_cast<int>(p);
        // x^-n = 1 / x^n, with x^n shared with its other uses.
        if (n < 0) return program_.push(Op::div_k, emit(GiNaC::pow(base, -n)), 0, 0, 1.0);
        return integer_power(emit(base), n);
      }
      if (2.0 * p == std::trunc(2.0 * p) && std::abs(p) <= kLargest) {
        // x^(m/2) = sqrt(x)^m: exact for squares, and shared with sqrt(x).
        const GiNaC::ex root = GiNaC::pow(base, GiNaC::numeric(1, 2));
        int r;
        const auto found = memo_.find(root);
        if (found != memo_.end()) {
          r = found->second;
        } else {
          r = program_.push(Op::sqrt, emit(base));
          memo_.emplace(root, r);
        }
        return integer_power(r, static_cast<int>(2.0 * p));
      }
      return program_.push(Op::pow_k, emit(base), 0, 0, p);
    }
    const int b = emit(base);
    return program_.push(Op::pow, b, emit(exponent));
  }

  int emit_function(const GiNaC::ex& e) {
    const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
    static const std::map<std::string, Op> unary{
        {"sin", Op::sin},   {"cos", Op::cos},   {"tan", Op::tan},   {"exp", Op::exp},   {"log", Op::log},
        {"abs", Op::abs},   {"asin", Op::asin}, {"acos", Op::acos}, {"atan", Op::atan}, {"sinh", Op::sinh},
        {"cosh", Op::cosh}, {"tanh", Op::tanh}, {"sqrt", Op::sqrt}};
    const auto op = unary.find(name);
    if (op != unary.end() && e.nops() == 1) return program_.push(op->second, emit(e.op(0)));
    if (name == "atan2" && e.nops() == 2) {
      const int y = emit(e.op(0));
      return program_.push(Op::atan2, y, emit(e.op(1)));
    }
    // Every quantity is real, so the conjugate that GiNaC's derivative of abs() brings in
    // (d|x|/dx = (x + conjugate(x)) / (2 |x|)) is the identity.
    if ((name == "conjugate" || name == "real_part") && e.nops() == 1) return emit(e.op(0));
    if (name == "imag_part" && e.nops() == 1) return constant(0.0);
    fail(fmt::format("calls the function '{}', which the compiler does not support (supported: {})", name,
                     kSupportedFunctions));
  }

  // Sorts items by the canonical key of their expression (ties, if the hash ever collides, by
  // GiNaC's structural order).
  template <class T, class Key>
  void sort_canonically(std::vector<T>& items, Key key) {
    std::vector<std::pair<std::uint64_t, std::size_t>> order;
    order.reserve(items.size());
    for (std::size_t i = 0; i < items.size(); ++i) order.emplace_back(canonical_key(key(items[i])), i);
    std::stable_sort(order.begin(), order.end(), [&](const auto& x, const auto& y) {
      if (x.first != y.first) return x.first < y.first;
      return key(items[x.second]).compare(key(items[y.second])) < 0;
    });
    std::vector<T> sorted;
    sorted.reserve(items.size());
    for (const auto& [k, i] : order) sorted.push_back(items[i]);
    items = std::move(sorted);
  }

  // A structural hash that depends on names, values and shape only (GiNaC's own hashes depend on
  // symbol serial numbers and on addresses).
  std::uint64_t canonical_key(const GiNaC::ex& e) {
    const auto found = keys_.find(e);
    if (found != keys_.end()) return found->second;
    std::uint64_t h = 0;
    if (GiNaC::is_exactly_a<GiNaC::numeric>(e)) {
      const GiNaC::numeric& x = GiNaC::ex_to<GiNaC::numeric>(e);
      h = mix(mix(1, hash_double(GiNaC::real(x).to_double())), hash_double(GiNaC::imag(x).to_double()));
    } else if (GiNaC::is_a<GiNaC::symbol>(e)) {
      h = mix(2, hash_string(GiNaC::ex_to<GiNaC::symbol>(e).get_name()));
    } else if (GiNaC::is_exactly_a<GiNaC::add>(e) || GiNaC::is_exactly_a<GiNaC::mul>(e)) {
      std::vector<std::uint64_t> children;
      for (std::size_t i = 0; i < e.nops(); ++i) children.push_back(canonical_key(e.op(i)));
      std::sort(children.begin(), children.end());
      h = GiNaC::is_exactly_a<GiNaC::add>(e) ? 3 : 4;
      for (std::uint64_t child : children) h = mix(h, child);
    } else if (GiNaC::is_a<GiNaC::function>(e)) {
      h = mix(5, hash_string(GiNaC::ex_to<GiNaC::function>(e).get_name()));
      for (std::size_t i = 0; i < e.nops(); ++i) h = mix(h, canonical_key(e.op(i)));
    } else {
      h = mix(6, hash_string(GiNaC::ex_to<GiNaC::basic>(e).class_name()));
      for (std::size_t i = 0; i < e.nops(); ++i) h = mix(h, canonical_key(e.op(i)));
    }
    keys_.emplace(e, h);
    return h;
  }

  // Rewrites a program so that sin(x) and cos(x) of the same register become one sincos (one
  // call to the math library less when the compiler fuses them, and always one dispatch less).
  static Program fuse_sincos(const Program& in) {
    const std::vector<Instruction>& code = in.code();
    const int inputs = in.inputs();
    std::map<int, int> sin_of, cos_of;  // operand register -> instruction index
    for (std::size_t i = 0; i < code.size(); ++i) {
      if (code[i].op == Op::sin) sin_of.emplace(code[i].a, static_cast<int>(i));
      if (code[i].op == Op::cos) cos_of.emplace(code[i].a, static_cast<int>(i));
    }
    std::vector<int> partner(code.size(), -1);
    for (const auto& [operand, i] : sin_of) {
      const auto c = cos_of.find(operand);
      if (c == cos_of.end()) continue;
      partner[static_cast<std::size_t>(i)] = c->second;
      partner[static_cast<std::size_t>(c->second)] = i;
    }
    Program out(in.coordinates(), in.parameters());
    std::vector<int> map(static_cast<std::size_t>(in.registers()), -1);  // old register -> new
    for (int r = 0; r < inputs; ++r) map[static_cast<std::size_t>(r)] = r;
    const auto arg = [&](int reg) { return map[static_cast<std::size_t>(reg)]; };
    for (std::size_t i = 0; i < code.size(); ++i) {
      const Instruction& x = code[i];
      const std::size_t reg = static_cast<std::size_t>(inputs) + i;
      const int p = partner[i];
      if (p >= 0) {
        if (map[reg] >= 0) continue;  // written by the sincos of its partner
        const int r = out.push(Op::sincos, arg(x.a));
        const bool is_sin = x.op == Op::sin;
        map[reg] = is_sin ? r : r + 1;
        map[static_cast<std::size_t>(inputs + p)] = is_sin ? r + 1 : r;
        continue;
      }
      if (x.op == Op::nop) {
        map[reg] = map[reg - 1] + 1;
        continue;
      }
      if (x.op == Op::parameter) {
        map[reg] = out.push_parameter(x.a);
        continue;
      }
      const int operands = operand_count(x.op);
      map[reg] = out.push(x.op, operands >= 1 ? arg(x.a) : 0, operands >= 2 ? arg(x.b) : 0,
                          operands >= 3 ? arg(x.c) : 0, x.k);
    }
    for (const Output& o : in.output_list()) {
      if (o.reg < 0)
        out.add_constant_output(o.value);
      else
        out.add_output(arg(o.reg));
    }
    return out;
  }

  const Spec& spec_;
  std::map<GiNaC::ex, GiNaC::ex, GiNaC::ex_is_less> values_;  // symbol -> its value (none so far)
  std::map<GiNaC::ex, int, GiNaC::ex_is_less> parameters_;   // parameter symbol -> its index
  std::map<GiNaC::ex, bool, GiNaC::ex_is_less> parameters_only_;
  std::unordered_map<const GiNaC::basic*, std::pair<GiNaC::ex, GiNaC::ex>> with_values_memo_;
  Program program_;
  std::map<GiNaC::ex, int, GiNaC::ex_is_less> variables_;  // t, q, q' -> input register
  std::map<GiNaC::ex, int, GiNaC::ex_is_less> memo_;
  std::map<std::uint64_t, int> constants_;  // by the bits of the value
  std::map<GiNaC::ex, std::uint64_t, GiNaC::ex_is_less> keys_;
  std::string what_;
  GiNaC::ex original_;
};

void check_size(const Spec& spec, const char* what, const GiNaC::matrix& m, int rows, int cols) {
  if (static_cast<int>(m.rows()) != rows || static_cast<int>(m.cols()) != cols)
    throw ModelError(fmt::format("model '{}': the derivation's {} is {} x {}, expected {} x {}", spec.name, what,
                                 m.rows(), m.cols(), rows, cols));
}

// The value of an initial condition once the parameters are set.
double initial_value(const Spec& spec, const GiNaC::lst& values, const GiNaC::ex& e, const std::string& what) {
  GiNaC::ex value;
  try {
    value = e.subs(values, GiNaC::subs_options::no_pattern).evalf();
  } catch (const std::exception& error) {
    throw ModelError(fmt::format("model '{}': the initial value of {} = {} cannot be evaluated ({})", spec.name,
                                 what, to_text(e), error.what()));
  }
  if (!GiNaC::is_exactly_a<GiNaC::numeric>(value) || !GiNaC::ex_to<GiNaC::numeric>(value).is_real())
    throw ModelError(fmt::format("model '{}': the initial value of {} = {} is not a real number once the "
                                 "parameters are set (it is {}); initial values may use the parameters only",
                                 spec.name, what, to_text(e), to_text(value)));
  return GiNaC::ex_to<GiNaC::numeric>(value).to_double();
}

int coordinate_index(const Spec& spec, const std::string& name, const char* what) {
  const auto it = std::find(spec.coordinates.begin(), spec.coordinates.end(), name);
  if (it == spec.coordinates.end())
    throw ModelError(fmt::format("model '{}': the {} coordinate '{}' of the path is not a coordinate", spec.name,
                                 what, name));
  return static_cast<int>(it - spec.coordinates.begin());
}

// The entries of m that are not identically zero, in compressed columns.
SparsityPattern pattern_of(const GiNaC::matrix& m) {
  SparsityPattern p;
  p.rows = static_cast<int>(m.rows());
  p.cols = static_cast<int>(m.cols());
  p.outer.push_back(0);
  for (unsigned j = 0; j < m.cols(); ++j) {
    for (unsigned i = 0; i < m.rows(); ++i)
      if (!m(i, j).is_zero()) p.inner.push_back(static_cast<int>(i));
    p.outer.push_back(static_cast<int>(p.inner.size()));
  }
  return p;
}

bool compile_sparse(const TermsSparsity& sparsity, int n, int s, TermsLayout layout) {
  if (layout != TermsLayout::automatic) return layout == TermsLayout::sparse;
  const double entries = static_cast<double>(n) * static_cast<double>(n + s);
  return n >= kSparseFrom && sparsity.A.nonzeros() + sparsity.b.nonzeros() <= 0.25 * entries;
}

}  // namespace

Model compile_model(const Spec& spec, const Derivation& derivation, const CompileOptions& options) {
  const int n = spec.n(), s = spec.s();
  if (n == 0) throw ModelError(fmt::format("model '{}' has no coordinates", spec.name));
  if (s >= n)
    throw ModelError(fmt::format("model '{}' has {} constraints for {} coordinates; it needs fewer constraints "
                                 "than coordinates",
                                 spec.name, s, n));
  if (spec.symbols.coordinates() != n)
    throw ModelError(fmt::format("model '{}': {} coordinates, but {} in the symbol table", spec.name, n,
                                 spec.symbols.coordinates()));
  check_size(spec, "A", derivation.A, n, n);
  check_size(spec, "Q", derivation.Q, n, 1);
  check_size(spec, "G", derivation.G, n, 1);
  check_size(spec, "b", derivation.b, s, n);
  check_size(spec, "b0", derivation.b0, s, 1);
  if (derivation.D) check_size(spec, "D", *derivation.D, n - s, n);

  Model model;
  model.name = spec.name;
  model.description = spec.description;
  model.coordinates = spec.coordinates;
  for (const SpecConstraint& c : spec.constraints) model.constraints.push_back({c.name, c.level, c.text});
  for (const SpecParameter& p : spec.parameters) model.parameters.push_back({p.name, p.value, p.unit, p.expression});
  // The derived values by the evaluator the Model uses later (parameters.hpp), so that a model
  // compiled with a value and one set to it at run time compute with the same bits.
  update_parameters(model.parameters, spec.name);
  if (static_cast<int>(derivation.phi.size()) != model.position_constraints() ||
      static_cast<int>(derivation.f.size()) != model.velocity_constraints())
    throw ModelError(fmt::format("model '{}': the derivation has {} position and {} velocity residuals for {} "
                                 "position and {} position-or-velocity constraints",
                                 spec.name, derivation.phi.size(), derivation.f.size(),
                                 model.position_constraints(), model.velocity_constraints()));

  const auto q_name = [&](int i) { return spec.coordinates[static_cast<std::size_t>(i)]; };
  const auto c_name = [&](int i) { return spec.constraints[static_cast<std::size_t>(i)].name; };
  const GiNaC::lst values = spec.parameter_values();

  ModelPrograms programs;
  programs.parameters = static_cast<int>(spec.parameters.size());
  {
    TermsSparsity sparsity{pattern_of(derivation.A), pattern_of(derivation.b)};
    const bool sparse = compile_sparse(sparsity, n, s, options.layout);
    ProgramCompiler terms(spec);
    // Column by column: every entry when dense, the pattern's nonzeros when sparse. Entry names
    // are formatted only when compiled (a thousand-body chain has 18 million entries).
    const auto matrix_outputs = [&](const GiNaC::matrix& m, const SparsityPattern& pattern, const char* symbol,
                                    auto row_name) {
      for (int j = 0; j < static_cast<int>(m.cols()); ++j) {
        const auto output = [&](int i) {
          const GiNaC::ex& e = m(static_cast<unsigned>(i), static_cast<unsigned>(j));
          if (e.is_zero())
            terms.add_output(e, "");
          else
            terms.add_output(e, fmt::format("{}({}, {})", symbol, row_name(i), q_name(j)));
        };
        if (sparse) {
          for (int k = pattern.outer[static_cast<std::size_t>(j)]; k < pattern.outer[static_cast<std::size_t>(j) + 1];
               ++k)
            output(pattern.inner[static_cast<std::size_t>(k)]);
        } else {
          for (int i = 0; i < static_cast<int>(m.rows()); ++i) output(i);
        }
      }
    };
    matrix_outputs(derivation.A, sparsity.A, "A", q_name);
    for (int i = 0; i < n; ++i)
      terms.add_output(derivation.Q(static_cast<unsigned>(i), 0), fmt::format("Q({})", q_name(i)));
    for (int i = 0; i < n; ++i)
      terms.add_output(derivation.G(static_cast<unsigned>(i), 0), fmt::format("G({})", q_name(i)));
    matrix_outputs(derivation.b, sparsity.b, "b", c_name);
    for (int i = 0; i < s; ++i)
      terms.add_output(derivation.b0(static_cast<unsigned>(i), 0), fmt::format("b0({})", c_name(i)));
    programs.terms = terms.finish();
    if (sparse) programs.sparsity = std::move(sparsity);
  }
  if (derivation.D) {
    ProgramCompiler complement(spec);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n - s; ++i)
        complement.add_output((*derivation.D)(static_cast<unsigned>(i), static_cast<unsigned>(j)),
                              fmt::format("D({}, {})", i + 1, q_name(j)));
    programs.complement = complement.finish();
  }
  {
    // Residual i belongs to the i-th constraint of its level (constraint order).
    std::vector<int> position, velocity;
    for (int i = 0; i < s; ++i) {
      const ConstraintLevel level = spec.constraints[static_cast<std::size_t>(i)].level;
      if (level == ConstraintLevel::position) position.push_back(i);
      if (level != ConstraintLevel::acceleration) velocity.push_back(i);
    }
    ProgramCompiler phi(spec);
    for (std::size_t i = 0; i < derivation.phi.size(); ++i)
      phi.add_output(derivation.phi[i], fmt::format("phi({})", c_name(position[i])));
    programs.position_residual = phi.finish();
    if (programs.position_residual.reads_velocities())
      throw ModelError(fmt::format("model '{}': a position-level residual depends on the velocities", spec.name));
    ProgramCompiler f(spec);
    for (std::size_t i = 0; i < derivation.f.size(); ++i)
      f.add_output(derivation.f[i], fmt::format("f({})", c_name(velocity[i])));
    programs.velocity_residual = f.finish();
  }
  if (derivation.energy) {
    ProgramCompiler energy(spec);
    energy.add_output(*derivation.energy, "energy");
    programs.energy = energy.finish();
    // The energy balance (docs/derivations/energy-balance.md): h where it differs from E, and the
    // symbolic parts of the power where they are not zero (the power program runs at every
    // right-hand side of a run, so a conservative model has none).
    programs.energy_balance = true;
    if (derivation.energy_function) {
      ProgramCompiler h(spec);
      h.add_output(*derivation.energy_function, "energy function");
      programs.energy_function = h.finish();
    }
    if (!derivation.conservative) {
      ProgramCompiler power(spec);
      power.add_output(derivation.power_forces, "power of the forces");
      power.add_output(derivation.power_time, "power of the explicit time dependence");
      programs.power = power.finish();
    }
  }

  model.t0 = spec.t0;
  model.q0 = Vector::Zero(n);
  model.v0 = Vector::Zero(n);
  if (!spec.q0.empty() || !spec.v0.empty()) {
    if (static_cast<int>(spec.q0.size()) != n || static_cast<int>(spec.v0.size()) != n)
      throw ModelError(fmt::format("model '{}': {} initial coordinates and {} initial velocities for {} coordinates",
                                   spec.name, spec.q0.size(), spec.v0.size(), n));
    // Checked here, symbolically (an initial value may use the parameters only); its values come
    // from the initial-state program, which follows the parameters when they change.
    for (int i = 0; i < n; ++i) {
      initial_value(spec, values, spec.q0[static_cast<std::size_t>(i)], q_name(i));
      initial_value(spec, values, spec.v0[static_cast<std::size_t>(i)], q_name(i) + "'");
    }
    ProgramCompiler initial(spec);
    for (int i = 0; i < n; ++i) initial.add_output(spec.q0[static_cast<std::size_t>(i)], "initial " + q_name(i));
    for (int i = 0; i < n; ++i) initial.add_output(spec.v0[static_cast<std::size_t>(i)], "initial " + q_name(i) + "'");
    programs.initial_state = initial.finish();
  }
  if (!spec.solution.empty()) {
    // q(t), then its first and second derivatives: the exact velocities and accelerations. A
    // closed form that cannot be evaluated at these parameter values (v0/w with w = 0) must not
    // stop the model: that output is NaN, which check_solution refuses where the solution is used.
    ProgramCompiler solution(spec);
    const GiNaC::symbol& t = spec.symbols.time();
    for (int order = 0; order < 3; ++order)
      for (int i = 0; i < n; ++i) {
        try {
          solution.add_output(spec.solution[static_cast<std::size_t>(i)].diff(t, order),
                              fmt::format("solution {}{}", q_name(i), std::string(static_cast<std::size_t>(order), '\'')));
        } catch (const ModelError&) {
          solution.add_nan_output();
        }
      }
    programs.solution = solution.finish();
  }
  model.defaults = spec.defaults;
  if (spec.path)
    model.path = PlanarPath{coordinate_index(spec, spec.path->first, "x"), coordinate_index(spec, spec.path->second, "y")};
  std::vector<double> parameter_values;
  for (const Parameter& p : model.parameters) parameter_values.push_back(p.value);
  model.evaluator = std::make_shared<ProgramEvaluator>(n, s, std::move(programs), std::move(parameter_values));
  if (model.evaluator->has_initial_state()) {
    std::vector<double> scratch(model.evaluator->scratch_size());
    model.evaluator->initial_state(scratch.data(), model.q0.data(), model.v0.data());
  }
  check_model_shape(model);
  return model;
}

Model compile_model(const Spec& spec, const CompileOptions& options) {
  return compile_model(spec, derive(spec), options);
}

}  // namespace nhdyn::symbolic
