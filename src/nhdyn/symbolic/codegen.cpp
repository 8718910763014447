#include "nhdyn/symbolic/codegen.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/tape.hpp"
#include "nhdyn/model/detail/tape_printer.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn::symbolic {
namespace {

constexpr const char* kKeywords[] = {
    "alignas",   "alignof",      "and",          "and_eq",      "asm",        "auto",         "bitand",
    "bitor",     "bool",         "break",        "case",        "catch",      "char",         "char8_t",
    "char16_t",  "char32_t",     "class",        "compl",       "concept",    "const",        "consteval",
    "constexpr", "constinit",    "const_cast",   "continue",    "co_await",   "co_return",    "co_yield",
    "decltype",  "default",      "delete",       "do",          "double",     "dynamic_cast", "else",
    "enum",      "explicit",     "export",       "extern",      "false",      "float",        "for",
    "friend",    "goto",         "if",           "inline",      "int",        "long",         "mutable",
    "namespace", "new",          "noexcept",     "not",         "not_eq",     "nullptr",      "operator",
    "or",        "or_eq",        "private",      "protected",   "public",     "register",     "reinterpret_cast",
    "requires",  "return",       "short",        "signed",      "sizeof",     "static",       "static_assert",
    "static_cast", "struct",     "switch",       "template",    "this",       "thread_local", "throw",
    "true",      "try",          "typedef",      "typeid",      "typename",   "union",        "unsigned",
    "using",     "virtual",      "void",         "volatile",    "wchar_t",    "while",        "xor",
    "xor_eq"};

// Macros (and errno) of the standard headers a generated header includes or is included beside
// (<cmath>, <cstdio>, <cerrno>, <cstddef>, <climits>, <cassert>, POSIX's M_PI): a field so named
// would be replaced by the preprocessor and the header would not compile.
const char* const kMacros[] = {
    "INFINITY", "NAN", "HUGE_VAL", "HUGE_VALF", "HUGE_VALL", "EOF", "errno", "NULL", "assert", "EDOM", "ERANGE",
    "EILSEQ", "FP_NAN", "FP_INFINITE", "FP_ZERO", "FP_SUBNORMAL", "FP_NORMAL", "FP_ILOGB0", "FP_ILOGBNAN",
    "FP_FAST_FMA", "MATH_ERRNO", "MATH_ERREXCEPT", "math_errhandling", "stdin", "stdout", "stderr", "BUFSIZ",
    "FILENAME_MAX", "SEEK_SET", "SEEK_CUR", "SEEK_END", "offsetof", "CHAR_BIT", "INT_MAX", "INT_MIN", "LONG_MAX",
    "LONG_MIN", "UINT_MAX", "M_PI", "M_E", "M_SQRT2", "M_LN2", "EXIT_SUCCESS", "EXIT_FAILURE", "RAND_MAX",
    "TRUE", "FALSE", "DBL_MAX", "DBL_MIN", "DBL_EPSILON", "unix", "linux"};

bool is_keyword(const std::string& s) {
  for (const char* k : kKeywords)
    if (s == k) return true;
  for (const char* k : kMacros)
    if (s == k) return true;
  return false;
}

bool is_identifier(const std::string& s) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  for (char ch : s)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_')) return false;
  // Names with "__" or "_X" are reserved to the implementation.
  if (s.find("__") != std::string::npos) return false;
  if (s[0] == '_' && s.size() > 1 && std::isupper(static_cast<unsigned char>(s[1]))) return false;
  return !is_keyword(s);
}

std::string camel_case(const std::string& identifier) {
  std::string out;
  bool upper = true;
  for (char ch : identifier) {
    if (ch == '_') {
      upper = true;
      continue;
    }
    out += upper ? static_cast<char>(std::toupper(static_cast<unsigned char>(ch))) : ch;
    upper = false;
  }
  return out;
}

// A double as a C++ literal that reads back to the same value ({:.17g}), always of type double.
std::string literal(double x) {
  if (std::isnan(x)) return "NAN";
  if (std::isinf(x)) return x > 0 ? "HUGE_VAL" : "(-HUGE_VAL)";
  std::string s = fmt::format("{:.17g}", x);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return x < 0 || std::signbit(x) ? "(" + s + ")" : s;
}

