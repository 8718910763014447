// Compilation of GiNaC expressions into tapes, straight-line code on doubles (model/tape.hpp).
//
// Parameters stay symbols: each becomes a `parameter` instruction, which the evaluator binds to
// the Model's current values (so a parameter changes without recompiling). The constants (pi) are
// made numeric, and in a product the factors that depend on parameters only are gathered into one
// subexpression, which the evaluator computes once per parameter change (its parameter stage)
// instead of at every call; terms of a sum that differ only in such factors are merged into one,
// (c1 p1 + c2 p2) s, as a computer algebra system merges them once the parameters are numbers, so
// that a call costs what it cost when parameters were literals. Each expression is first translated into a canonical form of our own
// (below: sorted operands, sums of canonical sign, every distinct subexpression one node), which
// does not depend on GiNaC's internal term order or sign choices (they follow addresses, which
// change from process to process); the tape is emitted from that form, every subexpression
// once, so that a subexpression shared by several terms (sin(phi) in A, G, b, b0) is computed
// once, and the tape — its rounding, and the generated code printed from it — is the same in
// every process (docs/design.md, "Reproducibility").
#include "nhdyn/symbolic/compile.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <memory_resource>
#include <optional>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/model/tape.hpp"
#include "nhdyn/symbolic/contact_forces.hpp"
#include "nhdyn/symbolic/contact_modes.hpp"
#include "nhdyn/symbolic/events.hpp"
#include "nhdyn/symbolic/outputs.hpp"
#include "nhdyn/symbolic/detail/derivative.hpp"
#include "nhdyn/symbolic/detail/kind.hpp"
#include "nhdyn/symbolic/detail/pairs.hpp"
#include "nhdyn/symbolic/detail/plain_words.hpp"

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

// The canonical form the compiler emits from: a DAG of our own in which every node is unique
// (hash-consed), the operands of every sum and product are sorted by a structural key of names,
// values and shape, and every sum has the sign of its first term in that order positive. GiNaC's
// own form depends on the process: its hashes (and so its term order) derive from addresses, and
// it makes a sum that is a factor or a base "unit normal" with respect to a term it picks by that
// order, so one process holds (y' + a)^2 and another (-y' - a)^2, or -x (b - a) for x (a - b).
// Translated here, both become the same node times the same coefficient: the -1 of a sum moves
// into the product, power or function that uses it (through an integer power by its parity,
// through an odd function such as sin out of it, into an even one such as cos not at all), and
// negation is exact, so the tapes — and their rounding — are the same in every process.

// c * node: a node times a coefficient (kOne for a plain number c).
struct Scaled {
  double c = 1.0;
  int id = 0;
};

enum class Kind : std::uint8_t { one, symbol, add, mul, power, function };

struct Node {
  Kind kind = Kind::one;
  std::uint64_t key = 0;          // structural: names, values and shape only
  bool parameters_only = true;    // depends on parameters and numbers only (not t, q, q')
  int input = -1;                 // symbol: its input register (t, q, q'), -1 for a parameter
  int parameter = -1;             // symbol: the parameter's index, -1 for an input
  Op op = Op::constant;           // function: its instruction
  std::string name;               // symbol or function
  std::vector<Scaled> items;      // add: terms, sorted; mul: factors (c = 1), sorted; power: base
                                  // [, exponent]; function: arguments
  double offset = 0.0;            // add: its number term
  double exponent = 0.0;          // power with a number exponent (items has the base only)
};

constexpr int kOne = 0;

bool same_bits(double x, double y) { return hash_double(x) == hash_double(y); }

// The value of a unary function at a number (a function of a constant folds at compile time).
double apply(Op op, double x) {
  switch (op) {
    case Op::sin: return std::sin(x);
    case Op::cos: return std::cos(x);
    case Op::tan: return std::tan(x);
    case Op::exp: return std::exp(x);
    case Op::log: return std::log(x);
    case Op::abs: return std::abs(x);
    case Op::asin: return std::asin(x);
    case Op::acos: return std::acos(x);
    case Op::atan: return std::atan(x);
    case Op::sinh: return std::sinh(x);
    case Op::cosh: return std::cosh(x);
    case Op::tanh: return std::tanh(x);
    case Op::sqrt: return std::sqrt(x);
    default: return std::numeric_limits<double>::quiet_NaN();
  }
}

// f(-x) = -f(x), bit for bit in the C library (it computes on |x| and restores the sign).
bool is_odd(Op op) {
  return op == Op::sin || op == Op::tan || op == Op::asin || op == Op::atan || op == Op::sinh || op == Op::tanh;
}
// f(-x) = f(x).
bool is_even(Op op) { return op == Op::cos || op == Op::cosh || op == Op::abs; }

// The translation of expressions of one spec into one Tape.
class TapeCompiler {
 public:
  explicit TapeCompiler(const Spec& spec)
      : spec_(spec), tape_(spec.n(), static_cast<int>(spec.parameters.size())) {
    const SymbolTable& symbols = spec.symbols;
    inputs_.reserve(2 * static_cast<std::size_t>(symbols.coordinates()) + spec.parameters.size() + 1);
    for (std::size_t i = 0; i < spec.parameters.size(); ++i)
      add_input(spec.symbols.parameter(spec.parameters[i].name), -1, static_cast<int>(i));
    add_input(symbols.time(), Tape::time_register(), -1);
    for (int i = 0; i < symbols.coordinates(); ++i) {
      add_input(symbols.coordinate(i), tape_.coordinate_register(i), -1);
      add_input(symbols.velocity(i), tape_.velocity_register(i), -1);
    }
    nodes_.emplace_back();  // kOne
    nodes_.back().key = 1;
    same_key_.push_back(-1);
  }

  // Compiles `e` (parameters still symbolic) into the next output; `what` names it in errors.
  void add_output(const GiNaC::ex& e, const std::string& what) {
    if (e.is_zero()) {
      tape_.add_constant_output(0.0);
      return;
    }
    what_ = what;
    original_ = e;
    Scaled form;
    try {
      form = canonical(e);
    } catch (const Error&) {
      throw;
    } catch (const std::exception& error) {
      fail(fmt::format("cannot be evaluated: {}", plain_words(error.what())));
    }
    if (form.id == kOne)
      tape_.add_constant_output(form.c);
    else
      tape_.add_output(emit(form));
  }

  // An output that is NaN at every call (an expression that cannot be evaluated).
  void add_nan_output() { tape_.add_constant_output(std::numeric_limits<double>::quiet_NaN()); }

  // The finished tape, with each sin(x), cos(x) pair fused into one sincos.
  Tape finish() const { return fuse_sincos(tape_); }

 private:
  [[noreturn]] void fail(const std::string& message) const {
    throw ModelError(fmt::format("model '{}': {} = {} {}", spec_.name, what_, to_text(original_), message));
  }

  // ---- The canonical form -------------------------------------------------------------------

  const Node& node(int id) const { return nodes_[static_cast<std::size_t>(id)]; }

