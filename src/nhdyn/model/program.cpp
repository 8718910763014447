#include "nhdyn/model/program.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>

namespace nhdyn {
namespace {

// a^n by repeated squaring, n != 0. Generated code (symbolic/codegen.cpp) prints the same
// algorithm, so that both round alike.
inline double powi_value(double a, int n) {
  unsigned m = n < 0 ? 0u - static_cast<unsigned>(n) : static_cast<unsigned>(n);
  double result = 1.0;
  double base = a;
  for (;;) {
    if (m & 1u) result *= base;
    m >>= 1u;
    if (m == 0u) break;
    base *= base;
  }
  return n < 0 ? 1.0 / result : result;
}

// Largest |exponent| of powi: beyond it, repeated squaring is no better than std::pow.
constexpr double kMaxPowi = 1 << 20;

bool has_immediate(Op op) {
  return op == Op::constant || op == Op::add_k || op == Op::mul_k || op == Op::mulk || op == Op::div_k ||
         op == Op::mulk_add || op == Op::mulk_muladd || op == Op::powi || op == Op::pow_k;
}

std::string format_double(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
}

// The interpreter, inlined into Program::execute and ProgramEvaluator::terms (a call less on the
// hottest path).
#if defined(__GNUC__)
[[gnu::always_inline]]
#endif
inline void run_code(const Instruction* code, std::size_t size, std::size_t n, const bool* reads, double t,
                     const double* q, const double* v, double* registers) {
  // Only the inputs the program reads are copied in (a position residual has no v, say).
  if (reads[0]) registers[0] = t;
  if (reads[1])
    for (std::size_t i = 0; i < n; ++i) registers[1 + i] = q[i];
  if (reads[2])
    for (std::size_t i = 0; i < n; ++i) registers[1 + n + i] = v[i];
  double* r = registers + 1 + 2 * n;  // r[i]: the register of instruction i
  const double* x = registers;        // operands, by register number
  for (std::size_t i = 0; i < size; ++i) {
    const Instruction& in = code[i];
    switch (in.op) {
      case Op::constant: r[i] = in.k; break;
      case Op::add: r[i] = x[in.a] + x[in.b]; break;
      case Op::sub: r[i] = x[in.a] - x[in.b]; break;
      case Op::mul: r[i] = x[in.a] * x[in.b]; break;
      case Op::div: r[i] = x[in.a] / x[in.b]; break;
      case Op::neg: r[i] = -x[in.a]; break;
      case Op::add_k: r[i] = x[in.a] + in.k; break;
      case Op::mul_k: r[i] = in.k * x[in.a]; break;
      case Op::mulk: r[i] = in.k * (x[in.a] * x[in.b]); break;
      case Op::div_k: r[i] = in.k / x[in.a]; break;
      case Op::muladd: r[i] = x[in.a] * x[in.b] + x[in.c]; break;
      case Op::mulsub: r[i] = x[in.c] - x[in.a] * x[in.b]; break;
      case Op::mulk_add: r[i] = in.k * x[in.a] + x[in.b]; break;
      case Op::mulk_muladd: r[i] = in.k * (x[in.a] * x[in.b]) + x[in.c]; break;
      case Op::square: r[i] = x[in.a] * x[in.a]; break;
      case Op::cube: r[i] = x[in.a] * x[in.a] * x[in.a]; break;
      case Op::powi: r[i] = powi_value(x[in.a], static_cast<int>(in.k)); break;
      case Op::pow: r[i] = std::pow(x[in.a], x[in.b]); break;
      case Op::pow_k: r[i] = std::pow(x[in.a], in.k); break;
      case Op::sqrt: r[i] = std::sqrt(x[in.a]); break;
      case Op::sin: r[i] = std::sin(x[in.a]); break;
      case Op::cos: r[i] = std::cos(x[in.a]); break;
      case Op::sincos: {
        const double y = x[in.a];
        r[i] = std::sin(y);
        r[i + 1] = std::cos(y);
        ++i;  // skip the companion nop
        break;
      }
      case Op::tan: r[i] = std::tan(x[in.a]); break;
      case Op::exp: r[i] = std::exp(x[in.a]); break;
      case Op::log: r[i] = std::log(x[in.a]); break;
      case Op::abs: r[i] = std::abs(x[in.a]); break;
      case Op::asin: r[i] = std::asin(x[in.a]); break;
      case Op::acos: r[i] = std::acos(x[in.a]); break;
      case Op::atan: r[i] = std::atan(x[in.a]); break;
      case Op::atan2: r[i] = std::atan2(x[in.a], x[in.b]); break;
      case Op::sinh: r[i] = std::sinh(x[in.a]); break;
      case Op::cosh: r[i] = std::cosh(x[in.a]); break;
      case Op::tanh: r[i] = std::tanh(x[in.a]); break;
      case Op::nop: break;
    }
  }
}

}  // namespace

int operand_count(Op op) {
  switch (op) {
    case Op::constant:
    case Op::nop:
      return 0;
    case Op::add:
    case Op::sub:
    case Op::mul:
    case Op::div:
    case Op::mulk:
    case Op::mulk_add:
    case Op::pow:
    case Op::atan2:
      return 2;
    case Op::muladd:
    case Op::mulsub:
    case Op::mulk_muladd:
      return 3;
    default:
      return 1;
  }
}

const char* op_name(Op op) {
  switch (op) {
    case Op::constant: return "constant";
    case Op::add: return "add";
    case Op::sub: return "sub";
    case Op::mul: return "mul";
    case Op::div: return "div";
    case Op::neg: return "neg";
    case Op::add_k: return "add_k";
    case Op::mul_k: return "mul_k";
    case Op::mulk: return "mulk";
    case Op::div_k: return "div_k";
    case Op::muladd: return "muladd";
    case Op::mulsub: return "mulsub";
    case Op::mulk_add: return "mulk_add";
    case Op::mulk_muladd: return "mulk_muladd";
    case Op::square: return "square";
    case Op::cube: return "cube";
    case Op::powi: return "powi";
    case Op::pow: return "pow";
    case Op::pow_k: return "pow_k";
    case Op::sqrt: return "sqrt";
    case Op::sin: return "sin";
    case Op::cos: return "cos";
    case Op::sincos: return "sincos";
    case Op::tan: return "tan";
    case Op::exp: return "exp";
    case Op::log: return "log";
    case Op::abs: return "abs";
    case Op::asin: return "asin";
    case Op::acos: return "acos";
    case Op::atan: return "atan";
    case Op::atan2: return "atan2";
    case Op::sinh: return "sinh";
    case Op::cosh: return "cosh";
    case Op::tanh: return "tanh";
    case Op::nop: return "nop";
  }
  return "?";
}

Program::Program(int coordinates) : n_(coordinates) {
  if (coordinates < 0) throw std::invalid_argument("Program: negative number of coordinates");
}

int Program::coordinate_register(int i) const {
  if (i < 0 || i >= n_)
    throw std::invalid_argument("Program: coordinate index " + std::to_string(i) + " out of range [0, " +
                                std::to_string(n_) + ")");
  return 1 + i;
}

int Program::velocity_register(int i) const { return coordinate_register(i) + n_; }

void Program::note_read(int reg) {
  if (reg == 0)
    reads_[0] = true;
  else if (reg <= n_)
    reads_[1] = true;
  else if (reg <= 2 * n_)
    reads_[2] = true;
}

int Program::push(Op op, int a, int b, int c, double k) {
  const int next = registers();
  if (op == Op::nop) throw std::invalid_argument("Program::push: nop is only the companion of a sincos");
  const int operands[3] = {a, b, c};
  const int count = operand_count(op);
  for (int i = 0; i < count; ++i)
    if (operands[i] < 0 || operands[i] >= next)
      throw std::invalid_argument(std::string("Program::push: ") + op_name(op) + " reads register " +
                                  std::to_string(operands[i]) + ", which is not written before register " +
                                  std::to_string(next));
  if (op == Op::powi && !(k != 0.0 && std::abs(k) <= kMaxPowi && k == std::trunc(k)))
    throw std::invalid_argument("Program::push: powi needs a nonzero integer exponent of magnitude at most 2^20, not " +
                                format_double(k));
  // Unused fields are zeroed so that equal programs compare equal field by field.
  Instruction in{op, 0, 0, 0, 0.0};
  if (count >= 1) in.a = a;
  if (count >= 2) in.b = b;
  if (count >= 3) in.c = c;
  if (has_immediate(op)) in.k = k;
  for (int i = 0; i < count; ++i) note_read(operands[i]);
  code_.push_back(in);
  if (op == Op::sincos) code_.push_back(Instruction{Op::nop, next, 0, 0, 0.0});
  return next;
}

void Program::add_output(int reg) {
  if (reg < 0 || reg >= registers())
    throw std::invalid_argument("Program::add_output: register " + std::to_string(reg) + " is not written");
  note_read(reg);
  outputs_.push_back(Output{reg, 0.0});
}

void Program::add_constant_output(double value) { outputs_.push_back(Output{-1, value}); }

int Program::count(Op op) const {
  int total = 0;
  for (const Instruction& in : code_) total += in.op == op ? 1 : 0;
  return total;
}

void Program::execute(double t, const double* q, const double* v, double* registers) const {
  run_code(code_.data(), code_.size(), static_cast<std::size_t>(n_), reads_, t, q, v, registers);
}

void Program::run(double t, const double* q, const double* v, double* registers, double* outputs) const {
  execute(t, q, v, registers);
  const std::size_t m = outputs_.size();
  const Output* o = outputs_.data();
  for (std::size_t i = 0; i < m; ++i) outputs[i] = o[i].reg < 0 ? o[i].value : registers[o[i].reg];
}

std::string Program::register_name(int reg) const {
  if (reg == 0) return "t";
  if (reg >= 1 && reg <= n_) return "q" + std::to_string(reg - 1);
  if (reg > n_ && reg <= 2 * n_) return "v" + std::to_string(reg - 1 - n_);
  return "r" + std::to_string(reg);
}

std::string Program::describe() const {
  std::string out;
  for (std::size_t i = 0; i < code_.size(); ++i) {
    const Instruction& in = code_[i];
    if (in.op == Op::nop) continue;
    const int reg = inputs() + static_cast<int>(i);
    out += register_name(reg);
    if (in.op == Op::sincos) out += ", " + register_name(reg + 1);
    out += std::string(" = ") + op_name(in.op);
    const int operands[3] = {in.a, in.b, in.c};
    for (int j = 0; j < operand_count(in.op); ++j) out += " " + register_name(operands[j]);
    if (has_immediate(in.op)) out += " " + format_double(in.k);
    out += "\n";
  }
  out += "outputs:";
  for (const Output& o : outputs_) out += " " + (o.reg < 0 ? format_double(o.value) : register_name(o.reg));
  out += "\n";
  return out;
}

// --- ProgramEvaluator ---------------------------------------------------------------------------

namespace {

void check_program(const Program& program, const char* what, int n, int outputs) {
  if (program.coordinates() != n)
    throw std::invalid_argument(std::string("ProgramEvaluator: the ") + what + " program reads " +
                                std::to_string(program.coordinates()) + " coordinates, the model has " +
                                std::to_string(n));
  if (outputs >= 0 && program.outputs() != outputs)
    throw std::invalid_argument(std::string("ProgramEvaluator: the ") + what + " program has " +
                                std::to_string(program.outputs()) + " outputs, " + std::to_string(outputs) +
                                " expected");
}

}  // namespace

ProgramEvaluator::ProgramEvaluator(int n, int s, ModelPrograms programs)
    : n_(n), s_(s), programs_(std::move(programs)) {
  if (n <= 0 || s < 0 || s >= n)
    throw std::invalid_argument("ProgramEvaluator: needs 0 <= s < n, got n = " + std::to_string(n) +
                                ", s = " + std::to_string(s));
  check_program(programs_.terms, "terms", n, n * n + 2 * n + s * n + s);
  if (programs_.complement) check_program(*programs_.complement, "complement", n, (n - s) * n);
  check_program(programs_.position_residual, "position residual", n, -1);
  check_program(programs_.velocity_residual, "velocity residual", n, -1);
  if (programs_.energy) check_program(*programs_.energy, "energy", n, 1);
  if (programs_.position_residual.reads_velocities())
    throw std::invalid_argument("ProgramEvaluator: the position residual program reads velocities");
  if (programs_.position_residual.outputs() > s || programs_.velocity_residual.outputs() > s ||
      programs_.position_residual.outputs() > programs_.velocity_residual.outputs())
    throw std::invalid_argument("ProgramEvaluator: more residuals than constraints");

  std::size_t largest = static_cast<std::size_t>(programs_.terms.registers());
  const auto widen = [&largest](const Program& p) {
    largest = std::max(largest, static_cast<std::size_t>(p.registers()));
  };
  if (programs_.complement) widen(*programs_.complement);
  widen(programs_.position_residual);
  widen(programs_.velocity_residual);
  if (programs_.energy) widen(*programs_.energy);
  scratch_ = largest;

  // The terms' outputs as an image of constants plus the registers to scatter over it.
  const std::vector<Output>& outputs = programs_.terms.output_list();
  const int sizes[5] = {n * n, n, n, s * n, s};
  std::size_t j = 0;
  for (int array = 0; array < 5; ++array) {
    first_entry_[array] = static_cast<std::int32_t>(entries_.size());
    for (int i = 0; i < sizes[array]; ++i, ++j) {
      const Output& o = outputs[j];
      image_.push_back(o.reg < 0 ? o.value : 0.0);
      if (o.reg >= 0) entries_.push_back(Entry{i, o.reg});
    }
  }
  first_entry_[5] = static_cast<std::int32_t>(entries_.size());
  terms_function_ = choose_terms(n, s);
}

namespace {

template <int N>
inline void copy_fixed(const double* from, double* to) {
  for (int i = 0; i < N; ++i) to[i] = from[i];
}

inline void copy_any(const double* from, double* to, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) to[i] = from[i];
}

}  // namespace

