#include "nhdyn/model/detail/tape_printer.hpp"

#include <fmt/format.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace nhdyn {
namespace {

// `form` (a `cpp` of kOps) with {a}, {b}, {c}, {k}, {n}, {p} replaced by the given texts.
std::string expand(std::string_view form, const std::string& a, const std::string& b, const std::string& c,
                   const std::string& k, const std::string& n, const std::string& p) {
  std::string out;
  for (std::size_t i = 0; i < form.size(); ++i) {
    if (form[i] == '{' && i + 2 < form.size() && form[i + 2] == '}') {
      switch (form[i + 1]) {
        case 'a': out += a; break;
        case 'b': out += b; break;
        case 'c': out += c; break;
        case 'k': out += k; break;
        case 'n': out += n; break;
        case 'p': out += p; break;
        default: out.append(form.substr(i, 3)); break;
      }
      i += 2;
      continue;
    }
    out += form[i];
  }
  return out;
}

}  // namespace

TapePrinter::TapePrinter(const Tape& tape, TapePrintStyle style, bool hoist)
    : tape_(tape), style_(std::move(style)) {
  const std::size_t registers = static_cast<std::size_t>(tape.registers());
  stage_.assign(registers, 0);
  constant_.assign(registers, 0);
  read_by_stage_.assign(registers, 0);
  read_by_call_.assign(registers, 0);
  place_.assign(registers, -1);
  const std::vector<Instruction>& code = tape.code();
  const std::size_t inputs = static_cast<std::size_t>(tape.inputs());
  const auto at = [](int r) { return static_cast<std::size_t>(r); };
  // In the stage: a parameter, and what reads only stage registers and constants.
  for (std::size_t i = 0; i < code.size(); ++i) {
    const Instruction& in = code[i];
    const std::size_t r = inputs + i;
    if (in.op == Op::nop) {
      stage_[r] = stage_[r - 1];  // the cosine of a sincos goes with its sine
      continue;
    }
    if (in.op == Op::constant) {
      constant_[r] = 1;
      continue;
    }
    const int operands[3] = {in.a, in.b, in.c};
    const int count = operand_count(in.op);
    bool only = in.op == Op::parameter || count > 0;
    for (int k = 0; k < count; ++k) only = only && (stage_[at(operands[k])] || constant_[at(operands[k])]);
    stage_[r] = hoist && only;
  }
  for (std::size_t i = 0; i < code.size(); ++i) {
    const Instruction& in = code[i];
    if (in.op == Op::nop) continue;
    const std::size_t r = inputs + i;
    const int operands[3] = {in.a, in.b, in.c};
    for (int k = 0; k < operand_count(in.op); ++k) (stage_[r] ? read_by_stage_ : read_by_call_)[at(operands[k])] = 1;
  }
  for (const Output& o : tape.output_list())
    if (o.reg >= 0) read_by_call_[at(o.reg)] = 1;
  for (std::size_t r = 0; r < registers; ++r)
    if (stage_[r] && read_by_call_[r]) place_[r] = stored_count_++;
}

std::vector<std::pair<int, int>> TapePrinter::stored_registers() const {
  std::vector<std::pair<int, int>> out;
  for (std::size_t r = 0; r < place_.size(); ++r)
    if (place_[r] >= 0) out.emplace_back(static_cast<int>(r), place_[r]);
  return out;
}

std::string TapePrinter::reg(int r, bool in_stage) const {
  const int n = tape_.coordinates();
  const std::size_t at = static_cast<std::size_t>(r);
  if (r == Tape::time_register()) return "t";
  if (r <= n) return fmt::format("q[{}]", r - 1);
  if (r <= 2 * n) return fmt::format("v[{}]", r - 1 - n);
  if (constant_[at] && !style_.declare_constants)
    return style_.literal(tape_.code()[at - static_cast<std::size_t>(tape_.inputs())].k);
  if (!in_stage && stage_[at]) return style_.stored(r, place_[at]);
  return "r" + std::to_string(r);
}

std::string TapePrinter::output(int j) const {
  const Output& o = tape_.output_list()[static_cast<std::size_t>(j)];
  return o.reg < 0 ? style_.literal(o.value) : reg(o.reg, false);
}

std::string TapePrinter::expression(const Instruction& in, bool in_stage) const {
  const int count = operand_count(in.op);
  const std::string a = count >= 1 ? reg(in.a, in_stage) : "", b = count >= 2 ? reg(in.b, in_stage) : "",
                    c = count >= 3 ? reg(in.c, in_stage) : "";
  const std::string p = in.op == Op::parameter ? style_.parameter(in.a) : "";
  const std::string power = in.op == Op::powi ? std::to_string(static_cast<int>(in.k)) : "";
  return expand(op_info(in.op).cpp, a, b, c, style_.literal(in.k), power, p);
}

std::string TapePrinter::statements(bool in_stage, std::string_view indent) const {
  std::string out;
  const std::vector<Instruction>& code = tape_.code();
  for (std::size_t i = 0; i < code.size(); ++i) {
    const Instruction& in = code[i];
    const int r = tape_.inputs() + static_cast<int>(i);
    const std::size_t at = static_cast<std::size_t>(r);
    if (in.op == Op::nop) continue;
    const bool wanted = constant_[at] ? style_.declare_constants && (in_stage ? read_by_stage_[at] : read_by_call_[at])
                                      : static_cast<bool>(stage_[at]) == in_stage;
    if (!wanted) continue;
    if (in.op == Op::sincos) {
      const std::string a = reg(in.a, in_stage);
      out += fmt::format("{}const double r{} = std::sin({});\n", indent, r, a);
      out += fmt::format("{}const double r{} = std::cos({});\n", indent, r + 1, a);
    } else {
      out += fmt::format("{}const double r{} = {};\n", indent, r, expression(in, in_stage));
    }
  }
  if (in_stage)
    for (const auto& [r, place] : stored_registers()) out += fmt::format("{}{} = r{};\n", indent, style_.stored(r, place), r);
  return out;
}

}  // namespace nhdyn