  // The node equal to `n` (made once): its key is computed here from its fields.
  int intern(Node n) {
    std::uint64_t h = mix(static_cast<std::uint64_t>(n.kind) + 11, hash_string(n.name));
    h = mix(h, static_cast<std::uint64_t>(n.input + 2));
    h = mix(h, static_cast<std::uint64_t>(n.parameter + 2));
    h = mix(h, static_cast<std::uint64_t>(n.op));
    h = mix(h, hash_double(n.offset));
    h = mix(h, hash_double(n.exponent));
    for (const Scaled& item : n.items) h = mix(mix(h, hash_double(item.c)), node(item.id).key);
    n.key = h;
    const auto [first, fresh] = by_key_.try_emplace(h, static_cast<int>(nodes_.size()));
    if (!fresh) {
      for (int id = first->second; id >= 0; id = same_key_[static_cast<std::size_t>(id)])
        if (shallow_equal(node(id), n)) return id;
    }
    nodes_.push_back(std::move(n));
    const int id = static_cast<int>(nodes_.size()) - 1;
    same_key_.push_back(-1);
    if (!fresh) {  // the chain of nodes with this key: the new one first
      same_key_.back() = first->second;
      first->second = id;
    }
    return id;
  }

  static bool shallow_equal(const Node& x, const Node& y) {
    if (x.kind != y.kind || x.input != y.input || x.parameter != y.parameter || x.op != y.op || x.name != y.name ||
        !same_bits(x.offset, y.offset) || !same_bits(x.exponent, y.exponent) || x.items.size() != y.items.size())
      return false;
    for (std::size_t i = 0; i < x.items.size(); ++i)
      if (x.items[i].id != y.items[i].id || !same_bits(x.items[i].c, y.items[i].c)) return false;
    return true;
  }

  // A total order on nodes that is the same in every process: by key, and (should two keys ever
  // collide) by structure.
  int compare(int a, int b) const {
    if (a == b) return 0;
    const Node& x = node(a);
    const Node& y = node(b);
    if (x.key != y.key) return x.key < y.key ? -1 : 1;
    if (x.kind != y.kind) return x.kind < y.kind ? -1 : 1;
    if (x.name != y.name) return x.name < y.name ? -1 : 1;
    if (x.input != y.input) return x.input < y.input ? -1 : 1;
    if (x.parameter != y.parameter) return x.parameter < y.parameter ? -1 : 1;
    if (x.op != y.op) return x.op < y.op ? -1 : 1;
    if (!same_bits(x.offset, y.offset)) return x.offset < y.offset ? -1 : 1;
    if (!same_bits(x.exponent, y.exponent)) return x.exponent < y.exponent ? -1 : 1;
    if (x.items.size() != y.items.size()) return x.items.size() < y.items.size() ? -1 : 1;
    for (std::size_t i = 0; i < x.items.size(); ++i) {
      if (!same_bits(x.items[i].c, y.items[i].c)) return x.items[i].c < y.items[i].c ? -1 : 1;
      const int c = compare(x.items[i].id, y.items[i].id);
      if (c != 0) return c;
    }
    return 0;
  }
  bool less(const Scaled& x, const Scaled& y) const {
    const int c = compare(x.id, y.id);
    if (c != 0) return c < 0;
    return !same_bits(x.c, y.c) && x.c < y.c;
  }
  void sort_canonically(std::vector<Scaled>& items) const {
    std::sort(items.begin(), items.end(), [this](const Scaled& x, const Scaled& y) { return less(x, y); });
  }

  // The sum of numbers in an order of their own (their values), not GiNaC's.
  static double sum(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    double s = 0.0;
    for (double x : values) s += x;
    return s;
  }
  static double product_of(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    double p = 1.0;
    for (double x : values) p *= x;
    return p;
  }

  // Like terms merged: the same node, coefficients added.
  std::vector<Scaled> merge_like(std::vector<Scaled> terms) const {
    sort_canonically(terms);
    std::vector<Scaled> merged;
    for (const Scaled& t : terms) {
      if (!merged.empty() && merged.back().id == t.id)
        merged.back().c += t.c;
      else
        merged.push_back(t);
    }
    merged.erase(std::remove_if(merged.begin(), merged.end(), [](const Scaled& t) { return t.c == 0.0; }),
                 merged.end());
    return merged;
  }

  // The terms that differ only in their factors of parameters, c1 p1 s + c2 p2 s, merged into one,
  // (c1 p1 + c2 p2) s, whose coefficient the parameter stage computes; the terms of parameters only
  // merged with the offset into one. The tape then does per call what it did when parameters were
  // numbers in the expression (and a computer algebra system merged such terms): a derived inertia
  // matrix sums each product of sines and cosines over the bodies, each with its own parameters.
  std::vector<Scaled> merge_parameter_terms(std::vector<Scaled> terms, double& offset) {
    struct Part {
      Scaled term;         // as it was
      Scaled coefficient;  // c p (kOne: no parameter)
    };
    std::vector<Scaled> constants;                 // terms of parameters only
    std::map<int, std::vector<Part>> by_state;     // state part -> its terms
    std::vector<int> order;                        // state parts in the order of the terms (canonical)
    bool merges = false;
    for (const Scaled& t : terms) {
      const Node& n = node(t.id);
      if (n.parameters_only) {
        constants.push_back(t);
        continue;
      }
      Scaled coefficient{t.c, kOne};
      int state = t.id;
      if (n.kind == Kind::mul) {
        std::vector<int> k, rest;
        for (const Scaled& f : n.items) (node(f.id).parameters_only ? k : rest).push_back(f.id);
        if (!k.empty()) {
          coefficient = make_mul(std::move(k), t.c);
          state = make_mul(std::move(rest), 1.0).id;
        }
      }
      std::vector<Part>& group = by_state[state];
      if (group.empty())
        order.push_back(state);
      else
        merges = true;
      group.push_back({t, coefficient});
    }
    const bool merge_constants = !constants.empty() && !order.empty() && (constants.size() > 1 || offset != 0.0);
    if (!merges && !merge_constants) return terms;
    std::vector<Scaled> out;
    if (merge_constants) {
      const Scaled c = make_add(std::move(constants), offset);
      offset = 0.0;
      if (c.id == kOne)
        offset = c.c;
      else
        out.push_back(c);
    } else {
      out.insert(out.end(), constants.begin(), constants.end());
    }
    for (int state : order) {
      const std::vector<Part>& group = by_state[state];
      if (group.size() == 1) {
        out.push_back(group[0].term);
        continue;
      }
      std::vector<Scaled> parametric;
      std::vector<double> numbers;
      for (const Part& part : group) {
        if (part.coefficient.id == kOne)
          numbers.push_back(part.coefficient.c);
        else
          parametric.push_back(part.coefficient);
      }
      const Scaled c = make_add(std::move(parametric), sum(std::move(numbers)));
      if (c.c == 0.0) continue;
      std::vector<int> factors = c.id == kOne ? std::vector<int>{} : factors_of(c.id);
      for (int f : factors_of(state)) factors.push_back(f);
      out.push_back(make_mul(std::move(factors), c.c));
    }
    return merge_like(std::move(out));
  }

