#include "nhdyn/symbolic/spec_builder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <limits>
#include <map>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/symbolic/contact_forces.hpp"
#include "nhdyn/symbolic/contact_modes.hpp"
#include "nhdyn/symbolic/detail/occurrence.hpp"
#include "nhdyn/core/detail/characters.hpp"
#include "nhdyn/symbolic/detail/plain_words.hpp"
#include "nhdyn/core/detail/suggest.hpp"

namespace nhdyn::symbolic {
namespace {

// The functions an expression may call (spec_builder.hpp), with their number of arguments.
const std::vector<std::pair<std::string, int>>& functions() {
  static const std::vector<std::pair<std::string, int>> table = {
      {"sin", 1},  {"cos", 1},  {"tan", 1},  {"exp", 1},  {"log", 1},   {"sqrt", 1}, {"abs", 1},
      {"asin", 1}, {"acos", 1}, {"atan", 1}, {"atan2", 2}, {"sinh", 1}, {"cosh", 1}, {"tanh", 1}};
  return table;
}

int function_arity(const std::string& name) {
  for (const auto& [function, arity] : functions())
    if (function == name) return arity;
  return -1;
}

std::vector<std::string> function_names() {
  std::vector<std::string> names;
  for (const auto& entry : functions()) names.push_back(entry.first);
  return names;
}

std::string compose(const SourceLocation& where, const std::string& context, const std::string& problem) {
  std::string out;
  const std::string location = where.describe();
  if (!location.empty()) out += location + ": ";
  if (!context.empty()) out += context + ": ";
  return out + problem;
}

[[noreturn]] void fail(const SourceLocation& where, const std::string& context, const std::string& problem) {
  throw_model_error(where, context, problem);
}

// GiNaC identifiers cannot contain a prime, and a user's name may collide with GiNaC's own
// literals (I, Pi, Euler, Catalan): the parser sees every symbol under an internal name.
std::string internal_name(const std::string& name) {
  std::string base = name;
  std::string suffix;
  if (base.size() > 2 && base.compare(base.size() - 2, 2, "''") == 0) {
    base.resize(base.size() - 2);
    suffix = "__ddot";
  } else if (base.size() > 1 && base.back() == '\'') {
    base.pop_back();
    suffix = "__dot";
  }
  return "n__" + base + suffix;
}

bool identifier_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0 || c == '_'; }
bool identifier_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; }

// A refused name as the message shows it: its control characters escaped (\n, \t, \x1b), so
// that a name with a line break does not break the message's line.
std::string shown_name(const std::string& name) {
  std::string out;
  for (const char c : name) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '\n') out += "\\n";
    else if (c == '\t') out += "\\t";
    else if (byte < 0x20 || byte == 0x7f) out += fmt::format("\\x{:02x}", byte);
    else out += c;
  }
  return out;
}
bool digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }

enum class SymbolKind { time, constant, coordinate, velocity, acceleration, parameter };

// One occurrence of a symbol in the user's text.
struct Occurrence {
  SymbolKind kind;
  std::string name;  // as written, e.g. "x'"
  GiNaC::ex symbol;
  std::size_t position;  // byte offset in the text
};

struct Parsed {
  GiNaC::ex value;
  std::vector<Occurrence> symbols;  // in the order they appear
  SymbolSet present;                // the symbols `value` still contains (x' - x' has none)
  bool contains(const Occurrence& o) const { return present.count(o.symbol) > 0; }
};

// Where a piece of text sits, to turn byte offsets into file positions.
struct Site {
  const std::string& text;
  SourceLocation where;
  std::string context;

  // Line (0-based, within the text) and column (1-based, in characters) of a byte offset.
  std::pair<int, int> position(std::size_t offset) const {
    int line = 0, column = 1;
    for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
      if (text[i] == '\n') {
        ++line;
        column = 1;
      } else if ((static_cast<unsigned char>(text[i]) & 0xC0) != 0x80) {
        ++column;
      }
    }
    return {line, column};
  }

  // The location of a byte offset: the site's location moved to it when the site has one
  // (its column is that of the text's first character); otherwise the column is spelled out.
  [[noreturn]] void fail_at(std::size_t offset, const std::string& problem) const {
    const auto [line, column] = position(offset);
    SourceLocation at = where;
    std::string message = problem;
    if (where.line > 0) {
      if (line == 0) {
        if (where.column > 0) at.column = where.column + column - 1;
      } else {
        at.line = where.line + line;
        at.column = column;
      }
    } else if (line == 0) {
      message += fmt::format(" (column {} of \"{}\")", column, text);
    } else {
      message += fmt::format(" (line {}, column {} of \"{}\")", line + 1, column, text);
    }
    throw ModelError(compose(at, context, message));
  }

  // An error about the whole text.
  [[noreturn]] void fail_whole(const std::string& problem) const {
    throw ModelError(compose(where, context, problem));
  }
};

enum class TokenKind { number, identifier, plus, minus, times, divide, power, open, close, comma, end };

struct Token {
  TokenKind kind;
  std::size_t begin, end;  // byte offsets in the text
  std::string name;        // identifier without primes
  int primes = 0;
};

bool operand_start(TokenKind kind) {
  return kind == TokenKind::number || kind == TokenKind::identifier || kind == TokenKind::open;
}

std::vector<Token> lex(const Site& site, std::size_t begin, std::size_t end) {
  const std::string& s = site.text;
  std::vector<Token> tokens;
  std::size_t i = begin;
  while (i < end) {
    const char c = s[i];
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
      ++i;
      continue;
    }
    Token token{TokenKind::end, i, i + 1, "", 0};
    if (digit(c) || (c == '.' && i + 1 < end && digit(s[i + 1]))) {
      std::size_t j = i;
      while (j < end && digit(s[j])) ++j;
      if (j < end && s[j] == '.') {
        ++j;
        while (j < end && digit(s[j])) ++j;
      }
      if (j < end && (s[j] == 'e' || s[j] == 'E')) {
        std::size_t k = j + 1;
        if (k < end && (s[k] == '+' || s[k] == '-')) ++k;
        if (k < end && digit(s[k])) {
          j = k;
          while (j < end && digit(s[j])) ++j;
        }
      }
      token.kind = TokenKind::number;
      token.end = j;
    } else if (identifier_start(c)) {
      std::size_t j = i;
      while (j < end && identifier_char(s[j])) ++j;
      token.kind = TokenKind::identifier;
      token.name = s.substr(i, j - i);
      while (j < end && s[j] == '\'') {
        ++token.primes;
        ++j;
      }
      token.end = j;
    } else {
      switch (c) {
        case '+': token.kind = TokenKind::plus; break;
        case '-': token.kind = TokenKind::minus; break;
        case '*':
          // ** is a power as in Python and SymPy (whose printed expressions then read as they are).
          if (i + 1 < end && s[i + 1] == '*') {
            token.kind = TokenKind::power;
            token.end = i + 2;
          } else {
            token.kind = TokenKind::times;
          }
          break;
        case '/': token.kind = TokenKind::divide; break;
        case '^': token.kind = TokenKind::power; break;
        case '(': token.kind = TokenKind::open; break;
        case ')': token.kind = TokenKind::close; break;
        case ',': token.kind = TokenKind::comma; break;
        case '\'':
          site.fail_at(i, "syntax error: a prime must follow a coordinate's name directly, as in x' or x''");
        case '=':
          site.fail_at(i, "syntax error: unexpected '=' (only a constraint may be written as lhs = rhs)");
        default: {
          site.fail_at(i, fmt::format("syntax error: unexpected character {}", describe_character(s, i)));
        }
      }
    }
    tokens.push_back(token);
    i = token.end;
  }
  tokens.push_back(Token{TokenKind::end, end, end, "", 0});
  return tokens;
}

