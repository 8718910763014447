#include "nhdyn/model/parameters.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <utility>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/detail/characters.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/core/detail/suggest.hpp"

namespace nhdyn {
namespace {

// "; did you mean 'm'?" for the known name nearest to `name`, or "" when none is close.
std::string did_you_mean(std::string_view name, const std::vector<Parameter>& known) {
  std::vector<std::string> names;
  for (const Parameter& p : known) names.push_back(p.name);
  const std::string best = nearest_name(std::string(name), names);
  return best.empty() ? std::string() : fmt::format("; did you mean '{}'?", best);
}

// A hostile text may be megabytes long: messages quote its start only.
// A value as a message echoes it: invisible characters shown by code (shown_text), and a long one
// cut on a character's boundary before it is shown, so that no code is cut in two.
std::string shorten(std::string_view text) {
  if (text.size() <= 80) return shown_text(text);
  std::size_t cut = 60;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  const auto characters = std::count_if(text.begin(), text.end(),
                                        [](char b) { return (static_cast<unsigned char>(b) & 0xC0) != 0x80; });
  return fmt::format("{}... ({} characters)", shown_text(text.substr(0, cut)), characters);
}

std::string list_names(const std::vector<Parameter>& known) {
  std::string names;
  for (const Parameter& p : known) names += (names.empty() ? "" : ", ") + p.name;
  return names.empty() ? "(none)" : names;
}

// A recursive-descent parser that evaluates as it reads, or only collects the names it meets.
class ExpressionParser {
 public:
  ExpressionParser(std::string_view text, const std::vector<Parameter>& known, bool evaluate)
      : text_(text), known_(known), evaluate_(evaluate) {}

  double parse() {
    skip_space();
    if (pos_ == text_.size()) fail("it is empty");
    const double value = sum();
    skip_space();
    if (pos_ != text_.size()) fail(fmt::format("unexpected {}", describe_character(text_, pos_)));
    return value;
  }
  const std::vector<std::string>& names() const { return names_; }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    const std::string shown = shorten(text_);
    throw InputError(fmt::format("'{}' is not a valid expression: {} (column {}); write numbers, + - * / ^, "
                                 "parentheses, functions such as sin(x) or sqrt(x), pi, e and other parameters",
                                 shown, what, pos_ + 1));
  }
  // An operation of finite operands whose value is infinite (1/0, log(0), exp(1000)): refused
  // where the operation ends, saying which. (A NaN, sqrt(-1), is named by check_parameter_value.)
  // Only when evaluating: collecting names, every value is a placeholder 0.
  double defined(double value, const std::string& operation) const {
    if (!evaluate_ || !std::isinf(value)) return value;
    throw InputError(fmt::format("'{}' has no finite value: {} (column {}); write the value meant",
                                 shorten(text_), operation, pos_));
  }
  void skip_space() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool accept(std::string_view token) {
    skip_space();
    if (text_.substr(pos_, token.size()) != token) return false;
    pos_ += token.size();
    return true;
  }