  // The factors of a node: its items for a product, itself otherwise.
  std::vector<int> factors_of(int id) const {
    const Node& n = node(id);
    if (n.kind != Kind::mul) return {id};
    std::vector<int> out;
    for (const Scaled& f : n.items) out.push_back(f.id);
    return out;
  }

  // offset + sum of the terms, with like terms merged and the sign made canonical.
  Scaled make_add(std::vector<Scaled> terms, double offset) {
    std::vector<Scaled> merged = merge_parameter_terms(merge_like(std::move(terms)), offset);
    if (merged.empty()) return {offset, kOne};
    if (merged.size() == 1 && offset == 0.0) return merged[0];
    const double sign = merged[0].c < 0.0 ? -1.0 : 1.0;
    Node n;
    n.kind = Kind::add;
    for (Scaled& t : merged) {
      t.c *= sign;
      n.parameters_only = n.parameters_only && node(t.id).parameters_only;
    }
    n.items = std::move(merged);
    n.offset = sign * offset;
    return {sign, intern(std::move(n))};
  }

  // The factors of a product with the powers of one base merged, S^p S^q = S^(p + q): GiNaC merges
  // them only where the base is written alike, and it writes a sum's sign by its term order, which
  // changes from process to process, so one process holds S^(1/2) (-S) and another -S^(3/2). Here
  // the sign has gone to the coefficient `c`: a factor S (exponent 1) and a power (e S)^p with
  // e = +-1 merge into e (e S)^(p + 1), powers of the same signed base add their exponents. Factors
  // whose exponents add to 0 drop out.
  std::vector<int> merge_powers(std::vector<int> factors, double& c) {
    struct Power {
      Scaled base;
      double p;
    };
    std::vector<Power> powers;
    bool merged = false;
    for (int f : factors) {
      const Node& n = node(f);
      const bool number_power = n.kind == Kind::power && n.items.size() == 1;
      Power x = number_power ? Power{n.items[0], n.exponent} : Power{{1.0, f}, 1.0};
      bool done = false;
      for (Power& y : powers) {
        if (y.base.id != x.base.id) continue;
        if (same_bits(y.base.c, x.base.c)) {
          y.p += x.p;
        } else if (x.p == 1.0 && same_bits(x.base.c, 1.0) && std::abs(y.base.c) == 1.0) {
          c *= y.base.c;  // S (e S)^p = e (e S)^(p + 1)
          y.p += 1.0;
        } else if (y.p == 1.0 && same_bits(y.base.c, 1.0) && std::abs(x.base.c) == 1.0) {
          c *= x.base.c;
          y = {x.base, x.p + 1.0};
        } else {
          continue;
        }
        done = merged = true;
        break;
      }
      if (!done) powers.push_back(x);
    }
    if (!merged) return factors;
    std::vector<int> out;
    for (const Power& x : powers) {
      if (x.p == 0.0) continue;
      const Scaled f = make_power(x.base, x.p);
      c *= f.c;
      if (f.id != kOne) out.push_back(f.id);
    }
    return out;
  }

  // c * the product of the factors (nodes), sorted.
  Scaled make_mul(std::vector<int> factors, double c) {
    if (c == 0.0) return {0.0, kOne};
    std::sort(factors.begin(), factors.end(), [this](int x, int y) { return compare(x, y) < 0; });
    if (factors.empty()) return {c, kOne};
    if (factors.size() == 1) return {c, factors[0]};
    Node n;
    n.kind = Kind::mul;
    for (int f : factors) {
      n.items.push_back({1.0, f});
      n.parameters_only = n.parameters_only && node(f).parameters_only;
    }
    return {c, intern(std::move(n))};
  }

  // base^p for a number p.
  Scaled make_power(Scaled base, double p) {
    if (base.id == kOne) {
      const double value = p == 0.5 ? std::sqrt(base.c) : std::pow(base.c, p);
      if (std::isnan(value)) fail(fmt::format("cannot be evaluated ({}^{} is not a real number)", base.c, p));
      return {value, kOne};
    }
    if (p == 1.0) return base;
    double sign = 1.0;
    if (p == std::trunc(p) && base.c < 0.0) {
      // (-x)^n = (-1)^n x^n.
      base.c = -base.c;
      if (std::fmod(std::abs(p), 2.0) == 1.0) sign = -1.0;
    }
    Node n;
    n.kind = Kind::power;
    n.items = {base};
    n.exponent = p;
    n.parameters_only = node(base.id).parameters_only;
    return {sign, intern(std::move(n))};
  }

  // The canonical form of `e`: every distinct GiNaC node is translated once (derived terms share
  // large subexpressions, a bicycle's entries of A and G).
  Scaled canonical(const GiNaC::ex& e) {
    const GiNaC::basic* key = &GiNaC::ex_to<GiNaC::basic>(e);
    const auto found = translated_.find(key);
    if (found != translated_.end()) return found->second.second;
    const Scaled s = translate(e);
    // The node itself is kept in the memo so that its address cannot be reused by another. A node
    // held by `e` alone (the temporary c x that op() makes of a sum's term with a coefficient) can
    // never be met again: it is not kept.
    if (key->get_refcount() > 1) translated_.emplace(key, std::make_pair(e, s));
    return s;
  }

  double real_number(const GiNaC::numeric& x) const {
    if (!x.is_real()) fail(fmt::format("contains the complex number {}; every quantity must be real", to_text(x)));
    return numeric_value(x);
  }

  // The term c x of a sum (x its pair's rest, c != 1): GiNaC's product of x and c, whose factors
  // are x's (x a product, its number times c) or x itself.
  Scaled term(const GiNaC::ex& x, const GiNaC::numeric& c) {
    if (detail::kind_of(x) == detail::ExKind::mul)
      return product(detail::Pairs::of(x), GiNaC::ex_to<GiNaC::numeric>(detail::Pairs::number(x)).mul(c));
    return product(GiNaC::epvector{GiNaC::expair(x, 1)}, c);
  }

  // number * the product of the factors rest^exponent: each factor translated (a power for an
  // exponent other than 1), the numbers multiplied in their own order, powers of a base merged.
  Scaled product(const GiNaC::epvector& pairs, const GiNaC::numeric& number) {
    std::vector<int> factors;
    std::vector<double> numbers;
    for (const GiNaC::expair& p : pairs) {
      const Scaled f = p.coeff.is_equal(1) ? canonical(p.rest)
                                           : make_power(canonical(p.rest), real_number(GiNaC::ex_to<GiNaC::numeric>(p.coeff)));
      if (f.c != 1.0) numbers.push_back(f.c);
      if (f.id == kOne) continue;
      if (node(f.id).kind == Kind::mul) {
        for (const Scaled& g : node(f.id).items) factors.push_back(g.id);
      } else {
        factors.push_back(f.id);
      }
    }
    if (!number.is_equal(1)) {
      const double x = real_number(number);
      if (x != 1.0) numbers.push_back(x);
    }
    double c = product_of(std::move(numbers));
    factors = merge_powers(std::move(factors), c);
    return make_mul(std::move(factors), c);
  }

