#include "nhdyn/jit/source.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace nhdyn::jit {
namespace {

// A double as an exact C++ literal (hexadecimal floating point).
std::string literal(double x) {
  if (std::isnan(x)) return "__builtin_nan(\"\")";
  if (std::isinf(x)) return x > 0 ? "__builtin_inf()" : "(-__builtin_inf())";
  return x < 0 || std::signbit(x) ? fmt::format("({:a})", x) : fmt::format("{:a}", x);
}

class Printer {
 public:
  Printer(const Program& p) : program_(p) {
    const std::size_t registers = static_cast<std::size_t>(p.registers());
    stage_.assign(registers, 0);
    constant_.assign(registers, 0);
    slot_.assign(registers, -1);
    const std::vector<Instruction>& code = p.code();
    const std::size_t inputs = static_cast<std::size_t>(p.inputs());
    std::vector<char> read_by_call(registers, 0);
    for (std::size_t i = 0; i < code.size(); ++i) {
      const Instruction& in = code[i];
      const std::size_t r = inputs + i;
      if (in.op == Op::nop) {
        stage_[r] = stage_[r - 1];
        continue;
      }
      if (in.op == Op::constant) {
        constant_[r] = 1;
        continue;
      }
      if (in.op == Op::parameter) {
        stage_[r] = 1;
        continue;
      }
      // Computed once when every operand is a constant or a stage register.
      const int operands[3] = {in.a, in.b, in.c};
      const int count = operand_count(in.op);
      bool only = count > 0;
      for (int k = 0; k < count; ++k) {
        const std::size_t o = static_cast<std::size_t>(operands[k]);
        only = only && (stage_[o] || constant_[o]);
      }
      stage_[r] = only;
    }
    for (std::size_t i = 0; i < code.size(); ++i) {
      const Instruction& in = code[i];
      const std::size_t r = inputs + i;
      if (in.op == Op::nop || stage_[r]) continue;
      const int operands[3] = {in.a, in.b, in.c};
      for (int k = 0; k < operand_count(in.op); ++k) read_by_call[static_cast<std::size_t>(operands[k])] = 1;
    }
    for (const Output& o : p.output_list())
      if (o.reg >= 0) read_by_call[static_cast<std::size_t>(o.reg)] = 1;
    for (std::size_t r = 0; r < registers; ++r)
      if (stage_[r] && read_by_call[r]) slot_[r] = stage_size_++;
  }

  int stage_size() const { return stage_size_; }

  // The stage: every stage instruction, then the registers a call reads stored in m.
  std::string stage_body() const {
    std::string out;
    for_each(true, out);
    for (std::size_t r = 0; r < slot_.size(); ++r)
      if (slot_[r] >= 0) out += fmt::format("  m[{}] = r{};\n", slot_[r], r);
    return out;
  }

  // The call: every other instruction, then the outputs through `destination(j)`.
  template <class Destination>
  std::string call_body(Destination destination) const {
    std::string out;
    for_each(false, out);
    const std::vector<Output>& outputs = program_.output_list();
    for (std::size_t j = 0; j < outputs.size(); ++j) {
      const Output& o = outputs[j];
      out += fmt::format("  {} = {};\n", destination(static_cast<int>(j)),
                         o.reg < 0 ? literal(o.value) : reg(o.reg, false));
    }
    return out;
  }

 private:
  void for_each(bool stage, std::string& out) const {
    const std::vector<Instruction>& code = program_.code();
    const std::size_t inputs = static_cast<std::size_t>(program_.inputs());
    for (std::size_t i = 0; i < code.size(); ++i) {
      const Instruction& in = code[i];
      const std::size_t r = inputs + i;
      if (in.op == Op::nop || in.op == Op::constant || static_cast<bool>(stage_[r]) != stage) continue;
      if (in.op == Op::sincos) {
        const std::string a = reg(in.a, stage);
        out += fmt::format("  const double r{} = std::sin({});\n  const double r{} = std::cos({});\n", r, a, r + 1, a);
        continue;
      }
      out += fmt::format("  const double r{} = {};\n", r, expression(in, stage));
    }
  }

  // A register as C++: inputs by name, constants as literals, stage registers in a call from m.
  std::string reg(int r, bool in_stage) const {
    const int n = program_.coordinates();
    const std::size_t at = static_cast<std::size_t>(r);
    if (r == Program::time_register()) return "t";
    if (r <= n) return fmt::format("q[{}]", r - 1);
    if (r <= 2 * n) return fmt::format("v[{}]", r - 1 - n);
    if (constant_[at]) return literal(program_.code()[at - static_cast<std::size_t>(program_.inputs())].k);
    if (!in_stage && stage_[at]) return fmt::format("m[{}]", slot_[at]);
    return "r" + std::to_string(r);
  }