  double sum() {
    double value = product();
    for (;;) {
      if (accept("+"))
        value = value + product();
      else if (accept("-"))
        value = value - product();
      else
        return value;
    }
  }
  double product() {
    double value = unary();
    for (;;) {
      skip_space();
      if (text_.substr(pos_, 2) == "**") return value;  // handled by power()
      if (accept("*"))
        value = value * unary();
      else if (accept("/")) {
        const double divisor = unary();
        if (evaluate_ && divisor == 0.0 && std::isfinite(value))
          defined(std::numeric_limits<double>::infinity(), "it divides by zero");
        value = defined(value / divisor, "a quotient overflows");
      }
      else
        return value;
    }
  }
  // Every level of nesting (a parenthesis, a call, a sign, an exponent) passes through here: the
  // same limit as the model file's other expressions (spec_builder.cpp), so that 20 000 nested
  // sqrt( or a run of minus signs is refused instead of overflowing the stack.
  double unary() {
    static constexpr int kMaxNesting = 256;
    struct Level {
      int& depth;
      ~Level() { --depth; }
    } level{++depth_};
    if (depth_ > kMaxNesting) fail(fmt::format("expression nested deeper than {} levels", kMaxNesting));
    if (accept("-")) return -unary();
    if (accept("+")) return unary();
    return power();
  }
  double power() {
    const double base = atom();
    if (!accept("^") && !accept("**")) return base;
    const double exponent = unary();
    if (evaluate_ && base == 0.0 && exponent == 0.0)
      throw InputError(fmt::format("'{}' contains 0^0, which is undefined: write 1 or 0 as meant", shorten(text_)));
    return defined(std::pow(base, exponent),
                   base == 0.0 && exponent < 0.0 ? "0 to a negative power divides by zero" : "a power overflows");
  }
  double atom() {
    skip_space();
    if (pos_ >= text_.size()) fail("it ends too early");
    const char ch = text_[pos_];
    if (accept("(")) {
      const double value = sum();
      if (!accept(")")) fail("a ')' is missing");
      return value;
    }
    if (std::isdigit(static_cast<unsigned char>(ch)) || ch == '.') return number();
    if (std::isalpha(static_cast<unsigned char>(ch)) || ch == '_') return name();
    fail(fmt::format("unexpected {}", describe_character(text_, pos_)));
  }
  double number() {
    const std::string rest(text_.substr(pos_));
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(rest.c_str(), &end);
    if (end == rest.c_str()) fail("a number is malformed");
    const std::string literal = rest.substr(0, static_cast<std::size_t>(end - rest.c_str()));
    if (errno == ERANGE && std::abs(value) > 1.0)
      throw InputError(fmt::format("the number {} is too large: it overflows a double (largest 1.8e308)", literal));
    if (errno == ERANGE || (value != 0.0 && std::abs(value) < DBL_MIN))
      throw InputError(fmt::format("the number {} is subnormal: below 2.2e-308 a double loses precision "
                                   "(down to none at 4.9e-324); write 0 or a normal number",
                                   literal));
    pos_ += static_cast<std::size_t>(end - rest.c_str());
    // 1e−3 with a pasted minus sign: strtod stops before the 'e'; the character at fault is the one after it.
    if (pos_ + 1 < text_.size() && (text_[pos_] == 'e' || text_[pos_] == 'E') &&
        static_cast<unsigned char>(text_[pos_ + 1]) >= 0x80) {
      ++pos_;
      fail(fmt::format("unexpected {}", describe_character(text_, pos_)));
    }
    return value;
  }
  double name() {
    const std::size_t start = pos_;
    while (pos_ < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '_')) ++pos_;
    const std::string word(text_.substr(start, pos_ - start));
    skip_space();
    if (pos_ < text_.size() && text_[pos_] == '(') return call(word);
    for (const Parameter& p : known_)
      if (p.name == word) {
        if (std::find(names_.begin(), names_.end(), word) == names_.end()) names_.push_back(word);
        return p.value;
      }
    if (word == "pi") return std::numbers::pi;
    if (word == "e") return std::numbers::e;
    pos_ = start;
    if (!evaluate_) {
      // Collecting names: an unknown one is reported by the caller, which knows the context.
      names_.push_back(word);
      pos_ = start + word.size();
      return 0.0;
    }
    throw InputError(fmt::format("'{}' uses '{}', which is neither a parameter ({}) nor a constant (pi, e){}", shorten(text_),
                                 word, list_names(known_), did_you_mean(word, known_)));
  }
  double call(const std::string& function) {
    accept("(");
    std::vector<double> args{sum()};
    while (accept(",")) args.push_back(sum());
    if (!accept(")")) fail("a ')' is missing after the arguments of " + function);
    using F = double (*)(double);
    static const std::pair<const char*, F> unary_functions[] = {
        {"sin", [](double x) { return std::sin(x); }},   {"cos", [](double x) { return std::cos(x); }},
        {"tan", [](double x) { return std::tan(x); }},   {"asin", [](double x) { return std::asin(x); }},
        {"acos", [](double x) { return std::acos(x); }}, {"atan", [](double x) { return std::atan(x); }},
        {"sinh", [](double x) { return std::sinh(x); }}, {"cosh", [](double x) { return std::cosh(x); }},
        {"tanh", [](double x) { return std::tanh(x); }}, {"exp", [](double x) { return std::exp(x); }},
        {"log", [](double x) { return std::log(x); }},   {"sqrt", [](double x) { return std::sqrt(x); }},
        {"abs", [](double x) { return std::abs(x); }}};
    if (function == "atan2") {
      if (args.size() != 2) fail("atan2 takes two arguments, atan2(y, x)");
      return std::atan2(args[0], args[1]);
    }
    for (const auto& [known, f] : unary_functions)
      if (function == known) {
        if (args.size() != 1) fail(function + " takes one argument");
        const double value = f(args[0]);
        return std::isfinite(args[0]) ? defined(value, fmt::format("{}({:g}) is infinite", function, args[0])) : value;
      }
    fail(fmt::format("'{}' is not a function this evaluator knows (sin, cos, tan, asin, acos, atan, atan2, sinh, "
                     "cosh, tanh, exp, log, sqrt, abs)",
                     function));
  }