// A C++ string literal; bytes outside printable ASCII as octal escapes (UTF-8 survives as bytes).
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (unsigned char ch : s) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += static_cast<char>(ch);
    } else if (ch == '\n') {
      out += "\\n";
    } else if (ch < 0x20 || ch >= 0x7f) {
      out += fmt::format("\\{:03o}", static_cast<unsigned>(ch));
    } else {
      out += static_cast<char>(ch);
    }
  }
  return out + "\"";
}

// A comment line safe to print (no line breaks, no "*/").
std::string comment_text(const std::string& s) {
  std::string out;
  for (char ch : s) out += (ch == '\n' || ch == '\r') ? ' ' : ch;
  return out;
}

// How codegen spells a tape (model/detail/tape_printer.hpp): its parameter stage is computed once
// per parameter change, in the evaluator's constructor, into members named <prefix>rN_; the calls
// compute the rest. Parameters read as p_.<field>; constants are declared where read, with
// literals that read back to the same value.
TapePrintStyle codegen_style(const std::string& prefix, const std::vector<std::string>& fields) {
  TapePrintStyle style;
  style.literal = literal;
  style.parameter = [fields](int i) { return "p_." + fields[static_cast<std::size_t>(i)]; };
  style.stored = [prefix](int r, int) { return prefix + "r" + std::to_string(r) + "_"; };
  style.declare_constants = true;
  return style;
}

// hoist = false: no stage, every instruction in the call (a tape that runs once anyway).
TapePrinter make_printer(const Tape& tape, const std::string& prefix, const std::vector<std::string>& fields,
                            bool hoist = true) {
  return TapePrinter(tape, codegen_style(prefix, fields), hoist);
}

// The declarations of a tape's stage members.
std::string members(const TapePrinter& printer) {
  std::string out;
  for (const std::pair<int, int>& stored : printer.stored_registers())
    out += fmt::format("  double {} = 0.0;\n", printer.stored(stored.first));
  return out;
}

struct Body {
  std::string code;
  bool reads_t = false, reads_q = false, reads_v = false;
};

// The statements of a tape's call, then `sink(i, register)` for each output i.
Body print_body(const TapePrinter& printer, const std::function<std::string(int, const std::string&)>& sink) {
  const Tape& tape = printer.tape();
  Body body;
  body.reads_t = tape.reads_time();
  body.reads_q = tape.reads_coordinates();
  body.reads_v = tape.reads_velocities();
  body.code = printer.statements(false, "    ");
  for (int i = 0; i < tape.outputs(); ++i) body.code += sink(i, printer.output(i));
  return body;
}

std::string parameter(bool used, const char* declaration, const char* name) {
  return used ? fmt::format("{} {}", declaration, name) : fmt::format("{} /*{}*/", declaration, name);
}

bool uses_powi(const ModelTapes& p) {
  const auto in = [](const Tape& tape) { return tape.count(Op::powi) > 0; };
  return in(p.terms) || (p.complement && in(*p.complement)) || in(p.position_residual) ||
         in(p.velocity_residual) || (p.energy && in(*p.energy)) || (p.initial_state && in(*p.initial_state));
}

// The fields of the parameter struct: each parameter's name as a C++ identifier, made unique.
std::vector<std::string> parameter_fields(const std::vector<Parameter>& parameters) {
  std::vector<std::string> fields;
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    std::string field = make_identifier(parameters[i].name);
    if (field == "p_" || std::find(fields.begin(), fields.end(), field) != fields.end())
      field += "_" + std::to_string(i);
    fields.push_back(field);
  }
  return fields;
}

}  // namespace