// A decimal literal as an exact rational, so that 0.5 m x'^2 stays exact through the derivation.
// The literal as an exact rational in GiNaC's syntax, or "" when its decimal exponent is beyond
// what a double holds (such numbers would take minutes to build exactly).
std::string exact_number(const std::string& literal) {
  std::string digits;
  long long scale = 0;  // value = digits * 10^scale
  std::size_t i = 0;
  for (; i < literal.size() && digit(literal[i]); ++i) digits += literal[i];
  if (i < literal.size() && literal[i] == '.') {
    for (++i; i < literal.size() && digit(literal[i]); ++i) {
      digits += literal[i];
      --scale;
    }
  }
  if (i < literal.size() && (literal[i] == 'e' || literal[i] == 'E')) {
    const std::string exponent = literal.substr(i + 1);
    std::size_t digits_start = exponent.find_first_not_of("+-");
    if (digits_start == std::string::npos || exponent.size() - digits_start > 4) return "";
    scale += std::stoll(exponent);
  }
  if (scale > 330 || scale < -330 - static_cast<long long>(digits.size())) return "";
  const std::size_t nonzero = digits.find_first_not_of('0');
  digits = nonzero == std::string::npos ? "0" : digits.substr(nonzero);
  if (scale == 0) return digits;
  if (scale > 0) return fmt::format("({}*10^{})", digits, scale);
  return fmt::format("({}/10^{})", digits, -scale);
}

const char* describe_token(TokenKind kind) {
  switch (kind) {
    case TokenKind::plus: return "'+'";
    case TokenKind::minus: return "'-'";
    case TokenKind::times: return "'*'";
    case TokenKind::divide: return "'/'";
    case TokenKind::power: return "'^'";
    case TokenKind::open: return "'('";
    case TokenKind::close: return "')'";
    case TokenKind::comma: return "','";
    case TokenKind::end: return "the end of the expression";
    default: return "an operand";
  }
}

// Recursive-descent check of the user's text, which reports every syntax error with its column
// (GiNaC's parser reports none), and writes the text GiNaC parses: internal names, exact numbers,
// explicit (-1)* for a leading sign. GiNaC's own parser then builds the expression.
class Reader {
 public:
  // `scope`: names beyond the spec's symbols (the reactions and outputs that outputs and events
  // may use, SpecBuilder::parse_derived); null for T, V, constraints and the rest.
  // `unavailable`: names that are not symbols here and why (an output's own name, the outputs
  // declared below it: SpecBuilder::parse_derived), said instead of "unknown symbol".
  Reader(const Site& site, const Spec& spec, std::vector<Token> tokens,
         const std::map<std::string, GiNaC::symbol>* scope = nullptr,
         const std::map<std::string, std::string>* unavailable = nullptr)
      : site_(site), spec_(spec), tokens_(std::move(tokens)), scope_(scope), unavailable_(unavailable) {}

  Parsed read() {
    if (tokens_.front().kind == TokenKind::end) site_.fail_at(tokens_.front().begin, "empty expression");
    expression();
    const Token& next = peek();
    if (next.kind != TokenKind::end) {
      if (next.kind == TokenKind::close) site_.fail_at(next.begin, "syntax error: unmatched ')'");
      unexpected(next);
    }
    Parsed parsed;
    // A lone name or a zero (most of a large model's initial values) is what GiNaC's parser
    // would make of it: the symbol (or pi) itself, the number 0.
    if (out_ == "0" || (symbols_.size() == 1 && out_ == internal_name(symbols_.front().name))) {
      if (out_ == "0")
        parsed.value = 0;
      else
        parsed.value = symbols_.front().kind == SymbolKind::constant ? GiNaC::ex(GiNaC::Pi) : symbols_.front().symbol;
      parsed.symbols = std::move(symbols_);
      parsed.present = symbols_of(parsed.value);
      return parsed;
    }
    // Only the names the text uses: a table of every symbol per expression would make reading
    // a model quadratic in its number of coordinates.
    GiNaC::symtab table;
    for (const Occurrence& o : symbols_)
      table[internal_name(o.name)] = o.kind == SymbolKind::constant ? GiNaC::ex(GiNaC::Pi) : o.symbol;
    try {
      // One parser per thread, given each expression's table: making a parser copies GiNaC's
      // table of functions, which cost as much as reading a short expression (a chain's 6000
      // initial values).
      thread_local GiNaC::parser parser(GiNaC::symtab(), /*strict=*/true);
      parser.get_syms() = std::move(table);
      parsed.value = parser(out_);
    } catch (const std::exception& e) {
      site_.fail_at(tokens_.front().begin, plain_words(e.what()));
    }
    parsed.symbols = std::move(symbols_);
    parsed.present = symbols_of(parsed.value);
    return parsed;
  }

 private:
  // A coordinate has a velocity symbol, name': a lookup in the symbol table instead of a search
  // of the list of coordinates, once per identifier read (quadratic for 10 000 particles).
  bool is_coordinate(const std::string& name) const { return spec_.symbols.has(name + "'"); }

  const Token& peek() const { return tokens_[index_]; }
  const Token& next() { return tokens_[index_++]; }
  std::string spelled(const Token& token) const {
    return site_.text.substr(token.begin, token.end - token.begin);
  }

  // For a name shaped like a contact-force column (NAME_N, NAME_Fx, ...) in a model without
  // contact forces: why it is unknown.
  std::string contact_force_hint(const std::string& name) const {
    if (spec_.contact_forces && !spec_.contact_forces->columns.empty()) return "";
    for (int k = 0; k < kContactComponentKinds; ++k) {
      const std::string suffix = std::string("_") + contact_component_name(static_cast<ContactComponent>(k));
      if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
        return fmt::format(" ('{}' looks like a contact-force column, but model '{}' has no contact forces: only "
                           "the [[wheels]], [[knife_edges]] and [[contacts]] of a multibody model have them, docs/multibody.md)",
                           name, spec_.name);
    }
    return "";
  }

  [[noreturn]] void unexpected(const Token& token) {
    if (operand_start(token.kind) && index_ > 0)
      site_.fail_at(token.begin, fmt::format("syntax error: missing operator between '{}' and '{}' "
                                             "(write * for a product)",
                                             spelled(tokens_[index_ - 1]), spelled(token)));
    const std::string what = token.kind == TokenKind::end ? describe_token(token.kind) : "'" + spelled(token) + "'";
    site_.fail_at(token.begin, "syntax error: unexpected " + what);
  }

  void no_sign_after(const Token& op) {
    const Token& token = peek();
    if (token.kind == TokenKind::plus || token.kind == TokenKind::minus)
      site_.fail_at(token.begin, fmt::format("syntax error: a sign directly after '{}' needs parentheses, "
                                             "as in x{}(-y)",
                                             spelled(op), spelled(op)));
  }

  // expression: [sign] factor ((+ | - | * | /) factor)*
  void expression() {
    // Nesting deeper than any formula needs would overflow the stack of this recursive reader.
    if (++depth_ > kMaxNesting) site_.fail_at(peek().begin, fmt::format("expression nested deeper than {} levels", kMaxNesting));
    expression_body();
    --depth_;
  }