  std::string_view text_;
  const std::vector<Parameter>& known_;
  bool evaluate_;
  std::size_t pos_ = 0;
  int depth_ = 0;
  std::vector<std::string> names_;
};

Parameter* find_in(std::vector<Parameter>& parameters, std::string_view name) {
  for (Parameter& p : parameters)
    if (p.name == name) return &p;
  return nullptr;
}

[[noreturn]] void unknown_parameter(std::string_view model, std::string_view name, const std::vector<Parameter>& known) {
  throw InputError(fmt::format("model '{}' has no parameter '{}'{} (its parameters: {})", model, name,
                               did_you_mean(name, known), list_names(known)));
}

}  // namespace

double calc_parameter_expression(std::string_view text, const std::vector<Parameter>& known) {
  ExpressionParser parser(text, known, true);
  return parser.parse();
}

std::vector<std::string> calc_expression_names(std::string_view text, const std::vector<Parameter>& known) {
  ExpressionParser parser(text, known, false);
  parser.parse();
  return parser.names();
}

void check_parameter_value(std::string_view name, double value) {
  if (std::isnan(value))
    throw InputError(fmt::format("parameter '{}' is not a number (NaN): its expression has no real value", name));
  const double largest = std::sqrt(DBL_MAX);
  if (std::abs(value) > largest)
    throw InputError(fmt::format("parameter '{}' = {:g} is too large: above {:.2g} in magnitude its square, the first "
                                 "product a term forms, overflows a double; rescale the units",
                                 name, value, largest));
  if (value != 0.0 && std::abs(value) < DBL_MIN)
    throw InputError(fmt::format("parameter '{}' = {:g} is subnormal: below 2.2e-308 a double loses precision; "
                                 "write 0 or a normal number",
                                 name, value));
}