  std::string expression(const Instruction& in, bool in_stage) const {
    const int count = operand_count(in.op);
    const std::string a = count >= 1 ? reg(in.a, in_stage) : "", b = count >= 2 ? reg(in.b, in_stage) : "",
                      c = count >= 3 ? reg(in.c, in_stage) : "";
    const std::string k = literal(in.k);
    switch (in.op) {
      case Op::parameter: return fmt::format("p[{}]", in.a);
      case Op::add: return a + " + " + b;
      case Op::sub: return a + " - " + b;
      case Op::mul: return a + " * " + b;
      case Op::div: return a + " / " + b;
      case Op::neg: return "-" + a;
      case Op::add_k: return a + " + " + k;
      case Op::mul_k: return k + " * " + a;
      case Op::mulk: return k + " * (" + a + " * " + b + ")";
      case Op::div_k: return k + " / " + a;
      case Op::muladd: return a + " * " + b + " + " + c;
      case Op::mulsub: return c + " - " + a + " * " + b;
      case Op::mulk_add: return k + " * " + a + " + " + b;
      case Op::mulk_muladd: return k + " * (" + a + " * " + b + ") + " + c;
      case Op::square: return a + " * " + a;
      case Op::cube: return a + " * " + a + " * " + a;
      case Op::powi: return fmt::format("powi({}, {})", a, static_cast<int>(in.k));
      case Op::pow: return "std::pow(" + a + ", " + b + ")";
      case Op::pow_k: return "std::pow(" + a + ", " + k + ")";
      case Op::atan2: return "std::atan2(" + a + ", " + b + ")";
      default: return std::string("std::") + op_name(in.op) + "(" + a + ")";
    }
  }

  const Program& program_;
  std::vector<char> stage_, constant_;
  std::vector<int> slot_;  // register -> its place in the stage array, -1 if none
  int stage_size_ = 0;
};

}  // namespace

std::string make_terms_source(const Program& terms, int n, int s, const TermsSparsity* sparsity) {
  const Printer printer(terms);
  const int a_size = sparsity ? sparsity->A.nonzeros() : n * n;
  const int b_size = sparsity ? sparsity->b.nonzeros() : s * n;
  // Output j -> where it goes: A, Q, G, b, b0 one after the other; with `dense`, a sparse
  // program's A and b entries at their dense places.
  const auto destination = [&](bool dense) {
    return [&, dense](int j) -> std::string {
      const auto place = [&](const SparsityPattern& pattern, int k, int rows) {
        if (!dense || sparsity == nullptr) return k;
        int col = 0;
        while (pattern.outer[static_cast<std::size_t>(col) + 1] <= k) ++col;
        return pattern.inner[static_cast<std::size_t>(k)] + col * rows;
      };
      if (j < a_size) return fmt::format("A[{}]", sparsity ? place(sparsity->A, j, n) : j);
      j -= a_size;
      if (j < n) return fmt::format("Q[{}]", j);
      j -= n;
      if (j < n) return fmt::format("G[{}]", j);
      j -= n;
      if (j < b_size) return fmt::format("b[{}]", sparsity ? place(sparsity->b, j, s) : j);
      j -= b_size;
      return fmt::format("b0[{}]", j);
    };
  };
  std::string out;
  out += "// Generated by nhdyn (jit/source.hpp): the terms program of a model. Do not edit.\n";
  out += "#include <cmath>\n#include <cstddef>\n\nnamespace {\n";
  out += "[[maybe_unused]] inline double powi(double a, int n) {\n";
  out += "  unsigned m = n < 0 ? 0u - static_cast<unsigned>(n) : static_cast<unsigned>(n);\n";
  out += "  double result = 1.0;\n  double base = a;\n";
  out += "  for (;;) {\n    if (m & 1u) result *= base;\n    m >>= 1u;\n    if (m == 0u) break;\n";
  out += "    base *= base;\n  }\n  return n < 0 ? 1.0 / result : result;\n}\n}  // namespace\n\n";
  out += "extern \"C\" {\n";
  out += fmt::format("int nhdyn_jit_version(void) {{ return {}; }}\n", kInterfaceVersion);
  out += fmt::format("std::size_t nhdyn_jit_stage_size(void) {{ return {}; }}\n\n", printer.stage_size());
  out += "void nhdyn_jit_stage([[maybe_unused]] const double* p, [[maybe_unused]] double* m) {\n";
  out += printer.stage_body() + "}\n\n";
  const char* signature =
      "([[maybe_unused]] const double* m, [[maybe_unused]] double t, [[maybe_unused]] const double* q, "
      "[[maybe_unused]] const double* v, double* A, double* Q, double* G, double* b, double* b0) {\n"
      "  (void)A; (void)Q; (void)G; (void)b; (void)b0;\n";
  out += std::string("void nhdyn_jit_terms") + signature + printer.call_body(destination(false)) + "}\n";
  if (sparsity)
    out += std::string("\nvoid nhdyn_jit_terms_dense") + signature + printer.call_body(destination(true)) + "}\n";
  out += "}  // extern \"C\"\n";
  return out;
}

std::string make_program_source(const std::string& name, const Program& program) {
  const Printer printer(program);
  std::string out = fmt::format("\n// The program '{}'.\nextern \"C\" {{\n", name);
  out += fmt::format("std::size_t nhdyn_jit_{}_stage_size(void) {{ return {}; }}\n", name, printer.stage_size());
  out += fmt::format("void nhdyn_jit_{}_stage([[maybe_unused]] const double* p, [[maybe_unused]] double* m) {{\n", name);
  out += printer.stage_body() + "}\n";
  out += fmt::format("void nhdyn_jit_{}([[maybe_unused]] const double* m, [[maybe_unused]] double t, "
                     "[[maybe_unused]] const double* q, [[maybe_unused]] const double* v, double* out) {{\n  (void)out;\n",
                     name);
  out += printer.call_body([](int j) { return fmt::format("out[{}]", j); }) + "}\n";
  out += "}  // extern \"C\"\n";
  return out;
}

}  // namespace nhdyn::jit