  void expression_body() {
    if (peek().kind == TokenKind::plus) {
      next();
    } else if (peek().kind == TokenKind::minus) {
      next();
      out_ += "(-1)*";
    }
    factor();
    for (;;) {
      const Token& token = peek();
      if (token.kind == TokenKind::plus || token.kind == TokenKind::minus || token.kind == TokenKind::times ||
          token.kind == TokenKind::divide) {
        next();
        out_ += spelled(token);
        no_sign_after(token);
        factor();
      } else if (operand_start(token.kind)) {
        unexpected(token);
      } else {
        return;
      }
    }
  }

  // factor: operand [^ operand]; x^a^b is refused as ambiguous.
  void factor() {
    operand();
    if (peek().kind != TokenKind::power) return;
    const Token& op = next();
    out_ += "^";
    no_sign_after(op);
    operand();
    if (peek().kind == TokenKind::power)
      site_.fail_at(peek().begin, "syntax error: x^a^b is ambiguous; write (x^a)^b or x^(a^b)");
  }

  void operand() {
    const Token& token = peek();
    switch (token.kind) {
      case TokenKind::number:
      {
        next();
        const std::string literal(spelled(token));
        const bool nonzero = literal.substr(0, literal.find_first_of("eE")).find_first_of("123456789") != std::string::npos;
        if (!nonzero) {  // zero, whatever its exponent (0e-400 included)
          out_ += "0";
          return;
        }
        const std::string exact = exact_number(literal);
        if (exact.empty())
          site_.fail_at(token.begin, fmt::format("the number {} is out of the range of double precision", spelled(token)));
        // A literal that is not zero but rounds to a subnormal double (or to 0) would reach the
        // numeric layer as a value without precision (CLN refuses it with "floating point
        // underflow"); one that rounds to infinity is out of range.
        const double rounded = std::strtod(literal.c_str(), nullptr);
        if (std::abs(rounded) < std::numeric_limits<double>::min())
          site_.fail_at(token.begin, fmt::format("the number {} is below the smallest normal double (2.2e-308); "
                                                 "write 0 or change the units",
                                                 spelled(token)));
        if (std::isinf(rounded))
          site_.fail_at(token.begin, fmt::format("the number {} is out of the range of double precision", spelled(token)));
        // As a parameter's value (model/parameters.cpp): beyond, the first product a term forms
        // overflows, and a turntable's rate of 1e200 wrote a column of NaN slip speeds.
        if (std::abs(rounded) > std::sqrt(std::numeric_limits<double>::max()))
          site_.fail_at(token.begin, fmt::format("the number {} is too large: above 1.3e154 in magnitude its square, the "
                                                 "first product a term forms, overflows a double; rescale the units",
                                                 spelled(token)));
        out_ += exact;
        return;
      }
      case TokenKind::identifier:
        identifier();
        return;
      case TokenKind::open: {
        next();
        out_ += "(";
        expression();
        if (peek().kind != TokenKind::close) {
          if (peek().kind == TokenKind::end)
            site_.fail_at(token.begin, "syntax error: this '(' is never closed");
          unexpected(peek());
        }
        next();
        out_ += ")";
        return;
      }
      case TokenKind::end:
        site_.fail_at(token.begin, "syntax error: the expression ends where an operand is expected");
      default:
        site_.fail_at(token.begin, fmt::format("syntax error: an operand is expected before '{}'", spelled(token)));
    }
  }

  void identifier() {
    const Token token = next();
    const std::string& name = token.name;
    const std::string written = spelled(token);
    if (token.primes > 2)
      site_.fail_at(token.begin, fmt::format("'{}': only velocities (one prime, {}') and accelerations "
                                             "(two primes, {}'') may be written",
                                             written, name, name));
    const int arity = function_arity(name);
    if (peek().kind == TokenKind::open) {
      if (arity < 0 || token.primes > 0) {
        if (token.primes > 0 || spec_.symbols.has(name))
          site_.fail_at(token.begin, fmt::format("'{}' is not a function; write {}*(...) for a product",
                                                 written, written));
        const std::string nearest = nearest_name(name, function_names());
        site_.fail_at(token.begin, fmt::format("unknown function '{}'{}", name,
                                               nearest.empty() ? "" : fmt::format("; did you mean '{}'?", nearest)));
      }
      const Token& open = next();
      out_ += name + "(";
      int arguments = 1;
      expression();
      while (peek().kind == TokenKind::comma) {
        next();
        out_ += ",";
        expression();
        ++arguments;
      }
      if (peek().kind != TokenKind::close) {
        if (peek().kind == TokenKind::end)
          site_.fail_at(open.begin, fmt::format("syntax error: the '(' of {}( is never closed", name));
        unexpected(peek());
      }
      next();
      out_ += ")";
      if (arguments != arity)
        site_.fail_at(token.begin, fmt::format("{} takes {} argument{}, not {}", name, arity,
                                               arity == 1 ? "" : "s", arguments));
      return;
    }
    if (arity >= 0)
      site_.fail_at(token.begin, fmt::format("'{}' is a function; write {}(...)", written, name));

    if (token.primes == 0) {
      SymbolKind kind = SymbolKind::parameter;
      if (name == "pi") {
        symbols_.push_back({SymbolKind::constant, name, GiNaC::symbol(), token.begin});
        out_ += internal_name(name);
        return;
      }
      std::optional<GiNaC::ex> symbol;
      if (const GiNaC::ex* held = spec_.symbols.expression_of(name)) symbol = *held;
      if (!symbol && scope_ != nullptr) {
        const auto found = scope_->find(name);
        if (found != scope_->end()) symbol = found->second;
      }
      if (!symbol && unavailable_ != nullptr) {
        const auto why = unavailable_->find(name);
        if (why != unavailable_->end()) site_.fail_at(token.begin, why->second);
      }
      if (!symbol) {
        std::vector<std::string> known = {"t", "pi"};
        for (const std::string& c : spec_.coordinates) known.push_back(c);
        for (const SpecParameter& p : spec_.parameters) known.push_back(p.name);
        if (scope_ != nullptr)
          for (const auto& entry : *scope_) known.push_back(entry.first);
        const std::string nearest = nearest_name(name, known);
        site_.fail_at(token.begin, fmt::format("unknown symbol '{}'{}{}", name,
                                               nearest.empty() ? "" : fmt::format("; did you mean '{}'?", nearest),
                                               scope_ != nullptr ? contact_force_hint(name) : ""));
      }
      if (name == "t")
        kind = SymbolKind::time;
      else if (is_coordinate(name))
        kind = SymbolKind::coordinate;
      symbols_.push_back({kind, name, *symbol, token.begin});
      out_ += internal_name(name);
      return;
    }

    const char* what = token.primes == 1 ? "velocity" : "acceleration";
    const bool coordinate = is_coordinate(name);
    if (!coordinate) {
      std::string why = "which is not a coordinate";
      if (name == "t")
        why = "the time, not a coordinate";
      else if (spec_.symbols.has(name))
        why = "which is a parameter, not a coordinate";
      const std::string nearest = spec_.symbols.has(name) ? "" : nearest_name(name, spec_.coordinates);
      site_.fail_at(token.begin,
                    fmt::format("'{}' is the {} of '{}', {}{}", written, what, name, why,
                                nearest.empty() ? "" : fmt::format("; did you mean '{}{}'?", nearest,
                                                                   std::string(static_cast<std::size_t>(token.primes), '\''))));
    }
    symbols_.push_back({token.primes == 1 ? SymbolKind::velocity : SymbolKind::acceleration, written,
                        *spec_.symbols.expression_of(written), token.begin});
    out_ += internal_name(written);
  }