// For a small model the fixed cost of the call dominates (19 outputs for n = 3, s = 1, most of
// them constant): with the sizes known at compile time the input copies and the image copies
// become a few vector moves instead of loops, and the register outputs are scattered array by
// array from a base pointer held in a register.
template <int N, int S>
void ProgramEvaluator::terms_fixed(const ProgramEvaluator& self, double t, const double* q, const double* v,
                                   double* scratch, const TermsOut& out) {
  const Program& p = self.programs_.terms;
  run_code(p.code_.data(), p.code_.size(), N, p.reads_, t, q, v, scratch);
  const double* image = self.image_.data();
  copy_fixed<N * N>(image, out.A);
  copy_fixed<N>(image + N * N, out.Q);
  copy_fixed<N>(image + N * N + N, out.G);
  copy_fixed<S * N>(image + N * N + 2 * N, out.b);
  copy_fixed<S>(image + N * N + 2 * N + S * N, out.b0);
  double* const arrays[5] = {out.A, out.Q, out.G, out.b, out.b0};
  const Entry* entries = self.entries_.data();
  for (int a = 0; a < 5; ++a) {
    double* to = arrays[a];
    for (std::int32_t e = self.first_entry_[a]; e < self.first_entry_[a + 1]; ++e)
      to[entries[e].index] = scratch[entries[e].reg];
  }
}