  // Sums and products are read from GiNaC's pairs (detail/pairs.hpp), not through op(), which
  // builds a product c x for each term with a coefficient and a power x^k for each factor with an
  // exponent: each is translated as translate() would translate that product or power.
  Scaled translate(const GiNaC::ex& e) {
    switch (detail::kind_of(e)) {
      case detail::ExKind::numeric: return {real_number(GiNaC::ex_to<GiNaC::numeric>(e)), kOne};
      case detail::ExKind::add: return sum_of(e);
      case detail::ExKind::mul:
        return product(detail::Pairs::of(e), GiNaC::ex_to<GiNaC::numeric>(detail::Pairs::number(e)));
      case detail::ExKind::symbol: return {1.0, symbol(GiNaC::ex_to<GiNaC::symbol>(e))};
      case detail::ExKind::constant: {
        const GiNaC::ex value = e.evalf();
        if (GiNaC::is_exactly_a<GiNaC::numeric>(value)) return {real_number(GiNaC::ex_to<GiNaC::numeric>(value)), kOne};
        fail(fmt::format("contains the constant '{}', which has no numeric value", to_text(e)));
      }
      case detail::ExKind::power: return power_of(e);
      case detail::ExKind::function: return function(e);
      case detail::ExKind::other: break;
    }
    // A subclass of symbol or function.
    if (GiNaC::is_a<GiNaC::symbol>(e)) return {1.0, symbol(GiNaC::ex_to<GiNaC::symbol>(e))};
    if (GiNaC::is_a<GiNaC::function>(e)) return function(e);
    fail(fmt::format("contains '{}' (a GiNaC {}), which is not a scalar expression the compiler handles",
                     to_text(e), GiNaC::ex_to<GiNaC::basic>(e).class_name()));
  }

  Scaled sum_of(const GiNaC::ex& e) {
    std::vector<Scaled> terms;
    std::vector<double> numbers;
    for (const GiNaC::expair& p : detail::Pairs::of(e)) {
      const Scaled t = p.coeff.is_equal(1) ? canonical(p.rest) : term(p.rest, GiNaC::ex_to<GiNaC::numeric>(p.coeff));
      if (t.id == kOne)
        numbers.push_back(t.c);
      else
        terms.push_back(t);
    }
    if (!detail::Pairs::number(e).is_zero()) numbers.push_back(translate(detail::Pairs::number(e)).c);
    return make_add(std::move(terms), sum(std::move(numbers)));
  }

  Scaled power_of(const GiNaC::ex& e) {
    const Scaled base = canonical(e.op(0));
    const GiNaC::ex exponent = e.op(1);
    if (GiNaC::is_exactly_a<GiNaC::numeric>(exponent))
      return make_power(base, real_number(GiNaC::ex_to<GiNaC::numeric>(exponent)));
    const Scaled p = canonical(exponent);
    if (p.id == kOne) return make_power(base, p.c);
    Node n;
    n.kind = Kind::power;
    n.items = {base, p};
    n.exponent = std::numeric_limits<double>::quiet_NaN();  // not a number exponent
    n.parameters_only = node(base.id).parameters_only && node(p.id).parameters_only;
    return {1.0, intern(std::move(n))};
  }

  int symbol(const GiNaC::symbol& x) {
    Node n;
    n.kind = Kind::symbol;
    n.name = x.get_name();
    const Input* found = nullptr;
    const auto [begin, end] = inputs_.equal_range(x.gethash());
    for (auto it = begin; it != end && found == nullptr; ++it)
      if (it->second.symbol.is_equal(x)) found = &it->second;
    if (found != nullptr && found->input >= 0) {
      n.input = found->input;
      n.parameters_only = false;
    } else if (found != nullptr) {
      n.parameter = found->parameter;
    } else {
      for (int i = 0; i < spec_.symbols.coordinates(); ++i)
        if (x.is_equal(spec_.symbols.acceleration(i)))
          fail(fmt::format("contains the acceleration {}; the terms may depend on t, q and q' only", n.name));
      fail(fmt::format("contains the symbol '{}', which is neither t, a coordinate nor a velocity once the "
                       "parameter values are set: declare it as a parameter with a value",
                       n.name));
    }
    return intern(std::move(n));
  }

  Scaled function(const GiNaC::ex& e) {
    const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
    static const std::map<std::string, Op> unary{
        {"sin", Op::sin},   {"cos", Op::cos},   {"tan", Op::tan},   {"exp", Op::exp},   {"log", Op::log},
        {"abs", Op::abs},   {"asin", Op::asin}, {"acos", Op::acos}, {"atan", Op::atan}, {"sinh", Op::sinh},
        {"cosh", Op::cosh}, {"tanh", Op::tanh}, {"sqrt", Op::sqrt}};
    // Every quantity is real, so the conjugate that GiNaC's derivative of abs() brings in
    // (d|x|/dx = (x + conjugate(x)) / (2 |x|)) is the identity.
    if ((name == "conjugate" || name == "real_part") && e.nops() == 1) return canonical(e.op(0));
    if (name == "imag_part" && e.nops() == 1) return {0.0, kOne};
    const auto op = unary.find(name);
    Node n;
    n.kind = Kind::function;
    n.name = name;
    double sign = 1.0;
    if (op != unary.end() && e.nops() == 1) {
      Scaled x = canonical(e.op(0));
      if (x.id == kOne) {
        const double value = apply(op->second, x.c);
        if (std::isnan(value)) fail(fmt::format("cannot be evaluated ({}({}) is not a real number)", name, x.c));
        return {value, kOne};
      }
      if (x.c < 0.0 && (is_odd(op->second) || is_even(op->second))) {
        if (is_odd(op->second)) sign = -1.0;
        x.c = -x.c;
      }
      n.op = op->second;
      n.items = {x};
    } else if (name == "atan2" && e.nops() == 2) {
      const Scaled y = canonical(e.op(0));
      const Scaled x = canonical(e.op(1));
      if (y.id == kOne && x.id == kOne) return {std::atan2(y.c, x.c), kOne};
      n.op = Op::atan2;
      n.items = {y, x};
    } else {
      fail(fmt::format("calls the function '{}', which the compiler does not support (supported: {})", name,
                       kSupportedFunctions));
    }
    for (const Scaled& x : n.items) n.parameters_only = n.parameters_only && node(x.id).parameters_only;
    return {sign, intern(std::move(n))};
  }

  // ---- Emission -----------------------------------------------------------------------------

  using MemoKey = std::pair<int, std::uint64_t>;  // (node, bits of the coefficient)

  bool emitted(int id) const { return memo_.count({id, hash_double(1.0)}) > 0; }

  int emit(const Scaled& s) {
    if (s.id == kOne) return constant(s.c);
    const MemoKey key{s.id, hash_double(s.c)};
    const auto found = memo_.find(key);
    if (found != memo_.end()) return found->second;
    int r;
    if (node(s.id).kind == Kind::mul)
      r = emit_mul(s.id, s.c);
    else if (s.c == 1.0)
      r = emit_node(s.id);
    else
      r = scaled(emit({1.0, s.id}), s.c);
    memo_.emplace(key, r);
    return r;
  }