  static constexpr int kMaxNesting = 256;
  int depth_ = 0;
  const Site& site_;
  const Spec& spec_;
  std::vector<Token> tokens_;
  std::size_t index_ = 0;
  std::string out_;
  std::vector<Occurrence> symbols_;
  const std::map<std::string, GiNaC::symbol>* scope_ = nullptr;
  const std::map<std::string, std::string>* unavailable_ = nullptr;
};

// Exponents beyond this make the derivation's expansion explode (a hang, not an answer); no
// kinetic energy, potential or constraint of mechanics needs them.
constexpr long kLargestExponent = 64;

// What read() measures of an expression, in one walk: a walk per measure, and largest_expansion's
// walk of every subtree again at each level, cost a tenth of reading a long kinetic energy.
struct Measures {
  bool huge_exponent = false;  // a number exponent larger than kLargestExponent in magnitude
  // 0^x with an exponent that is not a number (GiNaC keeps it as written; (x - x)^y is one): 0
  // where x > 0, undefined elsewhere, and its derivative 0^x log(0) makes GiNaC throw.
  bool zero_to_a_variable = false;
  // The number of terms that multiplying out the expression can produce (an upper bound: a sum's
  // terms add, a product's multiply, (t terms)^n gives at most C(n + t - 1, t - 1)); function
  // arguments and the bases of non-integer powers are atoms here and measured on their own.
  double terms = 1.0;
  double largest = 1.0;  // the largest `terms` of the expression and of its subexpressions
  std::size_t nodes = 1;
};

Measures measure(const GiNaC::ex& e) {
  Measures out;
  const bool sum = GiNaC::is_exactly_a<GiNaC::add>(e), product = GiNaC::is_exactly_a<GiNaC::mul>(e);
  const bool power = GiNaC::is_exactly_a<GiNaC::power>(e);
  const bool number_exponent = power && GiNaC::is_exactly_a<GiNaC::numeric>(e.op(1));
  const bool integer_power = number_exponent && GiNaC::ex_to<GiNaC::numeric>(e.op(1)).is_integer();
  if (number_exponent && GiNaC::abs(GiNaC::ex_to<GiNaC::numeric>(e.op(1))) > GiNaC::numeric(kLargestExponent))
    out.huge_exponent = true;
  if (power && !number_exponent && e.op(0).is_zero()) out.zero_to_a_variable = true;
  // The subexpressions whose own expansion counts: those of sums, products, powers and functions.
  const bool inner = sum || product || power || GiNaC::is_a<GiNaC::function>(e);
  double base_terms = 1.0;
  out.terms = sum ? 0.0 : 1.0;
  double largest = 0.0;
  for (std::size_t i = 0; i < e.nops(); ++i) {
    const Measures m = measure(e.op(i));
    out.huge_exponent = out.huge_exponent || m.huge_exponent;
    out.zero_to_a_variable = out.zero_to_a_variable || m.zero_to_a_variable;
    out.nodes += m.nodes;
    if (inner) largest = std::max(largest, m.largest);
    if (sum) out.terms += m.terms;
    if (product) out.terms *= m.terms;
    if (i == 0) base_terms = m.terms;
  }
  if (product) out.terms = std::min(out.terms, 1e300);
  if (integer_power && !out.huge_exponent) {  // refused when huge, whatever it measures
    const double t = base_terms;
    const double n = std::min(std::abs(GiNaC::ex_to<GiNaC::numeric>(e.op(1)).to_double()), 1e6);
    if (t <= 1.0) {
      out.terms = 1.0;
    } else {
      // C(n + t - 1, t - 1) through lgamma, capped: only its order of magnitude matters.
      const double log_terms = std::lgamma(n + t) - std::lgamma(n + 1.0) - std::lgamma(t);
      out.terms = log_terms > 690.0 ? 1e300 : std::exp(log_terms);
    }
  }
  out.largest = std::max(out.terms, largest);
  return out;
}

// The derivation multiplies expressions out (expand, normal), and its time grows faster than the
// terms it makes: a kinetic energy of 3500 terms once multiplied out (the sled's T times
// (x + y + phi + a)^20) takes 2.6 s to derive, one of 11000 terms 15 s, a product of powers of
// sums minutes and gigabytes. So an expression that would grow by more terms than this is refused
// where it is read. A long sum as written (the kinetic energy of a 10000-body chain) grows by
// nothing and is not limited here; the examples' largest expansion is 37 terms.
constexpr double kLargestExpansion = 1e3;

Parsed read(const Spec& spec, const Site& site, std::size_t begin, std::size_t end,
            const std::map<std::string, GiNaC::symbol>* scope = nullptr,
            const std::map<std::string, std::string>* unavailable = nullptr) {
  Parsed parsed = Reader(site, spec, lex(site, begin, end), scope, unavailable).read();
  const Measures measures = measure(parsed.value);
  if (measures.huge_exponent)
    site.fail_whole(fmt::format("an exponent larger than {} in magnitude; nhdyn expands powers symbolically, "
                                "so rewrite the expression (e.g. with exp and log) or use a smaller power",
                                kLargestExponent));
  if (measures.zero_to_a_variable)
    site.fail_whole("the expression raises 0 to a power that is not a number (0^x, or a base such as x - x that is "
                    "identically 0): that is 0 where the exponent is positive and undefined where it is not, and has no "
                    "derivative; write 0, or the base meant");
  const double terms = measures.largest;
  if (terms > kLargestExpansion + 10.0 * static_cast<double>(measures.nodes))
    site.fail_whole(fmt::format("multiplied out, this expression could have about {:.2g} terms (the limit is {:g}): "
                                "nhdyn expands products and powers of sums symbolically, which takes seconds at a few thousand terms "
                                "and minutes beyond; "
                                "use smaller powers, or fewer factors that are sums",
                                terms, kLargestExpansion));
  return parsed;
}

Parsed read(const Spec& spec, const Site& site) { return read(spec, site, 0, site.text.size()); }

// The number of nodes of `e` written out as a tree, each shared subexpression counted as often as
// it occurs, capped at 1e300; computed once per shared node (GiNaC shares them), so in time linear
// in the expression's memory. Walks of GiNaC (subs, has, evalf, printing) take time in this count.
double tree_size(const GiNaC::ex& e, std::unordered_map<const GiNaC::basic*, std::pair<GiNaC::ex, double>>& seen) {
  const GiNaC::basic* key = &GiNaC::ex_to<GiNaC::basic>(e);
  const auto found = seen.find(key);
  if (found != seen.end()) return found->second.second;
  double size = 1.0;
  for (std::size_t i = 0; i < e.nops(); ++i) size = std::min(size + tree_size(e.op(i), seen), 1e300);
  // The expression is kept with its size: op() of a sum or product may build a temporary, whose
  // address must not be reused by another one while the table lives.
  seen.emplace(key, std::make_pair(e, size));
  return size;
}

// An output or event with the outputs it names written out: beyond this many nodes, the walks of
// compiling it take minutes (outputs that each use the one before twice double at every line).
constexpr double kLargestDerived = 2e5;

// The first occurrence of a symbol of `kind` that the expression still contains (x' - x' does not).
const Occurrence* first_of(const Parsed& parsed, SymbolKind kind) {
  for (const Occurrence& o : parsed.symbols)
    if (o.kind == kind && parsed.contains(o)) return &o;
  return nullptr;
}