void ProgramEvaluator::terms_any(const ProgramEvaluator& self, double t, const double* q, const double* v,
                                 double* scratch, const TermsOut& out) {
  const Program& p = self.programs_.terms;
  const std::size_t n = static_cast<std::size_t>(self.n_), s = static_cast<std::size_t>(self.s_);
  run_code(p.code_.data(), p.code_.size(), n, p.reads_, t, q, v, scratch);
  const double* image = self.image_.data();
  copy_any(image, out.A, n * n);
  copy_any(image + n * n, out.Q, n);
  copy_any(image + n * n + n, out.G, n);
  copy_any(image + n * n + 2 * n, out.b, s * n);
  copy_any(image + n * n + 2 * n + s * n, out.b0, s);
  double* const arrays[5] = {out.A, out.Q, out.G, out.b, out.b0};
  const Entry* entries = self.entries_.data();
  for (int a = 0; a < 5; ++a) {
    double* to = arrays[a];
    for (std::int32_t e = self.first_entry_[a]; e < self.first_entry_[a + 1]; ++e)
      to[entries[e].index] = scratch[entries[e].reg];
  }
}

ProgramEvaluator::TermsFunction ProgramEvaluator::choose_terms(int n, int s) {
  switch (n * 8 + s) {
    case 1 * 8 + 0: return &terms_fixed<1, 0>;
    case 2 * 8 + 0: return &terms_fixed<2, 0>;
    case 2 * 8 + 1: return &terms_fixed<2, 1>;
    case 3 * 8 + 0: return &terms_fixed<3, 0>;
    case 3 * 8 + 1: return &terms_fixed<3, 1>;
    case 3 * 8 + 2: return &terms_fixed<3, 2>;
    case 4 * 8 + 0: return &terms_fixed<4, 0>;
    case 4 * 8 + 1: return &terms_fixed<4, 1>;
    case 4 * 8 + 2: return &terms_fixed<4, 2>;
    case 4 * 8 + 3: return &terms_fixed<4, 3>;
    default: return &terms_any;
  }
}

void ProgramEvaluator::terms(double t, const double* q, const double* v, double* scratch,
                             const TermsOut& out) const {
  terms_function_(*this, t, q, v, scratch, out);
}

void ProgramEvaluator::complement(double t, const double* q, const double* v, double* scratch, double* D) const {
  if (!programs_.complement) return;
  programs_.complement->run(t, q, v, scratch, D);
}

void ProgramEvaluator::position_residual(double t, const double* q, double* scratch, double* phi) const {
  programs_.position_residual.run(t, q, nullptr, scratch, phi);
}

void ProgramEvaluator::velocity_residual(double t, const double* q, const double* v, double* scratch,
                                         double* f) const {
  programs_.velocity_residual.run(t, q, v, scratch, f);
}

double ProgramEvaluator::energy(double t, const double* q, const double* v, double* scratch) const {
  if (!programs_.energy) return 0.0;
  double e = 0.0;
  programs_.energy->run(t, q, v, scratch, &e);
  return e;
}

}  // namespace nhdyn