  int emit_node(int id) {
    const Node& n = node(id);
    switch (n.kind) {
      case Kind::symbol: return n.input >= 0 ? n.input : tape_.push_parameter(n.parameter);
      case Kind::add: return emit_add(id);
      case Kind::power: return emit_power(id);
      case Kind::function: {
        if (n.op == Op::atan2) {
          const Scaled x = n.items[1];
          const int y = emit(n.items[0]);
          return tape_.push(Op::atan2, y, emit(x));
        }
        const Op op = n.op;
        return tape_.push(op, emit(n.items[0]));
      }
      default: break;
    }
    fail("could not be compiled (an unexpected node)");
  }

  int constant(double value) {
    const auto found = constants_.find(hash_double(value));
    if (found != constants_.end()) return found->second;
    const int r = tape_.push_constant(value);
    constants_.emplace(hash_double(value), r);
    return r;
  }

  int emit_add(int id) {
    std::vector<Scaled> terms = node(id).items;  // a copy: emission makes nodes
    const double offset = node(id).offset;
    // Start from a term with coefficient 1 when there is one, to save a negation or a scaling.
    const auto first = std::find_if(terms.begin(), terms.end(), [](const Scaled& t) { return t.c == 1.0; });
    if (first != terms.end()) std::rotate(terms.begin(), first, first + 1);

    // The first term with its coefficient folded into its last multiplication; each further term
    // c * h * f folded into one muladd, mulsub or mulk_muladd (h: the product of its other factors),
    // unless the whole product is needed elsewhere anyway.
    int acc;
    if (auto split = parameter_split(terms[0])) {
      acc = tape_.push(Op::mul, emit(split->first), emit(split->second));
    } else if (auto factors = fusable_factors(terms[0].id)) {
      acc = product(*factors, terms[0].c);
    } else {
      acc = scaled(emit({1.0, terms[0].id}), terms[0].c);
    }
    for (std::size_t i = 1; i < terms.size(); ++i) {
      const double c = terms[i].c;
      const int rest = terms[i].id;
      if (auto split = parameter_split(terms[i])) {
        // (c p) * s + acc: the evaluator makes it k * s + acc, with the last multiplication of s
        // inside (model/tape.hpp), one step as when the parameters were numbers.
        acc = tape_.push(Op::muladd, emit(split->first), emit(split->second), acc);
      } else if (auto factors = fusable_factors(rest)) {
        const Scaled last = factors->back();
        factors->pop_back();
        int h;
        if (factors->size() == 1) {
          h = emit(factors->front());
        } else {
          std::vector<int> ids;
          for (const Scaled& f : *factors) ids.push_back(f.id);
          h = emit(make_mul(std::move(ids), 1.0));
        }
        const int f = emit(last);
        if (c == 1.0)
          acc = tape_.push(Op::muladd, h, f, acc);
        else if (c == -1.0)
          acc = tape_.push(Op::mulsub, h, f, acc);
        else
          acc = tape_.push(Op::mulk_muladd, h, f, acc, c);
      } else if (c == 1.0 || c == -1.0) {
        acc = tape_.push(c == 1.0 ? Op::add : Op::sub, acc, emit({1.0, rest}));
      } else {
        acc = tape_.push(Op::mulk_add, emit({1.0, rest}), acc, 0, c);
      }
    }
    if (offset != 0.0) acc = tape_.push(Op::add_k, acc, 0, 0, offset);
    return acc;
  }

  // A term c * p * s of a sum, p the factors of parameters only and s the others (both present,
  // the product not computed yet), as (c p, s): c p is computed in the parameter stage.
  std::optional<std::pair<Scaled, Scaled>> parameter_split(const Scaled& term) {
    if (emitted(term.id) || node(term.id).kind != Kind::mul) return std::nullopt;
    std::vector<int> k, rest;
    for (const Scaled& f : node(term.id).items) (node(f.id).parameters_only ? k : rest).push_back(f.id);
    if (k.empty() || rest.empty()) return std::nullopt;
    return std::make_pair(make_mul(std::move(k), term.c), make_mul(std::move(rest), 1.0));
  }

  bool is_reciprocal(int id) const {
    const Node& n = node(id);
    return n.kind == Kind::power && n.items.size() == 1 && n.exponent < 0.0;
  }

  // The factors of a product (or square) that is not computed yet and has no denominator, in
  // canonical order: a sum folds its last multiplication into the accumulation.
  std::optional<std::vector<Scaled>> fusable_factors(int id) {
    if (emitted(id)) return std::nullopt;
    const Node& n = node(id);
    if (n.kind == Kind::power && n.items.size() == 1 && n.exponent == 2.0) {
      // x^2 = x * x: the square folds into the sum too.
      return std::vector<Scaled>{n.items[0], n.items[0]};
    }
    if (n.kind != Kind::mul) return std::nullopt;
    std::vector<Scaled> factors = n.items;
    for (const Scaled& f : factors)
      if (is_reciprocal(f.id)) return std::nullopt;
    parameters_first(factors);
    return factors;
  }

  // The factors of parameters only first (in their order), so that their products come first and
  // the evaluator's parameter stage computes them once.
  void parameters_first(std::vector<Scaled>& factors) const {
    std::stable_partition(factors.begin(), factors.end(),
                          [this](const Scaled& x) { return node(x.id).parameters_only; });
  }

  int scaled(int r, double c) {
    if (c == 1.0) return r;
    if (c == -1.0) return tape_.push(Op::neg, r);
    return tape_.push(Op::mul_k, r, 0, 0, c);
  }

  // c * f1 * f2 * ... as ((f1 f2) ...) with the coefficient folded into the last multiplication
  // (k (a b), exact for k = -1 too).
  int product(std::vector<Scaled>& factors, double c = 1.0) {
    sort_canonically(factors);
    parameters_first(factors);
    int acc = emit(factors[0]);
    for (std::size_t i = 1; i < factors.size(); ++i) {
      const int next = emit(factors[i]);
      if (i + 1 == factors.size() && c != 1.0) return tape_.push(Op::mulk, acc, next, 0, c);
      acc = tape_.push(Op::mul, acc, next);
    }
    return scaled(acc, c);
  }

  int emit_mul(int id, double c) {
    const std::vector<Scaled> items = node(id).items;  // a copy: emission makes nodes
    {
      // k * s, k the factors of parameters only with the coefficient (the parameter stage computes
      // it once) and s the others, when the product has both.
      std::vector<int> k, rest;
      for (const Scaled& f : items) (node(f.id).parameters_only ? k : rest).push_back(f.id);
      if (!k.empty() && !rest.empty()) {
        const int stage = emit(make_mul(std::move(k), c));
        return tape_.push(Op::mul, stage, emit(make_mul(std::move(rest), 1.0)));
      }
    }
    std::vector<Scaled> numerator, denominator;
    for (const Scaled& f : items) {
      if (is_reciprocal(f.id)) {
        const Node& p = node(f.id);
        denominator.push_back(make_power(p.items[0], -p.exponent));
      } else {
        numerator.push_back(f);
      }
    }
    if (numerator.empty()) return tape_.push(Op::div_k, product(denominator), 0, 0, c);
    if (denominator.empty()) return product(numerator, c);
    const int r = tape_.push(Op::div, product(numerator), product(denominator));
    return scaled(r, c);
  }