// Refuses the symbols of `kind` in an expression, naming the first one found ({} in `problem`).
void refuse(const Parsed& parsed, const Site& site, SymbolKind kind, const std::string& problem) {
  if (const Occurrence* o = first_of(parsed, kind))
    site.fail_at(o->position, fmt::format(fmt::runtime(problem), o->name));
}

bool valid_name(const std::string& name) {
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) return false;
  if (name.find("__") != std::string::npos) return false;
  return std::all_of(name.begin(), name.end(), identifier_char);
}

std::string did_you_mean(const std::string& name, const std::vector<std::string>& known) {
  const std::string nearest = nearest_name(name, known);
  return nearest.empty() ? "" : fmt::format("; did you mean '{}'?", nearest);
}

// Names of coordinates and parameters share one space with t, pi and the functions.
void check_new_name(const Spec& spec, bool is_coordinate, const std::string& name, const char* what,
                    const SourceLocation& where) {
  const std::string context = fmt::format("{} '{}'", what, shown_name(name));
  if (!valid_name(name))
    fail(where, context, "not a valid name: use letters, digits and single underscores, starting with a letter");
  if (name == "t") fail(where, context, "'t' is the time and cannot be declared");
  if (name == "pi") fail(where, context, "'pi' is the constant pi and cannot be declared");
  if (function_arity(name) >= 0) fail(where, context, fmt::format("'{}' is the name of a function", name));
  if (is_coordinate) fail(where, context, fmt::format("duplicated name: '{}' is already a coordinate", name));
  for (const SpecParameter& p : spec.parameters)
    if (p.name == name) {
      const std::string at = p.where.describe();
      fail(where, context, fmt::format("duplicated name: '{}' is already a parameter{}", name,
                                       at.empty() ? "" : " (declared at " + at + ")"));
    }
}

}  // namespace

int SpecBuilder::coordinate_of(const std::string& name) const {
  const auto it = coordinate_by_name_.find(name);
  return it == coordinate_by_name_.end() ? -1 : it->second;
}

SpecBuilder::SpecBuilder(std::string name, SourceLocation where) {
  spec_.name = std::move(name);
  spec_.where = std::move(where);
}

SpecBuilder& SpecBuilder::description(std::string text) {
  spec_.description = std::move(text);
  return *this;
}

SpecBuilder& SpecBuilder::coordinate(const std::string& name, SourceLocation where) {
  check_new_name(spec_, coordinate_of(name) >= 0, name, "coordinate", where);
  coordinate_by_name_.emplace(name, static_cast<int>(spec_.coordinates.size()));
  spec_.symbols.add_coordinate(name);
  spec_.coordinates.push_back(name);
  spec_.forces.resize(spec_.coordinates.size(), GiNaC::ex(0));
  spec_.q0.resize(spec_.coordinates.size(), GiNaC::ex(0));
  spec_.v0.resize(spec_.coordinates.size(), GiNaC::ex(0));
  initial_given_.resize(spec_.coordinates.size(), false);
  solution_given_.resize(spec_.coordinates.size(), false);
  return *this;
}

SpecBuilder& SpecBuilder::parameter(const std::string& name, double value, std::string unit, SourceLocation where) {
  check_new_name(spec_, coordinate_of(name) >= 0, name, "parameter", where);
  if (!std::isfinite(value))
    fail(where, fmt::format("parameter '{}'", name), fmt::format("value {} is not a finite number", value));
  if (value != 0.0 && std::abs(value) < std::numeric_limits<double>::min())
    fail(where, fmt::format("parameter '{}'", name),
         fmt::format("value {:g} is below the smallest normal double (2.2e-308), where numbers lose their precision; "
                     "give 0 or change the units",
                     value));
  spec_.symbols.add_parameter(name);
  spec_.parameters.push_back({name, value, std::move(unit), std::move(where)});
  return *this;
}

GiNaC::ex SpecBuilder::parse(const std::string& text, const SourceLocation& where) const {
  return read(spec_, Site{text, where, ""}).value;
}

SpecBuilder& SpecBuilder::kinetic_energy(const std::string& text, SourceLocation where) {
  const Site site{text, where, "kinetic energy T"};
  const Parsed parsed = read(spec_, site);
  refuse(parsed, site, SymbolKind::acceleration, "the kinetic energy may not contain accelerations (found {})");
  spec_.kinetic_energy = parsed.value;
  return *this;
}

SpecBuilder& SpecBuilder::potential_energy(const std::string& text, SourceLocation where) {
  const Site site{text, where, "potential energy V"};
  const Parsed parsed = read(spec_, site);
  refuse(parsed, site, SymbolKind::velocity,
         "the potential energy may not contain velocities (found {}); give velocity-dependent "
         "forces as nonconservative forces");
  refuse(parsed, site, SymbolKind::acceleration, "the potential energy may not contain accelerations (found {})");
  spec_.potential_energy = parsed.value;
  return *this;
}

SpecBuilder& SpecBuilder::force(const std::string& coordinate, const std::string& text, SourceLocation where) {
  const int i = coordinate_of(coordinate);
  if (i < 0)
    fail(where, fmt::format("force on '{}'", coordinate),
         fmt::format("'{}' is not a coordinate{}", coordinate, did_you_mean(coordinate, spec_.coordinates)));
  const Site site{text, where, fmt::format("force on '{}'", coordinate)};
  const Parsed parsed = read(spec_, site);
  refuse(parsed, site, SymbolKind::acceleration, "a force may not contain accelerations (found {})");
  // Several forces on one coordinate add up.
  spec_.forces[static_cast<std::size_t>(i)] += parsed.value;
  return *this;
}

void SpecBuilder::check_constraint_name(const std::string& name, const SourceLocation& where) const {
  const std::string context = fmt::format("constraint '{}'", shown_name(name));
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0])) ||
      !std::all_of(name.begin(), name.end(), [](char c) { return identifier_char(c) || c == '-'; }))
    fail(where, context, "not a valid constraint name: use letters, digits, '_' and '-', starting with a letter");
  if (const auto found = constraint_by_name_.find(name); found != constraint_by_name_.end()) {
    const std::string at = spec_.constraints[found->second].where.describe();
    fail(where, context, fmt::format("duplicated constraint name '{}'{}", name,
                                     at.empty() ? "" : " (first given at " + at + ")"));
  }
}

SpecBuilder& SpecBuilder::add_energies(const GiNaC::ex& kinetic, const GiNaC::ex& potential) {
  spec_.kinetic_energy += kinetic;
  spec_.potential_energy += potential;
  return *this;
}

SpecBuilder& SpecBuilder::constraint(const std::string& name, ConstraintLevel level, const GiNaC::ex& expression,
                                     const std::string& text, SourceLocation where) {
  check_constraint_name(name, where);
  const int n = spec_.n();
  bool velocities = false, accelerations = false;
  for (int i = 0; i < n; ++i) {
    velocities = velocities || expression.has(spec_.symbols.velocity(i));
    accelerations = accelerations || expression.has(spec_.symbols.acceleration(i));
  }
  const bool fits = level == ConstraintLevel::position   ? !velocities && !accelerations
                    : level == ConstraintLevel::velocity ? velocities && !accelerations
                                                         : accelerations;
  if (!fits)
    fail(where, fmt::format("constraint '{}'", name),
         "the expression does not match the level it is given at (position: no velocities; velocity: some "
         "velocity, no acceleration; acceleration: some acceleration)");
  constraint_by_name_.emplace(name, spec_.constraints.size());
  spec_.constraints.push_back({name, level, expression, text, std::move(where)});
  return *this;
}

