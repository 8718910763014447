#include "nhdyn/model/detail/tape_tangent.hpp"

#include <cmath>
#include <cstddef>

namespace nhdyn {
namespace {

// a^m for an integer m != 0 by repeated squaring, as the interpreter computes powi.
double integer_power(double a, int m) {
  unsigned e = m < 0 ? 0u - static_cast<unsigned>(m) : static_cast<unsigned>(m);
  double result = 1.0;
  double base = a;
  while (e != 0u) {
    if (e & 1u) result *= base;
    e >>= 1u;
    base *= base;
  }
  return m < 0 ? 1.0 / result : result;
}

}  // namespace

void run_tangent(const Tape& tape, const double* x, double dt, const double* dq, const double* dv,
                 double* d, double* doutputs) {
  const int n = tape.coordinates();
  d[0] = dt;
  for (int i = 0; i < n; ++i) {
    d[1 + i] = dq[i];
    d[1 + n + i] = dv != nullptr ? dv[i] : 0.0;
  }
  const std::vector<Instruction>& code = tape.code();
  const int first = tape.inputs();
  for (std::size_t j = 0; j < code.size(); ++j) {
    const Instruction& in = code[j];
    const std::size_t r = static_cast<std::size_t>(first) + j;
    const double a = x[in.a], b = x[in.b];
    const double da = d[in.a], db = d[in.b], dc = d[in.c];
    double value = 0.0;
    switch (in.op) {
      case Op::constant:
      case Op::parameter: value = 0.0; break;
      case Op::add: value = da + db; break;
      case Op::sub: value = da - db; break;
      case Op::mul: value = da * b + a * db; break;
      case Op::div: value = (da - x[r] * db) / b; break;
      case Op::neg: value = -da; break;
      case Op::add_k: value = da; break;
      case Op::mul_k: value = in.k * da; break;
      case Op::mulk: value = in.k * (da * b + a * db); break;
      case Op::div_k: value = -x[r] / a * da; break;
      case Op::muladd: value = da * b + a * db + dc; break;
      case Op::mulsub: value = dc - (da * b + a * db); break;
      case Op::mulk_add: value = in.k * da + db; break;
      case Op::mulk_muladd: value = in.k * (da * b + a * db) + dc; break;
      case Op::square: value = 2.0 * a * da; break;
      case Op::cube: value = 3.0 * a * a * da; break;
      case Op::powi: {
        const int m = static_cast<int>(in.k);
        value = m == 1 ? da : in.k * integer_power(a, m - 1) * da;
        break;
      }
      case Op::pow:
        // d(a^b) = b a^(b-1) da + a^b log(a) db; the second term only where b moves, so that a
        // constant exponent on a = 0 stays finite.
        value = (da != 0.0 ? b * std::pow(a, b - 1.0) * da : 0.0) + (db != 0.0 ? x[r] * std::log(a) * db : 0.0);
        break;
      case Op::pow_k: value = da != 0.0 ? in.k * std::pow(a, in.k - 1.0) * da : 0.0; break;
      case Op::sqrt: value = da != 0.0 ? da / (2.0 * x[r]) : 0.0; break;
      case Op::sin: value = std::cos(a) * da; break;
      case Op::cos: value = -std::sin(a) * da; break;
      case Op::sincos:
        // x[r] = sin(a), x[r + 1] = cos(a): the companion nop that follows fills d[r + 1].
        value = x[r + 1] * da;
        break;
      case Op::nop: value = -x[r - 1] * d[code[j - 1].a]; break;
      case Op::tan: value = (1.0 + x[r] * x[r]) * da; break;
      case Op::exp: value = x[r] * da; break;
      case Op::log: value = da / a; break;
      case Op::abs: value = a > 0.0 ? da : a < 0.0 ? -da : 0.0; break;
      case Op::asin: value = da / std::sqrt(1.0 - a * a); break;
      case Op::acos: value = -da / std::sqrt(1.0 - a * a); break;
      case Op::atan: value = da / (1.0 + a * a); break;
      case Op::atan2: value = (b * da - a * db) / (a * a + b * b); break;
      case Op::sinh: value = std::cosh(a) * da; break;
      case Op::cosh: value = std::sinh(a) * da; break;
      case Op::tanh: value = (1.0 - x[r] * x[r]) * da; break;
    }
    d[r] = value;
  }
  const std::vector<Output>& outputs = tape.output_list();
  for (std::size_t i = 0; i < outputs.size(); ++i) doutputs[i] = outputs[i].reg < 0 ? 0.0 : d[outputs[i].reg];
}

std::vector<char> calc_input_dependence(const Tape& tape) {
  // Backwards from the outputs: a register is needed when an output or a needed register reads it.
  const std::size_t registers = static_cast<std::size_t>(tape.registers());
  std::vector<char> needed(registers, 0);
  for (const Output& o : tape.output_list())
    if (o.reg >= 0) needed[static_cast<std::size_t>(o.reg)] = 1;
  const std::vector<Instruction>& code = tape.code();
  const std::size_t first = static_cast<std::size_t>(tape.inputs());
  for (std::size_t j = code.size(); j-- > 0;) {
    const Instruction& in = code[j];
    if (in.op == Op::nop) {
      // The cosine of a sincos: needing it needs the sincos, which reads the operand.
      if (needed[first + j]) needed[first + j - 1] = 1;
      continue;
    }
    if (!needed[first + j]) continue;
    const int operands[3] = {in.a, in.b, in.c};
    for (int k = 0; k < operand_count(in.op); ++k) needed[static_cast<std::size_t>(operands[k])] = 1;
  }
  return std::vector<char>(needed.begin(), needed.begin() + static_cast<std::ptrdiff_t>(first));
}

}  // namespace nhdyn