  // base^n for an integer n != 0, from the register of base.
  int integer_power(int base, int n) {
    if (n < 0) return tape_.push(Op::div_k, integer_power(base, -n), 0, 0, 1.0);
    if (n == 1) return base;
    if (n == 2) return tape_.push(Op::square, base);
    if (n == 3) return tape_.push(Op::cube, base);
    return tape_.push(Op::powi, base, 0, 0, n);
  }

  int emit_power(int id) {
    const Node& n = node(id);
    const Scaled base = n.items[0];
    if (n.items.size() == 2) {
      const Scaled exponent = n.items[1];
      const int b = emit(base);
      return tape_.push(Op::pow, b, emit(exponent));
    }
    const double p = n.exponent;
    constexpr double kLargest = 1 << 20;
    if (p == std::trunc(p) && std::abs(p) <= kLargest) {
      const int k = static_cast<int>(p);
      // x^-n = 1 / x^n, with x^n shared with its other uses.
      if (k < 0) return tape_.push(Op::div_k, emit(make_power(base, -k)), 0, 0, 1.0);
      return integer_power(emit(base), k);
    }
    if (2.0 * p == std::trunc(2.0 * p) && std::abs(p) <= kLargest) {
      // x^(m/2) = sqrt(x)^m: exact for squares, and shared with sqrt(x).
      const Scaled root = make_power(base, 0.5);
      int r;
      const auto found = memo_.find({root.id, hash_double(1.0)});
      if (found != memo_.end()) {
        r = found->second;
      } else {
        r = tape_.push(Op::sqrt, emit(base));
        memo_.emplace(MemoKey{root.id, hash_double(1.0)}, r);
      }
      return integer_power(r, static_cast<int>(2.0 * p));
    }
    return tape_.push(Op::pow_k, emit(base), 0, 0, p);
  }

  // Rewrites a tape so that sin(x) and cos(x) of the same register become one sincos (one
  // call to the math library less when the compiler fuses them, and always one dispatch less).
  static Tape fuse_sincos(const Tape& in) {
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
    Tape out(in.coordinates(), in.parameters());
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
  // The memory of the tables below, given back at once when the compiler ends: a large model's
  // tables hold 10^5 entries each, allocated one by one and never erased.
  std::pmr::monotonic_buffer_resource arena_;
  // t, q, q' -> input register, parameter symbol -> its index; found by the symbol's GiNaC hash
  // (from its serial number, the same in every copy), then by equality.
  struct Input {
    GiNaC::ex symbol;
    int input = -1;
    int parameter = -1;
  };
  std::unordered_multimap<unsigned, Input> inputs_;
  void add_input(const GiNaC::symbol& x, int input, int parameter) {
    inputs_.emplace(x.gethash(), Input{x, input, parameter});
  }
  std::pmr::unordered_map<const GiNaC::basic*, std::pair<GiNaC::ex, Scaled>> translated_{&arena_};
  std::deque<Node> nodes_;  // a deque: references stay valid while nodes are added
  std::pmr::unordered_map<std::uint64_t, int> by_key_{&arena_};  // key -> the last node made with it
  std::vector<int> same_key_;                       // per node: the one made before it with its key, or -1
  Tape tape_;
  struct MemoHash {
    std::size_t operator()(const MemoKey& k) const { return mix(static_cast<std::uint64_t>(k.first), k.second); }
  };
  std::pmr::unordered_map<MemoKey, int, MemoHash> memo_{&arena_};
  std::pmr::unordered_map<std::uint64_t, int> constants_{&arena_};  // by the bits of the value
  std::string what_;
  GiNaC::ex original_;
};

template <class Matrix>
void check_size(const Spec& spec, const char* what, const Matrix& m, int rows, int cols) {
  if (static_cast<int>(m.rows()) != rows || static_cast<int>(m.cols()) != cols)
    throw ModelError(fmt::format("model '{}': the derivation's {} is {} x {}, expected {} x {}", spec.name, what,
                                 m.rows(), m.cols(), rows, cols));
}

// An initial condition must be a real number once the parameters are set.
void require_initial_value(const Spec& spec, const GiNaC::lst& values, const GiNaC::ex& e, const std::string& what) {
  if (GiNaC::is_exactly_a<GiNaC::numeric>(e) && GiNaC::ex_to<GiNaC::numeric>(e).is_real()) return;  // a number
  GiNaC::ex value;
  try {
    value = e.subs(values, GiNaC::subs_options::no_pattern).evalf();
  } catch (const std::exception& error) {
    throw ModelError(fmt::format("model '{}': the initial value of {} = {} cannot be evaluated: {}", spec.name,
                                 what, to_text(e), plain_words(error.what())));
  }
  if (!GiNaC::is_exactly_a<GiNaC::numeric>(value) || !GiNaC::ex_to<GiNaC::numeric>(value).is_real())
    throw ModelError(fmt::format("model '{}': the initial value of {} = {} is not a real number once the "
                                 "parameters are set (it is {}); initial values may use the parameters only",
                                 spec.name, what, to_text(e), to_text(value)));
}

int coordinate_index(const Spec& spec, const std::string& name, const char* what) {
  const auto it = std::find(spec.coordinates.begin(), spec.coordinates.end(), name);
  if (it == spec.coordinates.end())
    throw ModelError(fmt::format("model '{}': the {} coordinate '{}' of the path is not a coordinate", spec.name,
                                 what, name));
  return static_cast<int>(it - spec.coordinates.begin());
}

// The entries of m that are not identically zero, in compressed columns.
SparsityPattern pattern_of(const ExMatrix& m) {
  SparsityPattern p;
  p.rows = static_cast<int>(m.rows());
  p.cols = static_cast<int>(m.cols());
  p.outer.push_back(0);
  for (unsigned j = 0; j < m.cols(); ++j) {
    for (const auto& [i, e] : m.column(j))
      if (!e.is_zero()) p.inner.push_back(static_cast<int>(i));
    p.outer.push_back(static_cast<int>(p.inner.size()));
  }
  return p;
}

bool compile_sparse(const TermsSparsity& sparsity, int n, int s, TermsLayout layout) {
  if (layout != TermsLayout::automatic) return layout == TermsLayout::sparse;
  const double entries = static_cast<double>(n) * static_cast<double>(n + s);
  return n >= kSparseFrom && sparsity.A.nonzeros() + sparsity.b.nonzeros() <= 0.25 * entries;
}

// The tapes of program motion (docs/derivations/program-motion.md): b_p, b_p0 and B in one
// tape (sharing subexpressions), and the programs' residuals in two more, like the constraints'.
void compile_program_constraints(const Spec& spec, const Derivation& derivation, ModelTapes& tapes,
                                 Model& model) {
  const int n = spec.n(), m = spec.m();
  if (m == 0) return;
  check_size(spec, "b_p", derivation.b_p, m, n);
  check_size(spec, "b_p0", derivation.b_p0, m, 1);
  check_size(spec, "B", derivation.B, n, m);
  std::vector<int> position, velocity;  // residual i belongs to the i-th program of its level
  for (int j = 0; j < m; ++j) {
    const SpecProgram& p = spec.programs[static_cast<std::size_t>(j)];
    model.program_constraints.push_back({p.constraint.name, p.constraint.level, p.constraint.text, p.actuator_text});
    if (p.constraint.level == ConstraintLevel::position) position.push_back(j);
    if (p.constraint.level != ConstraintLevel::acceleration) velocity.push_back(j);
  }
  if (derivation.phi_p.size() != position.size() || derivation.f_p.size() != velocity.size())
    throw ModelError(fmt::format("model '{}': the derivation has {} position and {} velocity program residuals for "
                                 "{} position and {} position-or-velocity programs",
                                 spec.name, derivation.phi_p.size(), derivation.f_p.size(), position.size(),
                                 velocity.size()));
  const auto q_name = [&](int i) { return spec.coordinates[static_cast<std::size_t>(i)]; };
  const auto p_name = [&](int j) { return spec.programs[static_cast<std::size_t>(j)].constraint.name; };
  TapeCompiler terms(spec);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < m; ++i)
      terms.add_output(derivation.b_p(static_cast<unsigned>(i), static_cast<unsigned>(j)),
                       fmt::format("b_p({}, {})", p_name(i), q_name(j)));
  for (int i = 0; i < m; ++i)
    terms.add_output(derivation.b_p0(static_cast<unsigned>(i), 0), fmt::format("b_p0({})", p_name(i)));
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i)
      terms.add_output(derivation.B(static_cast<unsigned>(i), static_cast<unsigned>(j)),
                       fmt::format("B({}, {})", q_name(i), p_name(j)));
  tapes.program_constraints = m;
  tapes.program_constraint_terms = terms.finish();
  TapeCompiler phi(spec);
  for (std::size_t i = 0; i < position.size(); ++i)
    phi.add_output(derivation.phi_p[i], fmt::format("phi({})", p_name(position[i])));
  tapes.program_constraint_position_residual = phi.finish();
  if (tapes.program_constraint_position_residual->reads_velocities())
    throw ModelError(fmt::format("model '{}': a program's position-level residual depends on the velocities",
                                 spec.name));
  TapeCompiler f(spec);
  for (std::size_t i = 0; i < velocity.size(); ++i)
    f.add_output(derivation.f_p[i], fmt::format("f({})", p_name(velocity[i])));
  tapes.program_constraint_velocity_residual = f.finish();
}