SpecBuilder& SpecBuilder::constraint(const std::string& name, ConstraintLevel level, const std::string& text,
                                     SourceLocation where) {
  const std::string context = fmt::format("constraint '{}'", name);
  check_constraint_name(name, where);
  const Site site{text, where, context};
  // `lhs = rhs` is read as lhs - rhs = 0.
  Parsed parsed;
  const std::size_t equals = text.find('=');
  if (equals == std::string::npos) {
    parsed = read(spec_, site);
  } else {
    if (text.find('=', equals + 1) != std::string::npos)
      site.fail_at(text.find('=', equals + 1), "syntax error: a constraint has at most one '='");
    Parsed lhs = read(spec_, site, 0, equals);
    Parsed rhs = read(spec_, site, equals + 1, text.size());
    parsed.value = lhs.value - rhs.value;
    parsed.symbols = std::move(lhs.symbols);
    parsed.symbols.insert(parsed.symbols.end(), rhs.symbols.begin(), rhs.symbols.end());
    parsed.present = symbols_of(parsed.value);
  }
  const bool velocities = first_of(parsed, SymbolKind::velocity) != nullptr;
  const bool accelerations = first_of(parsed, SymbolKind::acceleration) != nullptr;
  switch (level) {
    case ConstraintLevel::position:
      refuse(parsed, site, SymbolKind::velocity,
             "a position-level constraint may not contain velocities (found {}); give it at velocity level");
      refuse(parsed, site, SymbolKind::acceleration,
             "a position-level constraint may not contain accelerations (found {}); give it at acceleration "
             "level");
      break;
    case ConstraintLevel::velocity:
      refuse(parsed, site, SymbolKind::acceleration,
             "a velocity-level constraint may not contain accelerations (found {}); give it at acceleration "
             "level");
      if (!velocities)
        site.fail_whole("a velocity-level constraint must contain some velocity; without one it is a "
                  "position-level constraint");
      break;
    case ConstraintLevel::acceleration:
      if (!accelerations)
        site.fail_whole(fmt::format("an acceleration-level constraint must contain some acceleration; "
                              "without one it is a {}-level constraint",
                              velocities ? "velocity" : "position"));
      break;
  }
  constraint_by_name_.emplace(name, spec_.constraints.size());
  spec_.constraints.push_back({name, level, parsed.value, text, std::move(where)});
  return *this;
}

SpecBuilder& SpecBuilder::constraint(const std::string& name, const std::string& text, SourceLocation where) {
  // The level of the highest derivative present; read once just to find it.
  const Site site{text, where, fmt::format("constraint '{}'", name)};
  ConstraintLevel level = ConstraintLevel::position;
  const std::size_t equals = text.find('=');
  std::vector<Parsed> sides;
  if (equals == std::string::npos || text.find('=', equals + 1) != std::string::npos) {
    if (equals == std::string::npos) sides.push_back(read(spec_, site));
  } else {
    sides.push_back(read(spec_, site, 0, equals));
    sides.push_back(read(spec_, site, equals + 1, text.size()));
  }
  for (const Parsed& side : sides) {
    if (first_of(side, SymbolKind::acceleration))
      level = ConstraintLevel::acceleration;
    else if (first_of(side, SymbolKind::velocity) && level == ConstraintLevel::position)
      level = ConstraintLevel::velocity;
  }
  return constraint(name, level, text, std::move(where));
}

namespace {

// A program is checked and parsed like a constraint (the same rules for its level); its errors
// then name it as a program.
std::string as_program(std::string message, const std::string& name) {
  const std::string constraint = "constraint '" + name + "'";
  const std::size_t at = message.find(constraint);
  if (at != std::string::npos) message.replace(at, constraint.size(), "program '" + name + "'");
  return message;
}

}  // namespace

SpecBuilder& SpecBuilder::program(const std::string& name, ConstraintLevel level, const std::string& text,
                                  const std::vector<std::string>& actuator_direction, SourceLocation where,
                                  SourceLocation actuator_where) {
  const std::string context = fmt::format("program '{}'", name);
  for (const SpecProgram& p : spec_.programs)
    if (p.constraint.name == name) {
      const std::string at = p.constraint.where.describe();
      fail(where, context,
           fmt::format("duplicated program name '{}'{}", name, at.empty() ? "" : " (first given at " + at + ")"));
    }
  const int n = spec_.n();
  if (static_cast<int>(actuator_direction.size()) != n)
    fail(actuator_where, context,
         fmt::format("the actuator direction has {} entries for {} coordinates ({}); give one generalized force "
                     "component per coordinate, or name one coordinate (actuator = \"{}\")",
                     actuator_direction.size(), n, join(spec_.coordinates), spec_.coordinates.front()));
  SpecProgram program;
  for (std::size_t i = 0; i < actuator_direction.size(); ++i) {
    const Site site{actuator_direction[i], actuator_where,
                    fmt::format("actuator of {} (entry {}, on '{}')", context, i + 1, spec_.coordinates[i])};
    const Parsed parsed = read(spec_, site);
    refuse(parsed, site, SymbolKind::acceleration, "an actuator direction may not contain accelerations (found {})");
    program.actuator.push_back(parsed.value);
  }
  // Parsed and checked as a constraint would be, then moved to the programs.
  try {
    constraint(name, level, text, where);
  } catch (const ModelError& error) {
    throw ModelError(as_program(error.what(), name));
  }
  program.constraint = std::move(spec_.constraints.back());
  spec_.constraints.pop_back();
  program.actuator_text = "[" + join(actuator_direction) + "]";
  program.actuator_where = std::move(actuator_where);
  spec_.programs.push_back(std::move(program));
  return *this;
}

SpecBuilder& SpecBuilder::program(const std::string& name, ConstraintLevel level, const std::string& text,
                                  const std::string& actuator, SourceLocation where, SourceLocation actuator_where) {
  const int i = coordinate_of(actuator);
  if (i < 0)
    fail(actuator_where, fmt::format("program '{}'", name),
         fmt::format("the actuator '{}' is not a coordinate: name the coordinate the actuator's force or torque "
                     "acts on (one of {}), or give a direction, actuator = [\"...\", ...] with one entry per "
                     "coordinate{}",
                     actuator, join(spec_.coordinates), did_you_mean(actuator, spec_.coordinates)));
  std::vector<std::string> direction(spec_.coordinates.size(), "0");
  direction[static_cast<std::size_t>(i)] = "1";
  program(name, level, text, direction, where, actuator_where);
  spec_.programs.back().actuator_text = actuator;
  return *this;
}

SpecBuilder& SpecBuilder::independent(const std::vector<std::string>& coordinates, SourceLocation where) {
  const std::string context = "independent coordinates";
  for (std::size_t i = 0; i < coordinates.size(); ++i) {
    const std::string& name = coordinates[i];
    if (coordinate_of(name) < 0)
      fail(where, context, fmt::format("'{}' is not a coordinate{}", name, did_you_mean(name, spec_.coordinates)));
    if (std::find(coordinates.begin(), coordinates.begin() + static_cast<std::ptrdiff_t>(i), name) !=
        coordinates.begin() + static_cast<std::ptrdiff_t>(i))
      fail(where, context, fmt::format("duplicated: '{}' is listed twice", name));
  }
  spec_.independent = coordinates;
  independent_where_ = std::move(where);
  return *this;
}