void update_parameters(std::vector<Parameter>& parameters, std::string_view model) {
  // Depth first from each derived parameter: 0 not seen, 1 on the current path, 2 evaluated.
  std::vector<int> state(parameters.size(), 0);
  std::vector<std::size_t> path;
  const auto index_of = [&](const std::string& name) {
    for (std::size_t i = 0; i < parameters.size(); ++i)
      if (parameters[i].name == name) return i;
    return parameters.size();
  };
  std::function<void(std::size_t)> visit = [&](std::size_t i) {
    Parameter& p = parameters[i];
    if (state[i] == 2) return;
    if (p.expression.empty()) {
      state[i] = 2;
      return;
    }
    if (state[i] == 1) {
      std::string cycle;
      const auto from = std::find(path.begin(), path.end(), i);
      for (auto it = from; it != path.end(); ++it)
        cycle += fmt::format("{} = \"{}\", ", parameters[*it].name, parameters[*it].expression);
      cycle += p.name;
      throw InputError(fmt::format("model '{}': the definitions of the parameters form a cycle: {}; give one of them a "
                                   "number",
                                   model, cycle));
    }
    state[i] = 1;
    path.push_back(i);
    std::vector<std::string> used;
    try {
      used = calc_expression_names(p.expression, parameters);
    } catch (const InputError& e) {
      throw InputError(fmt::format("model '{}': parameter '{}': {}", model, p.name, e.what()));
    }
    for (const std::string& name : used) {
      const std::size_t j = index_of(name);
      if (j == parameters.size() && name != "pi" && name != "e")
        throw InputError(fmt::format("model '{}': parameter '{}' = \"{}\" uses '{}', which is neither a parameter "
                                     "({}) nor a constant (pi, e){}",
                                     model, p.name, p.expression, name, list_names(parameters),
                                     did_you_mean(name, parameters)));
      if (j < parameters.size()) visit(j);
    }
    double value = 0.0;
    try {
      value = calc_parameter_expression(p.expression, parameters);
      check_parameter_value(p.name, value);
    } catch (const InputError& e) {
      throw InputError(fmt::format("model '{}': parameter '{}' = \"{}\": {}", model, p.name, p.expression, e.what()));
    }
    p.value = value;
    path.pop_back();
    state[i] = 2;
  };
  for (std::size_t i = 0; i < parameters.size(); ++i) visit(i);
}

void set_parameter_expression(std::vector<Parameter>& parameters, std::string_view name, std::string_view expression,
                              std::string_view model) {
  Parameter* p = find_in(parameters, name);
  if (p == nullptr) unknown_parameter(model, name, parameters);
  const std::vector<std::string> used = calc_expression_names(expression, parameters);
  std::vector<Parameter> changed = parameters;
  Parameter& q = *find_in(changed, name);
  bool uses_parameters = false;
  for (const std::string& u : used) uses_parameters = uses_parameters || find_in(changed, u) != nullptr;
  if (uses_parameters) {
    q.expression = std::string(expression);
  } else {
    // A constant expression (an unknown name is reported by the evaluation).
    const double value = calc_parameter_expression(expression, parameters);
    check_parameter_value(name, value);
    q.value = value;
    q.expression.clear();
  }
  update_parameters(changed, model);
  parameters = std::move(changed);
}

std::pair<std::string, std::string> split_parameter_set(std::string_view set) {
  const std::size_t eq = set.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError(fmt::format("--set '{}': write it as NAME=VALUE or NAME=EXPRESSION, e.g. --set a=0.3 or "
                                 "--set alpha=pi/6",
                                 shorten(set)));
  return {std::string(set.substr(0, eq)), std::string(set.substr(eq + 1))};
}

void apply_parameter_sets(std::vector<Parameter>& parameters, const std::vector<std::string>& sets,
                          std::string_view model) {
  for (const std::string& set : sets) {
    auto [name, expression] = split_parameter_set(set);
    while (!name.empty() && std::isspace(static_cast<unsigned char>(name.back()))) name.pop_back();
    try {
      set_parameter_expression(parameters, name, expression, model);
    } catch (const InputError& e) {
      throw InputError(fmt::format("--set {}: {}", shorten(set), e.what()));
    }
  }
}

const Parameter& find_parameter(const Model& model, std::string_view name) {
  for (const Parameter& p : model.parameters)
    if (p.name == name) return p;
  unknown_parameter(model.name, name, model.parameters);
}

double get_parameter(const Model& model, std::string_view name) { return find_parameter(model, name).value; }