// The sizes of what the derivation gives, against the Spec's n coordinates and s constraints.
void check_derivation(const Spec& spec, const Derivation& derivation) {
  const int n = spec.n(), s = spec.s();
  if (n == 0) throw ModelError(fmt::format("model '{}' has no coordinates", spec.name));
  if (constraints_always_held(spec) >= n)
    throw ModelError(fmt::format("model '{}' has {} constraints for {} coordinates, {} of them held whatever the "
                                 "contacts' modes; fewer than n must hold at any time",
                                 spec.name, s, n, constraints_always_held(spec)));
  if (spec.symbols.coordinates() != n)
    throw ModelError(fmt::format("model '{}': {} coordinates, but {} in the symbol table", spec.name, n,
                                 spec.symbols.coordinates()));
  check_size(spec, "A", derivation.A, n, n);
  check_size(spec, "Q", derivation.Q, n, 1);
  check_size(spec, "G", derivation.G, n, 1);
  check_size(spec, "b", derivation.b, s, n);
  check_size(spec, "b0", derivation.b0, s, 1);
  if (derivation.D) check_size(spec, "D", *derivation.D, n - s, n);
}

// The names, constraints and parameters the Model carries as text and values.
void describe_model(const Spec& spec, const Derivation& derivation, Model& model) {
  model.name = spec.name;
  model.description = spec.description;
  model.coordinates = spec.coordinates;
  for (const SpecConstraint& c : spec.constraints) model.constraints.push_back({c.name, c.level, c.text, c.where.describe()});
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
}

// A, Q, G, b and b0 in one tape (sharing subexpressions), dense or by A's and b's patterns.
void compile_terms(const Spec& spec, const Derivation& derivation, TermsLayout layout, ModelTapes& tapes) {
  const int n = spec.n(), s = spec.s();
  const auto q_name = [&](int i) { return spec.coordinates[static_cast<std::size_t>(i)]; };
  const auto c_name = [&](int i) { return spec.constraints[static_cast<std::size_t>(i)].name; };
  TermsSparsity sparsity{pattern_of(derivation.A), pattern_of(derivation.b)};
  const bool sparse = compile_sparse(sparsity, n, s, layout);
  TapeCompiler terms(spec);
  // Column by column: every entry when dense, the pattern's nonzeros when sparse. Entry names
  // are formatted only when compiled (a thousand-body chain has 18 million entries).
  const auto matrix_outputs = [&](const ExMatrix& m, const SparsityPattern& pattern, const char* symbol,
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
  tapes.terms = terms.finish();
  if (sparse) tapes.sparsity = std::move(sparsity);
}

// The user's complement D, when the derivation has one.
void compile_complement(const Spec& spec, const Derivation& derivation, ModelTapes& tapes) {
  if (!derivation.D) return;
  const int n = spec.n(), s = spec.s();
  TapeCompiler complement(spec);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n - s; ++i)
      complement.add_output((*derivation.D)(static_cast<unsigned>(i), static_cast<unsigned>(j)),
                            fmt::format("D({}, {})", i + 1, spec.coordinates[static_cast<std::size_t>(j)]));
  tapes.complement = complement.finish();
}

// The constraints' residuals: phi of the position-level ones, f of those at the position or
// velocity level (residual i belongs to the i-th constraint of its level, in constraint order).
void compile_residuals(const Spec& spec, const Derivation& derivation, ModelTapes& tapes) {
  const auto c_name = [&](int i) { return spec.constraints[static_cast<std::size_t>(i)].name; };
  std::vector<int> position, velocity;
  for (int i = 0; i < spec.s(); ++i) {
    const ConstraintLevel level = spec.constraints[static_cast<std::size_t>(i)].level;
    if (level == ConstraintLevel::position) position.push_back(i);
    if (level != ConstraintLevel::acceleration) velocity.push_back(i);
  }
  TapeCompiler phi(spec);
  for (std::size_t i = 0; i < derivation.phi.size(); ++i)
    phi.add_output(derivation.phi[i], fmt::format("phi({})", c_name(position[i])));
  tapes.position_residual = phi.finish();
  if (tapes.position_residual.reads_velocities())
    throw ModelError(fmt::format("model '{}': a position-level residual depends on the velocities", spec.name));
  TapeCompiler f(spec);
  for (std::size_t i = 0; i < derivation.f.size(); ++i)
    f.add_output(derivation.f[i], fmt::format("f({})", c_name(velocity[i])));
  tapes.velocity_residual = f.finish();
}