SpecBuilder& SpecBuilder::complement(const std::vector<std::vector<std::string>>& rows, SourceLocation where) {
  std::size_t columns = 0;
  for (const auto& row : rows) columns = std::max(columns, row.size());
  GiNaC::matrix D(static_cast<unsigned>(rows.size()), static_cast<unsigned>(columns));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].size() != columns)
      fail(where, "complement D",
           fmt::format("row {} has {} entries but row {} has {}; every row needs one entry per coordinate", i + 1,
                       rows[i].size(), 1 + (rows[0].size() == columns ? 0 : i), columns));
    for (std::size_t j = 0; j < columns; ++j) {
      const Site site{rows[i][j], where, fmt::format("complement D, row {}, column {}", i + 1, j + 1)};
      const Parsed parsed = read(spec_, site);
      refuse(parsed, site, SymbolKind::acceleration, "D may not contain accelerations (found {})");
      D(static_cast<unsigned>(i), static_cast<unsigned>(j)) = parsed.value;
    }
  }
  spec_.complement = D;
  spec_.complement_where = std::move(where);
  return *this;
}

SpecBuilder& SpecBuilder::initial(const std::string& coordinate, const std::string& q0, const std::string& v0,
                                  SourceLocation where) {
  const int i = coordinate_of(coordinate);
  if (i < 0)
    fail(where, fmt::format("initial value of '{}'", coordinate),
         fmt::format("'{}' is not a coordinate{}", coordinate, did_you_mean(coordinate, spec_.coordinates)));
  const auto value = [&](const std::string& text, const char* what) {
    const Site site{text, where, fmt::format("initial {} of '{}'", what, coordinate)};
    const Parsed parsed = read(spec_, site);
    for (const Occurrence& o : parsed.symbols)
      if (o.kind != SymbolKind::parameter && o.kind != SymbolKind::constant && parsed.contains(o))
        site.fail_at(o.position, fmt::format("an initial value may depend on the parameters only, not on '{}'", o.name));
    return parsed.value;
  };
  spec_.q0[static_cast<std::size_t>(i)] = value(q0, "value");
  spec_.v0[static_cast<std::size_t>(i)] = value(v0, "velocity");
  initial_given_[static_cast<std::size_t>(i)] = true;
  return *this;
}

SpecBuilder& SpecBuilder::solution(const std::string& coordinate, const std::string& text, SourceLocation where) {
  const int i = coordinate_of(coordinate);
  if (i < 0)
    fail(where, fmt::format("solution of '{}'", coordinate),
         fmt::format("'{}' is not a coordinate{}", coordinate, did_you_mean(coordinate, spec_.coordinates)));
  const Site site{text, where, fmt::format("solution of '{}'", coordinate)};
  const Parsed parsed = read(spec_, site);
  for (const Occurrence& o : parsed.symbols)
    if (o.kind != SymbolKind::parameter && o.kind != SymbolKind::constant && o.kind != SymbolKind::time &&
        parsed.contains(o))
      site.fail_at(o.position, fmt::format("a solution q(t) may depend on t and the parameters only, not on '{}'",
                                           o.name));
  spec_.solution.resize(spec_.coordinates.size(), GiNaC::ex(0));
  spec_.solution_where.resize(spec_.coordinates.size());
  spec_.solution[static_cast<std::size_t>(i)] = parsed.value;
  spec_.solution_where[static_cast<std::size_t>(i)] = std::move(where);
  solution_given_[static_cast<std::size_t>(i)] = true;
  return *this;
}

SpecBuilder& SpecBuilder::initial_time(double t0) {
  if (!std::isfinite(t0)) fail(spec_.where, fmt::format("model '{}'", spec_.name), "the initial time is not finite");
  spec_.t0 = t0;
  return *this;
}

SpecBuilder& SpecBuilder::defaults(const SimulationDefaults& defaults) {
  spec_.defaults = defaults;
  return *this;
}

SpecBuilder& SpecBuilder::method(const std::string& name) {
  spec_.method = name;
  spec_.defaults.method = name.empty() ? RunOptions{}.method : name;
  return *this;
}

SpecBuilder& SpecBuilder::integrator(const std::string& name) {
  spec_.integrator = name;
  spec_.defaults.integrator = name.empty() ? RunOptions{}.integrator : name;
  return *this;
}

SpecBuilder& SpecBuilder::tolerances(std::optional<double> rtol, std::optional<double> atol) {
  const auto check = [&](const std::optional<double>& value, const char* what) {
    if (value && !(*value > 0.0 && std::isfinite(*value)))
      fail(spec_.where, fmt::format("model '{}'", spec_.name),
           fmt::format("{} must be a positive number, not {}", what, *value));
  };
  check(rtol, "rtol");
  check(atol, "atol");
  spec_.rtol = rtol;
  spec_.atol = atol;
  spec_.defaults.rtol = rtol.value_or(RunOptions{}.rtol);
  spec_.defaults.atol = atol.value_or(RunOptions{}.atol);
  return *this;
}

SpecBuilder& SpecBuilder::path(const std::string& x, const std::string& y) {
  for (const std::string& name : {x, y})
    if (coordinate_of(name) < 0)
      fail(spec_.where, "path", fmt::format("'{}' is not a coordinate{}", name, did_you_mean(name, spec_.coordinates)));
  spec_.path = std::make_pair(x, y);
  return *this;
}

namespace {

// The names outputs and events may use beyond the spec's symbols: the reactions R_x (unless a
// parameter is called so) and the outputs declared so far.
std::map<std::string, GiNaC::symbol> derived_scope(const Spec& spec) {
  std::map<std::string, GiNaC::symbol> scope;
  for (int i = 0; i < spec.n(); ++i)
    if (!spec.symbols.has("R_" + spec.coordinates[static_cast<std::size_t>(i)]))
      scope.emplace("R_" + spec.coordinates[static_cast<std::size_t>(i)], spec.symbols.reaction(i));
  for (const SpecOutput& o : spec.outputs) scope.emplace(o.name, o.symbol);
  // The contact-force columns (NAME_N ...): events may name them (symbolic/events.cpp); outputs
  // that do are refused (symbolic/outputs.cpp).
  if (spec.contact_forces)
    for (const ContactForceSymbol& c : spec.contact_forces->columns) scope.emplace(c.name, c.symbol);
  return scope;
}

// What parse_derived reads: `text` against `scope` (derived_scope), with the names in
// `unavailable` refused with their reason, each output then replaced by its expression.
GiNaC::ex read_derived(const Spec& spec, const std::string& text, const SourceLocation& where,
                       const std::map<std::string, GiNaC::symbol>& scope,
                       const std::map<std::string, std::string>& unavailable) {
  const Site site{text, where, ""};
  const GiNaC::ex value = read(spec, site, 0, text.size(), &scope, &unavailable).value;
  if (spec.outputs.empty()) return value;
  GiNaC::exmap outputs;
  for (const SpecOutput& o : spec.outputs) outputs[o.symbol] = o.expression;
  const GiNaC::ex written_out = value.subs(outputs);
  std::unordered_map<const GiNaC::basic*, std::pair<GiNaC::ex, double>> seen;
  const double size = tree_size(written_out, seen);
  if (size > kLargestDerived)
    site.fail_whole(fmt::format("with the outputs it names written out, this expression has about {:.2g} operations "
                                "(the limit is {:g}): outputs that each use the one above more than once grow "
                                "exponentially down the chain, and compiling them would take minutes; name each "
                                "output once per expression (e.g. b = \"a^2\" rather than \"a*a\"), or write the "
                                "expression in t, q, q', q'', R_x and the parameters",
                                size, kLargestDerived));
  return written_out;
}

}  // namespace