namespace {

// `model` with `parameters` (already checked and updated) bound into a new evaluator; commits only
// when every step succeeded.
void bind(Model& model, std::vector<Parameter> parameters) {
  if (!model.evaluator) throw ModelError(fmt::format("model '{}': it has no evaluator", model.name));
  std::vector<double> values;
  values.reserve(parameters.size());
  for (const Parameter& p : parameters) values.push_back(p.value);
  check_positive_values(model, parameters);
  std::shared_ptr<const Evaluator> evaluator = model.evaluator->with_parameters(values.data(), values.size());
  if (!evaluator)
    throw InputError(fmt::format("model '{}': its evaluator computes with fixed parameters and cannot take new values "
                                 "(code generated by an older nhdyn? regenerate it)",
                                 model.name));
  Vector q0 = model.q0, v0 = model.v0;
  if (evaluator->has_initial_state()) {
    std::vector<double> scratch(evaluator->scratch_size());
    evaluator->initial_state(scratch.data(), q0.data(), v0.data());
  }
  model.parameters = std::move(parameters);
  model.evaluator = std::move(evaluator);
  model.q0 = std::move(q0);
  model.v0 = std::move(v0);
}

}  // namespace

void check_positive_values(const Model& model, const std::vector<Parameter>& parameters) {
  if (model.positive_values.empty()) return;
  std::vector<double> values;
  values.reserve(parameters.size());
  for (const Parameter& p : parameters) values.push_back(p.value);
  std::vector<double> checked;
  for (const PositiveValue& check : model.positive_values) {
    const Tape tape = check.value.bind(values.data(), values.size());
    std::vector<double> registers(static_cast<std::size_t>(tape.registers()));
    double value = 0.0;
    tape.run(model.t0, model.q0.data(), model.v0.data(), registers.data(), &value);
    checked.push_back(value);
    if (value > 0.0 && std::isfinite(value)) continue;
    throw InputError(fmt::format("{}{}: \"{}\" must be positive, but it is {:.6g} with the parameters set; give "
                                 "values that keep it positive",
                                 check.where.empty() ? "" : check.where + ": ", check.what, check.text, value));
  }
  // The sizes of one shape, in a row of positive_values: the smallest against the largest.
  for (std::size_t first = 0; first < checked.size();) {
    const std::string& group = model.positive_values[first].group;
    std::size_t end = first + 1;
    while (end < checked.size() && !group.empty() && model.positive_values[end].group == group) ++end;
    const auto [smallest, largest] = std::minmax_element(checked.begin() + static_cast<std::ptrdiff_t>(first),
                                                         checked.begin() + static_cast<std::ptrdiff_t>(end));
    if (*largest > kLargestSizeRatio * *smallest) {
      const PositiveValue& a = model.positive_values[static_cast<std::size_t>(smallest - checked.begin())];
      const PositiveValue& b = model.positive_values[static_cast<std::size_t>(largest - checked.begin())];
      throw InputError(fmt::format(
          "{}{}: its sizes \"{}\" = {:.6g} and \"{}\" = {:.6g} are more than {:g} apart: to double precision the "
          "shape is flat (or a needle), where its contact point is not defined; model a flat body as a disk, or give "
          "sizes within {:g} of each other",
          a.where.empty() ? "" : a.where + ": ", group, a.text, *smallest, b.text, *largest, kLargestSizeRatio,
          kLargestSizeRatio));
    }
    first = end;
  }
}

void set_parameter(Model& model, std::string_view name, double value) {
  std::vector<Parameter> parameters = model.parameters;
  Parameter* p = find_in(parameters, name);
  if (p == nullptr) unknown_parameter(model.name, name, parameters);
  check_parameter_value(name, value);
  p->value = value;
  p->expression.clear();
  update_parameters(parameters, model.name);
  bind(model, std::move(parameters));
}

void set_parameter_expression(Model& model, std::string_view name, std::string_view expression) {
  std::vector<Parameter> parameters = model.parameters;
  set_parameter_expression(parameters, name, expression, model.name);
  bind(model, std::move(parameters));
}

void apply_parameter_sets(Model& model, const std::vector<std::string>& sets) {
  if (sets.empty()) return;
  std::vector<Parameter> parameters = model.parameters;
  apply_parameter_sets(parameters, sets, model.name);
  bind(model, std::move(parameters));
}

void rebind_parameters(Model& model) {
  std::vector<Parameter> parameters = model.parameters;
  update_parameters(parameters, model.name);
  bind(model, std::move(parameters));
}

}  // namespace nhdyn