// The energy and its balance (docs/derivations/energy-balance.md): h where it differs from E, and
// the symbolic parts of the power where they are not zero (the power tape runs at every
// right-hand side of a run, so a conservative model has none).
void compile_energy(const Spec& spec, const Derivation& derivation, ModelTapes& tapes) {
  if (!derivation.energy) return;
  TapeCompiler energy(spec);
  energy.add_output(*derivation.energy, "energy");
  tapes.energy = energy.finish();
  tapes.energy_balance = true;
  if (derivation.energy_function) {
    TapeCompiler h(spec);
    h.add_output(*derivation.energy_function, "energy function");
    tapes.energy_function = h.finish();
  }
  if (!derivation.conservative) {
    TapeCompiler power(spec);
    power.add_output(derivation.power_forces, "power of the forces");
    power.add_output(derivation.power_time, "power of the explicit time dependence");
    tapes.power = power.finish();
  }
}

// The initial state's tape, when the Spec gives one (else q0 = v0 = 0).
void compile_initial_state(const Spec& spec, ModelTapes& tapes) {
  const int n = spec.n();
  if (spec.q0.empty() && spec.v0.empty()) return;
  if (static_cast<int>(spec.q0.size()) != n || static_cast<int>(spec.v0.size()) != n)
    throw ModelError(fmt::format("model '{}': {} initial coordinates and {} initial velocities for {} coordinates",
                                 spec.name, spec.q0.size(), spec.v0.size(), n));
  const auto q_name = [&](int i) { return spec.coordinates[static_cast<std::size_t>(i)]; };
  // Checked here, symbolically (an initial value may use the parameters only); its values come
  // from the initial-state tape, which follows the parameters when they change.
  const GiNaC::lst values = spec.parameter_values();
  for (int i = 0; i < n; ++i) {
    require_initial_value(spec, values, spec.q0[static_cast<std::size_t>(i)], q_name(i));
    require_initial_value(spec, values, spec.v0[static_cast<std::size_t>(i)], q_name(i) + "'");
  }
  TapeCompiler initial(spec);
  for (int i = 0; i < n; ++i) initial.add_output(spec.q0[static_cast<std::size_t>(i)], "initial " + q_name(i));
  for (int i = 0; i < n; ++i) initial.add_output(spec.v0[static_cast<std::size_t>(i)], "initial " + q_name(i) + "'");
  tapes.initial_state = initial.finish();
}

// A closed-form solution's q(t), then its first and second derivatives: the exact velocities and
// accelerations. A closed form that cannot be evaluated at these parameter values (v0/w with w =
// 0) must not stop the model: that output is NaN, which check_solution refuses where the solution
// is used.
void compile_solution(const Spec& spec, ModelTapes& tapes) {
  if (spec.solution.empty()) return;
  TapeCompiler solution(spec);
  const GiNaC::symbol& t = spec.symbols.time();
  for (int order = 0; order < 3; ++order)
    for (int i = 0; i < spec.n(); ++i) {
      try {
        solution.add_output(spec.solution[static_cast<std::size_t>(i)].diff(t, order),
                            fmt::format("solution {}{}", spec.coordinates[static_cast<std::size_t>(i)],
                                        std::string(static_cast<std::size_t>(order), '\'')));
      } catch (const ModelError&) {
        solution.add_nan_output();
      }
    }
  tapes.solution = solution.finish();
}

// The contact coordinates nhdyn added (with the constraints that fix their start) and the contacts'
// watched measures (a disk or torus lying flat).
void compile_contact_coordinates(const Spec& spec, Model& model) {
  for (const SpecContactCoordinates& added : spec.contact_coordinates) {
    ContactCoordinates c{added.contact, added.where.describe(), added.coordinates, {}};
    for (const std::string& name : added.constraints)
      for (int i = 0; i < spec.s(); ++i)
        if (spec.constraints[static_cast<std::size_t>(i)].name == name) c.constraints.push_back(i);
    model.contact_coordinates.push_back(std::move(c));
  }
  for (const SpecContactWatch& w : spec.contact_watches)
    model.contact_watches.push_back({w.contact, w.where.describe(),
                                     compile_expression(spec, w.measure, fmt::format("{} '{}'", w.entry, w.contact)),
                                     w.threshold, w.reason, w.quantity, w.every_step, w.touching_only,
                                     w.free_only, w.entry});
  for (const SpecPositive& v : spec.positive_values)
    model.positive_values.push_back(
        {v.where.describe(), v.what, v.text, compile_expression(spec, v.value, v.what), v.group});
}

}  // namespace

Model compile_model(const Spec& spec, const Derivation& derivation, const CompileOptions& options) {
  check_derivation(spec, derivation);
  // The contact forces differentiate the same kinematics again and again (detail/derivative.hpp).
  const detail::DerivativeMemo memo;
  const int n = spec.n(), s = spec.s();
  Model model;
  describe_model(spec, derivation, model);

  ModelTapes tapes;
  tapes.parameters = static_cast<int>(spec.parameters.size());
  compile_terms(spec, derivation, options.layout, tapes);
  compile_complement(spec, derivation, tapes);
  compile_residuals(spec, derivation, tapes);
  compile_energy(spec, derivation, tapes);
  compile_initial_state(spec, tapes);
  compile_solution(spec, tapes);
  compile_program_constraints(spec, derivation, tapes, model);

  model.t0 = spec.t0;
  model.q0 = Vector::Zero(n);
  model.v0 = Vector::Zero(n);
  model.q0_written = spec.q0_written;
  model.v0_written = spec.v0_written;
  compile_contact_coordinates(spec, model);
  model.defaults = spec.defaults;
  if (spec.path)
    model.path = PlanarPath{coordinate_index(spec, spec.path->first, "x"), coordinate_index(spec, spec.path->second, "y")};
  std::vector<double> parameter_values;
  for (const Parameter& p : model.parameters) parameter_values.push_back(p.value);
  model.evaluator = std::make_shared<TapeEvaluator>(n, s, std::move(tapes), std::move(parameter_values));
  if (model.evaluator->has_initial_state()) {
    std::vector<double> scratch(model.evaluator->scratch_size());
    model.evaluator->initial_state(scratch.data(), model.q0.data(), model.v0.data());
  }
  compile_outputs(spec, model);
  // Before the events: an event that reads a contact force needs to know what the model determines.
  compile_contact_forces(spec, model);
  compile_contact_modes(spec, model);
  compile_events(spec, model);
  check_model_shape(model);
  check_positive_values(model, model.parameters);  // after a --set (the load judged the file's values)
  return model;
}

Tape compile_expression(const Spec& spec, const GiNaC::ex& expression, const std::string& what) {
  TapeCompiler compiler(spec);
  compiler.add_output(expression, what);
  return compiler.finish();
}

Tape compile_expressions(const Spec& spec, const std::vector<GiNaC::ex>& expressions,
                            const std::vector<std::string>& what) {
  TapeCompiler compiler(spec);
  for (std::size_t i = 0; i < expressions.size(); ++i) compiler.add_output(expressions[i], what.at(i));
  return compiler.finish();
}

Model compile_model(const Spec& spec, const CompileOptions& options) {
  return compile_model(spec, derive(spec), options);
}

}  // namespace nhdyn::symbolic