SpecBuilder& SpecBuilder::announce_outputs(std::vector<std::pair<std::string, SourceLocation>> names) {
  announced_outputs_ = std::move(names);
  return *this;
}

GiNaC::ex SpecBuilder::parse_derived(const std::string& text, const SourceLocation& where,
                                     const std::string& defining) const {
  const std::map<std::string, GiNaC::symbol> scope = derived_scope(spec_);
  // An output's own name and the outputs announced below it are not in scope: say why.
  std::map<std::string, std::string> unavailable;
  if (!defining.empty())
    unavailable.emplace(defining, fmt::format("output '{}' is defined through itself: its expression names '{}'; an "
                                              "output may use t, q, q', q'', R_x, the parameters and the outputs "
                                              "above it only",
                                              defining, defining));
  for (const auto& [name, at] : announced_outputs_) {
    if (name == defining || scope.count(name) > 0) continue;
    const std::string place = at.describe();
    unavailable.emplace(
        name, fmt::format("'{}' is an output declared below {}{}: an output may use only the outputs above it "
                          "(they are computed in file order); move '{}' above it (two outputs that use each other "
                          "have no value)",
                          name, defining.empty() ? std::string("this one") : fmt::format("'{}'", defining),
                          place.empty() ? "" : " (at " + place + ")", name));
  }
  return read_derived(spec_, text, where, scope, unavailable);
}

GiNaC::ex parse_derived(const Spec& spec, const std::string& text, const SourceLocation& where) {
  return read_derived(spec, text, where, derived_scope(spec), {});
}

SpecBuilder& SpecBuilder::output(const std::string& name, const std::string& text, SourceLocation where) {
  const GiNaC::ex expression = parse_derived(text, where, name);
  return output(name, expression, text, std::move(where));
}

SpecBuilder& SpecBuilder::output(const std::string& name, const GiNaC::ex& expression, const std::string& text,
                                 SourceLocation where, bool automatic) {
  check_new_name(spec_, coordinate_of(name) >= 0, name, "output", where);
  const std::string context = fmt::format("output '{}'", name);
  for (const SpecOutput& o : spec_.outputs)
    if (o.name == name) {
      const std::string at = o.where.describe();
      fail(where, context,
           fmt::format("duplicated name: '{}' is already an output{}{}", name,
                       o.automatic ? " (the multibody model's own, docs/multibody.md)" : "",
                       at.empty() ? "" : " (declared at " + at + ")"));
    }
  for (const std::string& q : spec_.coordinates)
    if (name == "R_" + q)
      fail(where, context, fmt::format("'{}' is the column of the reaction on '{}'; choose another name", name, q));
  SpecOutput output;
  output.name = name;
  output.expression = expression;
  output.text = text;
  output.where = std::move(where);
  output.automatic = automatic;
  output.symbol = GiNaC::symbol(name);
  spec_.outputs.push_back(std::move(output));
  return *this;
}

Spec SpecBuilder::build() const {
  const std::string context = fmt::format("model '{}'", spec_.name);
  const int n = spec_.n(), s = spec_.s();
  if (n == 0) fail(spec_.where, context, "no coordinates are declared");
  if (spec_.kinetic_energy.is_zero())
    fail(spec_.where, context, "missing kinetic energy T (it defines the inertia matrix A = d2T/dq'2)");
  if (const int held = constraints_always_held(spec_); held >= n)
    fail(spec_.where, context,
         held == s ? fmt::format("{} constraints for {} coordinates: there must be fewer constraints than coordinates "
                                 "(s < n)",
                                 s, n)
                   : fmt::format("{} constraints for {} coordinates, {} of them held whatever the contacts' modes: "
                                 "fewer than n must hold at any time (s < n, or contacts that lift off or slide, "
                                 "docs/contact-modes.md)",
                                 s, n, held));
  // With s >= n (contacts never all held) the model's own degrees of freedom change with the
  // modes: what is chosen for k = n - s of them has no meaning.
  if (s >= n && (spec_.m() > 0 || !spec_.independent.empty() || spec_.complement))
    fail(spec_.m() > 0 ? spec_.programs.front().constraint.where : spec_.where, context,
         fmt::format("{} constraints for {} coordinates: {} need{} fewer constraints than coordinates (s < n), "
                     "whatever the contacts' modes",
                     s, n,
                     spec_.m() > 0 ? "programs" : !spec_.independent.empty() ? "independent coordinates" : "a complement D",
                     spec_.m() > 0 || !spec_.independent.empty() ? "" : "s"));
  const int k = std::max(n - s, 0);
  if (spec_.m() > k) {
    const SpecProgram& extra = spec_.programs[static_cast<std::size_t>(k)];
    fail(extra.constraint.where, context,
         fmt::format("{} programs for k = n - s = {} - {} = {} degrees of freedom: at most {} programs are possible "
                     "(each program takes one degree of freedom; docs/derivations/program-motion.md section 3); "
                     "remove {} of them, starting with '{}'",
                     spec_.m(), n, s, k, k, spec_.m() - k, extra.constraint.name));
  }
  if (!spec_.independent.empty() && static_cast<int>(spec_.independent.size()) != k)
    fail(independent_where_, "independent coordinates",
         fmt::format("{} given ({}), but k = n - s = {} - {} = {} are needed", spec_.independent.size(),
                     join(spec_.independent), n, s, k));
  if (spec_.complement) {
    const GiNaC::matrix& D = *spec_.complement;
    if (static_cast<int>(D.rows()) != k || static_cast<int>(D.cols()) != n)
      fail(spec_.complement_where, "complement D",
           fmt::format("D is {} x {} but must be k x n = {} x {} (k = n - s = {} - {})", D.rows(), D.cols(), k, n, n,
                       s));
  }
  // A contact point's added coordinates are found at the start, never written.
  std::vector<bool> found(initial_given_.size(), false);
  for (const SpecContactCoordinates& added : spec_.contact_coordinates)
    for (int i : added.coordinates) found[static_cast<std::size_t>(i)] = true;
  std::size_t given = 0, writable = 0;
  for (std::size_t i = 0; i < initial_given_.size(); ++i)
    if (!found[i]) {
      ++writable;
      if (initial_given_[i]) ++given;
    }
  if (given != 0 && given != writable) {
    std::vector<std::string> missing;
    for (std::size_t i = 0; i < initial_given_.size(); ++i)
      if (!initial_given_[i] && !found[i]) missing.push_back(spec_.coordinates[i]);
    fail(spec_.where, context,
         fmt::format("initial values are given for some coordinates but not for {}: give all or none "
                     "(none means all zero)",
                     join(missing)));
  }
  const auto solved = static_cast<std::size_t>(std::count(solution_given_.begin(), solution_given_.end(), true));
  if (solved != 0 && solved != solution_given_.size()) {
    std::vector<std::string> missing;
    for (std::size_t i = 0; i < solution_given_.size(); ++i)
      if (!solution_given_[i]) missing.push_back(spec_.coordinates[i]);
    fail(spec_.where, context,
         fmt::format("the solution gives q(t) for some coordinates but not for {}: an exact motion needs "
                     "every coordinate",
                     join(missing)));
  }
  Spec spec = spec_;
  spec.forces.resize(static_cast<std::size_t>(n), GiNaC::ex(0));
  spec.q0.resize(static_cast<std::size_t>(n), GiNaC::ex(0));
  spec.v0.resize(static_cast<std::size_t>(n), GiNaC::ex(0));
  return spec;
}

}  // namespace nhdyn::symbolic