std::string make_identifier(const std::string& name) {
  std::string out;
  for (char ch : name) {
    const bool keep = std::isalnum(static_cast<unsigned char>(ch)) && static_cast<unsigned char>(ch) < 0x80;
    if (keep) {
      out += ch;
    } else if (!out.empty() && out.back() != '_') {
      out += '_';
    }
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  if (out.empty()) return "model";
  if (std::isdigit(static_cast<unsigned char>(out[0]))) out = "model_" + out;
  if (is_keyword(out)) out += '_';
  return out;
}

namespace {

// The namespaces of options.namespace_name, outermost first ("a::b" -> {"a", "b"}); InputError for
// a name that is not '::'-separated identifiers, or std.
std::vector<std::string> split_namespace(const CodegenOptions& options) {
  std::vector<std::string> namespaces;
  if (!options.namespace_name.empty()) {
    std::string rest = options.namespace_name;
    if (rest.rfind("::", 0) == 0) rest = rest.substr(2);
    for (std::size_t pos; (pos = rest.find("::")) != std::string::npos; rest = rest.substr(pos + 2))
      namespaces.push_back(rest.substr(0, pos));
    namespaces.push_back(rest);
    for (const std::string& part : namespaces)
      if (!is_identifier(part))
        throw InputError(fmt::format("codegen: the namespace '{}' is not '::'-separated C++ identifiers",
                                     options.namespace_name));
    if (namespaces.front() == "std") throw InputError("codegen: the generated code may not go into namespace std");
    // Inside a::std, the generated code's std::shared_ptr would name a::std::shared_ptr, and a
    // keyword is no name at all: neither header compiled.
    for (const std::string& part : namespaces)
      if (part == "std" || is_keyword(part))
        throw InputError(fmt::format("codegen: the namespace '{}' has a part '{}' that {}; choose another name",
                                     options.namespace_name, part,
                                     part == "std" ? "would hide the standard library the generated code calls"
                                                   : "is a C++ keyword"));
  }
  return namespaces;
}

// The names the generated code gives its model's parts, and the printers of its tapes.
struct Generated {
  Generated(const Model& model_, const ModelTapes& tapes_, const std::string& id_)
      : model(model_),
        tapes(tapes_),
        id(id_),
        cls(camel_case(id_) + "Evaluator"),
        parameters_struct(camel_case(id_) + "Parameters"),
        fields(parameter_fields(model_.parameters)),
        terms_printer(make_printer(tapes_.terms, "terms_", fields)),
        complement_printer(tapes_.complement
                               ? std::optional<TapePrinter>(make_printer(*tapes_.complement, "complement_", fields))
                               : std::nullopt),
        phi_printer(make_printer(tapes_.position_residual, "phi_", fields)),
        f_printer(make_printer(tapes_.velocity_residual, "f_", fields)),
        energy_printer(tapes_.energy
                           ? std::optional<TapePrinter>(make_printer(*tapes_.energy, "energy_", fields))
                           : std::nullopt),
        initial_printer(tapes_.initial_state ? std::optional<TapePrinter>(make_printer(
                                                      *tapes_.initial_state, "initial_", fields, false))
                                                : std::nullopt) {}

  std::string q_name(int i) const { return comment_text(model.coordinates[static_cast<std::size_t>(i)]); }
  std::string c_name(int i) const { return comment_text(model.constraints[static_cast<std::size_t>(i)].name); }

  const Model& model;
  const ModelTapes& tapes;
  const std::string id;
  const std::string cls;
  const std::string parameters_struct;
  const std::vector<std::string> fields;
  const TapePrinter terms_printer;
  const std::optional<TapePrinter> complement_printer;
  const TapePrinter phi_printer;
  const TapePrinter f_printer;
  const std::optional<TapePrinter> energy_printer;
  const std::optional<TapePrinter> initial_printer;
};

// The file's opening comment (what it was made from, its operation counts) and its includes.
std::string file_head(const Generated& g) {
  const Model& model = g.model;
  const ModelTapes& tapes = g.tapes;
  std::string out;
  out += fmt::format("// Generated by nhdyn (symbolic/codegen.hpp) from the model '{}'. Do not edit: regenerate.\n",
                     comment_text(model.name));
  if (!model.description.empty()) out += fmt::format("// {}\n", comment_text(model.description));
  const auto operations = [](const Tape& p) { return p.code().size() - static_cast<std::size_t>(p.count(Op::nop)); };
  out += fmt::format("// Operations: terms {}, complement {}, residuals {} + {}, energy {}.\n",
                     operations(tapes.terms), tapes.complement ? operations(*tapes.complement) : 0,
                     operations(tapes.position_residual), operations(tapes.velocity_residual),
                     tapes.energy ? operations(*tapes.energy) : 0);
  out += "#pragma once\n\n#include <cmath>\n#include <cstddef>\n#include <memory>\n\n";
  out += "#include \"nhdyn/model/evaluator.hpp\"\n#include \"nhdyn/model/model.hpp\"\n\n";
  return out;
}

// The parameter struct, with the file's values as defaults.
std::string parameters_struct_code(const Generated& g) {
  const Model& model = g.model;
  std::string out;
  out += "// The model's parameters, with the values of its file as defaults. A derived parameter (one\n";
  out += "// defined by an expression in the others) is a field too: set_parameter on the Model\n";
  out += "// (nhdyn/model/parameters.hpp) re-evaluates it, a struct filled by hand does not.\n";
  out += fmt::format("struct {} {{\n", g.parameters_struct);
  for (std::size_t i = 0; i < model.parameters.size(); ++i) {
    const Parameter& p = model.parameters[i];
    std::string note = p.unit.empty() ? "" : fmt::format("[{}]", comment_text(p.unit));
    if (!p.expression.empty()) note += fmt::format("{}= {}", note.empty() ? "" : " ", comment_text(p.expression));
    out += fmt::format("  double {} = {};{}\n", g.fields[i], literal(p.value), note.empty() ? "" : "  // " + note);
  }
  out += "};\n\n";
  return out;
}

// The evaluator class up to its kernels: the constructor, the parameters, the initial state.
std::string evaluator_head_code(const Generated& g) {
  const Model& model = g.model;
  const int n = model.n();
  std::string out;
  out += fmt::format("class {} final : public ::nhdyn::Evaluator {{\n public:\n", g.cls);
  // The constructor computes the parameter stage of every tape once.
  {
    std::string stage;
    // One block per tape: each numbers its registers from its own inputs.
    const auto add_stage = [&stage](const TapePrinter& printer) {
      const std::string statements = printer.statements(true, "      ");
      if (!statements.empty()) stage += "    {\n" + statements + "    }\n";
    };
    add_stage(g.terms_printer);
    if (g.complement_printer) add_stage(*g.complement_printer);
    add_stage(g.phi_printer);
    add_stage(g.f_printer);
    if (g.energy_printer) add_stage(*g.energy_printer);
    out += fmt::format("  explicit {}(const {}& p = {{}}) : p_(p) {{", g.cls, g.parameters_struct);
    out += stage.empty() ? "}\n" : "\n" + stage + "  }\n";
  }
  out += fmt::format("  const {}& parameters() const {{ return p_; }}\n\n", g.parameters_struct);
  out += "  std::shared_ptr<const ::nhdyn::Evaluator> with_parameters(const double* values, std::size_t count) const "
         "override {\n";
  out += fmt::format("    if (count != {}) return nullptr;\n", model.parameters.size());
  out += fmt::format("    {} p;\n", g.parameters_struct);
  for (std::size_t i = 0; i < g.fields.size(); ++i) out += fmt::format("    p.{} = values[{}];\n", g.fields[i], i);
  if (g.fields.empty()) out += "    (void)values;\n";
  out += fmt::format("    return std::make_shared<{}>(p);\n  }}\n", g.cls);
  if (g.initial_printer) {
    const Body body = print_body(*g.initial_printer, [&](int i, const std::string& r) {
      return i < n ? fmt::format("    q0[{}] = {};\n", i, r) : fmt::format("    v0[{}] = {};\n", i - n, r);
    });
    out += "  bool has_initial_state() const override { return true; }\n";
    out += "  void initial_state(double* /*scratch*/, double* q0, double* v0) const override {\n";
    out += body.code + "  }\n";
  }
  out += "\n";
  return out;
}

// The evaluator's kernels: terms, complement, residuals, energy.
std::string evaluator_kernels_code(const Generated& g) {
  const Model& model = g.model;
  const ModelTapes& tapes = g.tapes;
  const int n = model.n(), s = model.s();
  const auto q_name = [&](int i) { return g.q_name(i); };
  const auto c_name = [&](int i) { return g.c_name(i); };
  std::string out;
  // terms
  {
    const Body body = print_body(g.terms_printer, [&](int i, const std::string& r) {
      const int nn = n * n;
      if (i < nn) return fmt::format("    out.A[{}] = {};  // A({}, {})\n", i, r, q_name(i % n), q_name(i / n));
      i -= nn;
      if (i < n) return fmt::format("    out.Q[{}] = {};  // Q({})\n", i, r, q_name(i));
      i -= n;
      if (i < n) return fmt::format("    out.G[{}] = {};  // G({})\n", i, r, q_name(i));
      i -= n;
      if (i < s * n) return fmt::format("    out.b[{}] = {};  // b({}, {})\n", i, r, c_name(i % s), q_name(i / s));
      i -= s * n;
      return fmt::format("    out.b0[{}] = {};  // b0({})\n", i, r, c_name(i));
    });
    out += fmt::format("  void terms({}, {}, {}, double* /*scratch*/, const ::nhdyn::TermsOut& out) const override {{\n",
                       parameter(body.reads_t, "double", "t"), parameter(body.reads_q, "const double*", "q"),
                       parameter(body.reads_v, "const double*", "v"));
    out += body.code + "  }\n";
  }
  // complement
  if (tapes.complement) {
    const int k = n - s;
    const Body body = print_body(*g.complement_printer, [&](int i, const std::string& r) {
      return fmt::format("    D[{}] = {};  // D({}, {})\n", i, r, i % k + 1, q_name(i / k));
    });
    out += "\n  bool has_complement() const override { return true; }\n";
    out += fmt::format("  void complement({}, {}, {}, double* /*scratch*/, double* D) const override {{\n",
                       parameter(body.reads_t, "double", "t"), parameter(body.reads_q, "const double*", "q"),
                       parameter(body.reads_v, "const double*", "v"));
    out += body.code + "  }\n";
  }
  // residuals
  if (tapes.position_residual.outputs() > 0) {
    const Body body = print_body(g.phi_printer, [&](int i, const std::string& r) {
      return fmt::format("    phi[{}] = {};\n", i, r);
    });
    out += fmt::format("\n  void position_residual({}, {}, double* /*scratch*/, double* phi) const override {{\n",
                       parameter(body.reads_t, "double", "t"), parameter(body.reads_q, "const double*", "q"));
    out += body.code + "  }\n";
  }
  if (tapes.velocity_residual.outputs() > 0) {
    const Body body = print_body(g.f_printer, [&](int i, const std::string& r) {
      return fmt::format("    f[{}] = {};\n", i, r);
    });
    out += fmt::format("\n  void velocity_residual({}, {}, {}, double* /*scratch*/, double* f) const override {{\n",
                       parameter(body.reads_t, "double", "t"), parameter(body.reads_q, "const double*", "q"),
                       parameter(body.reads_v, "const double*", "v"));
    out += body.code + "  }\n";
  }
  // energy
  if (tapes.energy) {
    const Body body = print_body(*g.energy_printer, [&](int, const std::string& r) {
      return fmt::format("    return {};\n", r);
    });
    out += "\n  bool has_energy() const override { return true; }\n";
    out += fmt::format("  double energy({}, {}, {}, double* /*scratch*/) const override {{\n",
                       parameter(body.reads_t, "double", "t"), parameter(body.reads_q, "const double*", "q"),
                       parameter(body.reads_v, "const double*", "v"));
    out += body.code + "  }\n";
  }
  return out;
}

// The evaluator's members: the parameters, each tape's parameter stage, powi if used.
std::string evaluator_members_code(const Generated& g) {
  const ModelTapes& tapes = g.tapes;
  std::string out;
  out += "\n private:\n";
  out += fmt::format("  {} p_;\n", g.parameters_struct);
  out += members(g.terms_printer);
  if (g.complement_printer) out += members(*g.complement_printer);
  out += members(g.phi_printer) + members(g.f_printer);
  if (g.energy_printer) out += members(*g.energy_printer);
  if (uses_powi(tapes)) {
    // The interpreter's algorithm (model/tape.cpp), so that both round alike.
    out += "  // a^n by repeated squaring, n != 0.\n";
    out += "  static double powi(double a, int n) {\n";
    out += "    unsigned m = n < 0 ? 0u - static_cast<unsigned>(n) : static_cast<unsigned>(n);\n";
    out += "    double result = 1.0;\n    double base = a;\n";
    out += "    for (;;) {\n      if (m & 1u) result *= base;\n      m >>= 1u;\n      if (m == 0u) break;\n";
    out += "      base *= base;\n    }\n    return n < 0 ? 1.0 / result : result;\n  }\n";
  }
  out += "};\n\n";
  return out;
}

// make_<id>_model: the Model with the generated evaluator.
std::string make_model_code(const Generated& g) {
  const Model& model = g.model;
  const ModelTapes& tapes = g.tapes;
  const int n = model.n();
  const std::string& id = g.id;
  std::string out;
  out += fmt::format("inline ::nhdyn::Model make_{}_model(const {}& p = {{}}) {{\n", id, g.parameters_struct);
  out += "  ::nhdyn::Model model;\n";
  out += fmt::format("  model.name = {};\n", quoted(model.name));
  out += fmt::format("  model.description = {};\n", quoted(model.description));
  out += "  model.coordinates = {";
  for (int i = 0; i < n; ++i) out += (i ? ", " : "") + quoted(model.coordinates[static_cast<std::size_t>(i)]);
  out += "};\n";
  for (const Constraint& c : model.constraints)
    out += fmt::format("  model.constraints.push_back({{{}, ::nhdyn::ConstraintLevel::{}, {}}});\n", quoted(c.name),
                       level_name(c.level), quoted(c.expression));
  for (std::size_t i = 0; i < model.parameters.size(); ++i) {
    const Parameter& p = model.parameters[i];
    out += fmt::format("  model.parameters.push_back({{{}, p.{}, {}, {}}});\n", quoted(p.name), g.fields[i],
                       quoted(p.unit), quoted(p.expression));
  }
  out += fmt::format("  model.t0 = {};\n", literal(model.t0));
  out += fmt::format("  model.q0 = ::nhdyn::Vector({});\n  model.v0 = ::nhdyn::Vector({});\n", n, n);
  for (int i = 0; i < n; ++i) out += fmt::format("  model.q0[{}] = {};\n", i, literal(model.q0[i]));
  for (int i = 0; i < n; ++i) out += fmt::format("  model.v0[{}] = {};\n", i, literal(model.v0[i]));
  out += fmt::format("  model.defaults = ::nhdyn::SimulationDefaults{{{}, {}}};\n", literal(model.defaults.t_end),
                     literal(model.defaults.output_step));
  if (model.path) out += fmt::format("  model.path = ::nhdyn::PlanarPath{{{}, {}}};\n", model.path->x, model.path->y);
  out += fmt::format("  const auto evaluator = std::make_shared<{}>(p);\n", g.cls);
  if (tapes.initial_state) out += "  evaluator->initial_state(nullptr, model.q0.data(), model.v0.data());\n";
  out += "  model.evaluator = evaluator;\n";
  out += "  return model;\n}\n";
  return out;
}

}  // namespace

std::string generate_code(const Spec& spec, const Derivation& derivation, const CodegenOptions& options) {
  const std::string id = options.identifier.empty() ? make_identifier(spec.name) : options.identifier;
  if (!is_identifier(id))
    throw InputError(fmt::format("codegen: '{}' is not a valid C++ identifier for the generated names", id));
  const std::vector<std::string> namespaces = split_namespace(options);

  // The generated code writes every entry of A and b (dense outputs).
  const Model model = compile_model(spec, derivation, CompileOptions{TermsLayout::dense});
  require_fewer_constraints(model, "the generated code");
  if (model.m() > 0)
    throw InputError(fmt::format("codegen: model '{}' has programs ([[programs]]), which generated code does not "
                                 "carry yet; run it through the interpreted evaluator (nhdyn simulate)",
                                 model.name));
  const auto* evaluator = dynamic_cast<const TapeEvaluator*>(model.evaluator.get());
  if (evaluator == nullptr) throw std::logic_error("generate_code: compile_model did not make a TapeEvaluator");
  const Generated g(model, evaluator->parametric_tapes(), id);

  std::string out = file_head(g);
  for (const std::string& part : namespaces) out += fmt::format("namespace {} {{\n", part);
  if (!namespaces.empty()) out += "\n";
  out += parameters_struct_code(g);
  out += evaluator_head_code(g);
  out += evaluator_kernels_code(g);
  out += evaluator_members_code(g);
  out += make_model_code(g);
  if (!namespaces.empty()) out += "\n";
  for (auto it = namespaces.rbegin(); it != namespaces.rend(); ++it) out += fmt::format("}}  // namespace {}\n", *it);
  return out;
}

}  // namespace nhdyn::symbolic
