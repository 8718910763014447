#include "nhdyn/model/tape.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <functional>
#include <iterator>
#include <memory>
#include <queue>
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

// Whether the instruction calls the math library (std::sqrt too: it sets errno below zero).
bool calls_library(Op op) {
  switch (op) {
    case Op::pow:
    case Op::pow_k:
    case Op::sqrt:
    case Op::sin:
    case Op::cos:
    case Op::sincos:
    case Op::tan:
    case Op::exp:
    case Op::log:
    case Op::asin:
    case Op::acos:
    case Op::atan:
    case Op::atan2:
    case Op::sinh:
    case Op::cosh:
    case Op::tanh:
      return true;
    default:
      return false;
  }
}

#if defined(__GNUC__)
#define NHDYN_ALWAYS_INLINE [[gnu::always_inline]] inline
#define NHDYN_UNREACHABLE() __builtin_unreachable()
#else
#define NHDYN_ALWAYS_INLINE inline
#define NHDYN_UNREACHABLE() ((void)0)
#endif

// Copies in the inputs the tape reads (a position residual has no v, say); inlined with n
// known at compile time where it is.
NHDYN_ALWAYS_INLINE void load_inputs(const bool* reads, std::size_t n, double t, const double* q, const double* v,
                                     double* x) {
  if (reads[0]) x[0] = t;
  if (reads[1])
    for (std::size_t i = 0; i < n; ++i) x[1 + i] = q[i];
  if (reads[2])
    for (std::size_t i = 0; i < n; ++i) x[1 + n + i] = v[i];
}

// Keeps the compiler from merging the 8-byte stores around it into one 16-byte store, which a core
// may not forward to a later 8-byte load of its upper half: the load then waits for the store to
// retire (measured on AMD Zen 5: the sled's terms some 15% slower). Emits no instruction.
NHDYN_ALWAYS_INLINE void store_fence() { std::atomic_signal_fence(std::memory_order_seq_cst); }

// A step that calls the math library: from the registers x into y.
NHDYN_ALWAYS_INLINE void run_library_step(const Step* s, const double* x, double* y) {
  switch (s->op) {
    case Op::pow: y[s->to] = std::pow(x[s->a], x[s->b]); break;
    case Op::pow_k: y[s->to] = std::pow(x[s->a], s->k); break;
    case Op::sqrt: y[s->to] = std::sqrt(x[s->a]); break;
    case Op::sin: y[s->to] = std::sin(x[s->a]); break;
    case Op::cos: y[s->to] = std::cos(x[s->a]); break;
    case Op::sincos: {
      const double u = x[s->a];
      y[s->to] = std::sin(u);
      store_fence();
      y[s->to + 1] = std::cos(u);
      break;
    }
    case Op::tan: y[s->to] = std::tan(x[s->a]); break;
    case Op::exp: y[s->to] = std::exp(x[s->a]); break;
    case Op::log: y[s->to] = std::log(x[s->a]); break;
    case Op::asin: y[s->to] = std::asin(x[s->a]); break;
    case Op::acos: y[s->to] = std::acos(x[s->a]); break;
    case Op::atan: y[s->to] = std::atan(x[s->a]); break;
    case Op::atan2: y[s->to] = std::atan2(x[s->a], x[s->b]); break;
    case Op::sinh: y[s->to] = std::sinh(x[s->a]); break;
    case Op::cosh: y[s->to] = std::cosh(x[s->a]); break;
    case Op::tanh: y[s->to] = std::tanh(x[s->a]); break;
    default: NHDYN_UNREACHABLE();
  }
}

// The op and destination of a step, read at once: consecutive steps with the same key form a run.
static_assert(offsetof(Step, op) == 0 && offsetof(Step, dest) == 1 && sizeof(Op) == 1);
NHDYN_ALWAYS_INLINE unsigned run_key(const Step* s) {
  std::uint16_t key;
  std::memcpy(&key, s, sizeof key);
  return key;
}

// Runs the run of steps that starts at s, each writing value(step) to its destination; returns the
// step after the run.
template <class Value>
NHDYN_ALWAYS_INLINE const Step* run(const Step* s, double* const* arrays, Value value) {
  double* const y = arrays[s->dest];
  const unsigned key = run_key(s);
  do y[s->to] = value(*s);
  while (run_key(++s) == key);
  return s;
}

// The interpreter: runs steps up to their closing nop. arrays[0] is the registers, which every
// operand reads; a step writes arrays[dest]. A run of steps of the same op and destination loops
// inside its case, one dispatch for the run; the nop that ends the list spares a counter and a
// compare per step. With Calls = false no step calls the math library, and the interpreter, with
// no call either, saves and restores no registers: a small model's terms are mostly fixed cost.
template <bool Calls>
NHDYN_ALWAYS_INLINE void run_steps(const Step* s, double* const* arrays) {
  const double* x = arrays[0];
  for (;;) {
    switch (s->op) {
      case Op::constant: s = run(s, arrays, [](const Step& i) { return i.k; }); break;
      case Op::add: s = run(s, arrays, [x](const Step& i) { return x[i.a] + x[i.b]; }); break;
      case Op::sub: s = run(s, arrays, [x](const Step& i) { return x[i.a] - x[i.b]; }); break;
      case Op::mul: s = run(s, arrays, [x](const Step& i) { return x[i.a] * x[i.b]; }); break;
      case Op::div: s = run(s, arrays, [x](const Step& i) { return x[i.a] / x[i.b]; }); break;
      case Op::neg: s = run(s, arrays, [x](const Step& i) { return -x[i.a]; }); break;
      case Op::add_k: s = run(s, arrays, [x](const Step& i) { return x[i.a] + i.k; }); break;
      case Op::mul_k: s = run(s, arrays, [x](const Step& i) { return i.k * x[i.a]; }); break;
      case Op::mulk: s = run(s, arrays, [x](const Step& i) { return i.k * (x[i.a] * x[i.b]); }); break;
      case Op::div_k: s = run(s, arrays, [x](const Step& i) { return i.k / x[i.a]; }); break;
      case Op::muladd: s = run(s, arrays, [x](const Step& i) { return x[i.a] * x[i.b] + x[i.c]; }); break;
      case Op::mulsub: s = run(s, arrays, [x](const Step& i) { return x[i.c] - x[i.a] * x[i.b]; }); break;
      case Op::mulk_add: s = run(s, arrays, [x](const Step& i) { return i.k * x[i.a] + x[i.b]; }); break;
      case Op::mulk_muladd: s = run(s, arrays, [x](const Step& i) { return i.k * (x[i.a] * x[i.b]) + x[i.c]; }); break;
      case Op::square: s = run(s, arrays, [x](const Step& i) { return x[i.a] * x[i.a]; }); break;
      case Op::cube: s = run(s, arrays, [x](const Step& i) { return x[i.a] * x[i.a] * x[i.a]; }); break;
      case Op::powi:
        s = run(s, arrays, [x](const Step& i) { return powi_value(x[i.a], static_cast<int>(i.k)); });
        break;
      case Op::abs: s = run(s, arrays, [x](const Step& i) { return std::abs(x[i.a]); }); break;
      case Op::nop:
        return;
      default:
        if constexpr (Calls) {
          run_library_step(s, x, arrays[s->dest]);
          ++s;
        } else {
          NHDYN_UNREACHABLE();
        }
    }
  }
}

}  // namespace

// Every row of kOps at its Op's index, every Op in it.
constexpr bool ops_in_order() {
  for (std::size_t i = 0; i < std::size(kOps); ++i)
    if (static_cast<std::size_t>(kOps[i].op) != i) return false;
  return std::size(kOps) == static_cast<std::size_t>(Op::nop) + 1;
}
static_assert(ops_in_order(), "kOps lists every Op once, in the order of the enum");

int operand_count(Op op) { return op_info(op).operands; }

const char* op_name(Op op) { return op_info(op).name; }

Tape::Tape(int coordinates, int parameters) : n_(coordinates), parameters_(parameters), steps_(1) {
  if (coordinates < 0) throw std::invalid_argument("Tape: negative number of coordinates");
  if (parameters < 0) throw std::invalid_argument("Tape: negative number of parameters");
}

int Tape::coordinate_register(int i) const {
  if (i < 0 || i >= n_)
    throw std::invalid_argument("Tape: coordinate index " + std::to_string(i) + " out of range [0, " +
                                std::to_string(n_) + ")");
  return 1 + i;
}

int Tape::velocity_register(int i) const { return coordinate_register(i) + n_; }

void Tape::note_read(int reg) {
  if (reg == 0)
    reads_[0] = true;
  else if (reg <= n_)
    reads_[1] = true;
  else if (reg <= 2 * n_)
    reads_[2] = true;
}

int Tape::push(Op op, int a, int b, int c, double k) {
  const int next = registers();
  if (op == Op::nop) throw std::invalid_argument("Tape::push: nop is only the companion of a sincos");
  const int operands[3] = {a, b, c};
  const int count = operand_count(op);
  for (int i = 0; i < count; ++i)
    if (operands[i] < 0 || operands[i] >= next)
      throw std::invalid_argument(std::string("Tape::push: ") + op_name(op) + " reads register " +
                                  std::to_string(operands[i]) + ", which is not written before register " +
                                  std::to_string(next));
  if (op == Op::powi && !(k != 0.0 && std::abs(k) <= kMaxPowi && k == std::trunc(k)))
    throw std::invalid_argument("Tape::push: powi needs a nonzero integer exponent of magnitude at most 2^20, not " +
                                format_double(k));
  if (op == Op::parameter && (a < 0 || a >= parameters_))
    throw std::invalid_argument("Tape::push: parameter " + std::to_string(a) + " out of range [0, " +
                                std::to_string(parameters_) + ")");
  // Unused fields are zeroed so that equal tapes compare equal field by field.
  Instruction in{op, 0, 0, 0, 0.0};
  if (op == Op::parameter) {
    in.a = a;
    reads_parameters_ = true;
  }
  if (count >= 1) in.a = a;
  if (count >= 2) in.b = b;
  if (count >= 3) in.c = c;
  if (has_immediate(op)) in.k = k;
  for (int i = 0; i < count; ++i) note_read(operands[i]);
  code_.push_back(in);
  if (op == Op::sincos) code_.push_back(Instruction{Op::nop, next, 0, 0, 0.0});
  steps_.back() = Step{op, 0, next, in.a, in.b, in.c, in.k};
  steps_.push_back(Step{});
  calls_ = calls_ || calls_library(op);
  return next;
}

void Tape::add_output(int reg) {
  if (reg < 0 || reg >= registers())
    throw std::invalid_argument("Tape::add_output: register " + std::to_string(reg) + " is not written");
  note_read(reg);
  outputs_.push_back(Output{reg, 0.0});
}

void Tape::add_constant_output(double value) { outputs_.push_back(Output{-1, value}); }

int Tape::count(Op op) const {
  int total = 0;
  for (const Instruction& in : code_) total += in.op == op ? 1 : 0;
  return total;
}

Tape Tape::bind(const double* values, std::size_t count) const {
  if (static_cast<std::size_t>(parameters_) > count)
    throw std::invalid_argument("Tape::bind: " + std::to_string(count) + " values for " +
                                std::to_string(parameters_) + " parameters");
  if (!reads_parameters_) return *this;
  Tape out(n_, parameters_);
  for (const Instruction& in : code_) {
    if (in.op == Op::nop) continue;  // pushed with its sincos
    if (in.op == Op::parameter)
      out.push_constant(values[in.a]);
    else
      out.push(in.op, in.a, in.b, in.c, in.k);
  }
  out.outputs_ = outputs_;
  for (const Output& o : outputs_)
    if (o.reg >= 0) out.note_read(o.reg);
  return out;
}

void Tape::execute(double t, const double* q, const double* v, double* registers) const {
  if (reads_parameters_)
    throw std::logic_error("Tape::execute: the tape reads parameters; run the tape bind() returns");
  load_inputs(reads_, static_cast<std::size_t>(n_), t, q, v, registers);
  double* const arrays[1] = {registers};
  if (calls_)
    run_steps<true>(steps_.data(), arrays);
  else
    run_steps<false>(steps_.data(), arrays);
}

void Tape::run(double t, const double* q, const double* v, double* registers, double* outputs) const {
  execute(t, q, v, registers);
  const std::size_t m = outputs_.size();
  const Output* o = outputs_.data();
  for (std::size_t i = 0; i < m; ++i) outputs[i] = o[i].reg < 0 ? o[i].value : registers[o[i].reg];
}

std::string Tape::register_name(int reg) const {
  if (reg == 0) return "t";
  if (reg >= 1 && reg <= n_) return "q" + std::to_string(reg - 1);
  if (reg > n_ && reg <= 2 * n_) return "v" + std::to_string(reg - 1 - n_);
  return "r" + std::to_string(reg);
}

std::string Tape::describe() const {
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
    if (in.op == Op::parameter) out += " p" + std::to_string(in.a);
    if (has_immediate(in.op)) out += " " + format_double(in.k);
    out += "\n";
  }
  out += "outputs:";
  for (const Output& o : outputs_) out += " " + (o.reg < 0 ? format_double(o.value) : register_name(o.reg));
  out += "\n";
  return out;
}

// --- TapeEvaluator ---------------------------------------------------------------------------

namespace {

void check_tape(const Tape& tape, const char* what, int n, int outputs) {
  if (tape.coordinates() != n)
    throw std::invalid_argument(std::string("TapeEvaluator: the ") + what + " tape reads " +
                                std::to_string(tape.coordinates()) + " coordinates, the model has " +
                                std::to_string(n));
  if (outputs >= 0 && tape.outputs() != outputs)
    throw std::invalid_argument(std::string("TapeEvaluator: the ") + what + " tape has " +
                                std::to_string(tape.outputs()) + " outputs, " + std::to_string(outputs) +
                                " expected");
}

}  // namespace

namespace {

ModelTapes bind_tapes(const ModelTapes& parametric, const std::vector<double>& values) {
  if (values.size() < static_cast<std::size_t>(parametric.parameters))
    throw std::invalid_argument("TapeEvaluator: " + std::to_string(values.size()) + " parameter values for " +
                                std::to_string(parametric.parameters) + " parameters");
  const auto bound = [&values](const Tape& p) {
    if (p.parameters() > static_cast<int>(values.size()))
      throw std::invalid_argument("TapeEvaluator: a tape reads more parameters than the model has");
    return p.bind(values.data(), values.size());
  };
  const auto bound_optional = [&bound](const std::optional<Tape>& p) -> std::optional<Tape> {
    if (!p) return std::nullopt;
    return bound(*p);
  };
  ModelTapes out;
  out.parameters = parametric.parameters;
  out.terms = bound(parametric.terms);
  out.complement = bound_optional(parametric.complement);
  out.position_residual = bound(parametric.position_residual);
  out.velocity_residual = bound(parametric.velocity_residual);
  out.energy = bound_optional(parametric.energy);
  out.solution = bound_optional(parametric.solution);
  out.initial_state = bound_optional(parametric.initial_state);
  out.energy_balance = parametric.energy_balance;
  out.energy_function = bound_optional(parametric.energy_function);
  out.power = bound_optional(parametric.power);
  out.sparsity = parametric.sparsity;
  out.program_constraints = parametric.program_constraints;
  out.program_constraint_terms = bound_optional(parametric.program_constraint_terms);
  out.program_constraint_position_residual = bound_optional(parametric.program_constraint_position_residual);
  out.program_constraint_velocity_residual = bound_optional(parametric.program_constraint_velocity_residual);
  return out;
}

}  // namespace

TapeEvaluator::TapeEvaluator(int n, int s, ModelTapes tapes, std::vector<double> parameters)
    : n_(n), s_(s), parametric_(std::make_shared<const ModelTapes>(std::move(tapes))),
      parameters_(std::move(parameters)) {
  build();
}

TapeEvaluator::TapeEvaluator(const TapeEvaluator& other, std::vector<double> parameters)
    : n_(other.n_), s_(other.s_), parametric_(other.parametric_), parameters_(std::move(parameters)) {
  build();
}

std::shared_ptr<const Evaluator> TapeEvaluator::with_parameters(const double* values, std::size_t count) const {
  if (count < static_cast<std::size_t>(parametric_->parameters))
    throw std::invalid_argument("TapeEvaluator::with_parameters: " + std::to_string(count) + " values for " +
                                std::to_string(parameters_.size()) + " parameters");
  return std::make_shared<TapeEvaluator>(*this, std::vector<double>(values, values + count));
}

void TapeEvaluator::build() {
  const int n = n_, s = s_;
  if (n <= 0 || s < 0)  // s >= n is allowed: contacts that are never all held (Model::k())
    throw std::invalid_argument("TapeEvaluator: needs n > 0 and s >= 0, got n = " + std::to_string(n) +
                                ", s = " + std::to_string(s));
  tapes_ = bind_tapes(*parametric_, parameters_);
  std::size_t a_size = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
  std::size_t b_size = static_cast<std::size_t>(s) * static_cast<std::size_t>(n);
  if (tapes_.sparsity) {
    check_pattern(tapes_.sparsity->A, n, n, "A");
    check_pattern(tapes_.sparsity->b, s, n, "b");
    a_size = static_cast<std::size_t>(tapes_.sparsity->A.nonzeros());
    b_size = static_cast<std::size_t>(tapes_.sparsity->b.nonzeros());
  }
  terms_sizes_[0] = a_size;
  terms_sizes_[1] = terms_sizes_[2] = static_cast<std::size_t>(n);
  terms_sizes_[3] = b_size;
  terms_sizes_[4] = static_cast<std::size_t>(s);
  check_tape(tapes_.terms, "terms", n, static_cast<int>(a_size + b_size) + 2 * n + s);
  if (tapes_.complement) check_tape(*tapes_.complement, "complement", n, (n - s) * n);
  check_tape(tapes_.position_residual, "position residual", n, -1);
  check_tape(tapes_.velocity_residual, "velocity residual", n, -1);
  if (tapes_.energy) check_tape(*tapes_.energy, "energy", n, 1);
  if (tapes_.energy_function) check_tape(*tapes_.energy_function, "energy function", n, 1);
  if (tapes_.power) check_tape(*tapes_.power, "power", n, 2);
  if (tapes_.solution) {
    check_tape(*tapes_.solution, "solution", n, 3 * n);
    if (tapes_.solution->reads_coordinates() || tapes_.solution->reads_velocities())
      throw std::invalid_argument("TapeEvaluator: the solution tape reads the state; it may read only t");
  }
  if (tapes_.initial_state) {
    check_tape(*tapes_.initial_state, "initial state", n, 2 * n);
    if (tapes_.initial_state->reads_time() || tapes_.initial_state->reads_coordinates() ||
        tapes_.initial_state->reads_velocities())
      throw std::invalid_argument("TapeEvaluator: the initial state tape reads t, q or q'");
  }
  if (tapes_.position_residual.reads_velocities())
    throw std::invalid_argument("TapeEvaluator: the position residual tape reads velocities");
  if (tapes_.position_residual.outputs() > s || tapes_.velocity_residual.outputs() > s ||
      tapes_.position_residual.outputs() > tapes_.velocity_residual.outputs())
    throw std::invalid_argument("TapeEvaluator: more residuals than constraints");

  const int m = tapes_.program_constraints;
  if (m < 0 || m > std::max(n - s, 0) || (m > 0) != tapes_.program_constraint_terms.has_value() ||
      (m > 0) != tapes_.program_constraint_position_residual.has_value() ||
      (m > 0) != tapes_.program_constraint_velocity_residual.has_value())
    throw std::invalid_argument("TapeEvaluator: " + std::to_string(m) +
                                " programs need their terms and residual tapes (and at most n - s of them)");
  if (m > 0) {
    check_tape(*tapes_.program_constraint_terms, "program terms", n, 2 * m * n + m);
    check_tape(*tapes_.program_constraint_position_residual, "program position residual", n, -1);
    check_tape(*tapes_.program_constraint_velocity_residual, "program velocity residual", n, -1);
    if (tapes_.program_constraint_position_residual->reads_velocities())
      throw std::invalid_argument("TapeEvaluator: the program position residual tape reads velocities");
    if (tapes_.program_constraint_position_residual->outputs() > m ||
        tapes_.program_constraint_velocity_residual->outputs() > m)
      throw std::invalid_argument("TapeEvaluator: more program residuals than programs");
  }

  std::size_t largest = static_cast<std::size_t>(tapes_.terms.registers());
  const auto widen = [&largest](const Tape& p) {
    largest = std::max(largest, static_cast<std::size_t>(p.registers()));
  };
  if (tapes_.complement) widen(*tapes_.complement);
  widen(tapes_.position_residual);
  widen(tapes_.velocity_residual);
  if (tapes_.energy) widen(*tapes_.energy);
  if (tapes_.energy_function) widen(*tapes_.energy_function);
  if (tapes_.power) widen(*tapes_.power);
  if (tapes_.solution) widen(*tapes_.solution);
  if (tapes_.initial_state) widen(*tapes_.initial_state);
  if (m > 0) {
    widen(*tapes_.program_constraint_terms);
    widen(*tapes_.program_constraint_position_residual);
    widen(*tapes_.program_constraint_velocity_residual);
  }
  scratch_ = largest;
  if (tapes_.sparsity) {
    // The nonzeros of A and b, between the tape's run and their scatter into dense matrices.
    values_offset_ = static_cast<std::size_t>(tapes_.terms.registers());
    scratch_ = std::max(scratch_, values_offset_ + a_size + b_size);
  }

  terms_ = PreparedTape::prepare(tapes_.terms, {static_cast<int>(a_size), n, n, static_cast<int>(b_size), s});
  if (tapes_.complement) complement_ = PreparedTape::prepare(*tapes_.complement, {(n - s) * n});
  position_residual_ = PreparedTape::prepare(tapes_.position_residual, {tapes_.position_residual.outputs()});
  velocity_residual_ = PreparedTape::prepare(tapes_.velocity_residual, {tapes_.velocity_residual.outputs()});
  if (tapes_.energy) energy_ = PreparedTape::prepare(*tapes_.energy, {1});
  if (tapes_.energy_function) energy_function_ = PreparedTape::prepare(*tapes_.energy_function, {1});
  if (tapes_.power) power_ = PreparedTape::prepare(*tapes_.power, {2});
  if (tapes_.solution) solution_ = PreparedTape::prepare(*tapes_.solution, {3 * n});
  if (tapes_.initial_state) initial_state_ = PreparedTape::prepare(*tapes_.initial_state, {2 * n});
  if (m > 0) {
    program_sizes_[0] = program_sizes_[2] = static_cast<std::size_t>(m) * static_cast<std::size_t>(n);
    program_sizes_[1] = static_cast<std::size_t>(m);
    program_terms_ = PreparedTape::prepare(*tapes_.program_constraint_terms, {m * n, m, n * m});
    program_phi_ = PreparedTape::prepare(*tapes_.program_constraint_position_residual,
                           {tapes_.program_constraint_position_residual->outputs()});
    program_f_ = PreparedTape::prepare(*tapes_.program_constraint_velocity_residual,
                         {tapes_.program_constraint_velocity_residual->outputs()});
  }
  if (tapes_.sparsity) {
    terms_function_ = terms_.calls_ ? &terms_scatter<true> : &terms_scatter<false>;
    sparse_function_ = terms_.calls_ ? &terms_any<true> : &terms_any<false>;
  } else {
    terms_function_ = terms_.calls_ ? choose_terms<true>(n, s) : choose_terms<false>(n, s);
  }
}

namespace {

// The value of one instruction on constant operands, computed by the interpreter itself.
double fold(const Instruction& in, double a, double b, double c, double* cosine) {
  double x[5] = {a, b, c, 0.0, 0.0};
  const Step once[2] = {Step{in.op, 0, 3, 0, 1, 2, in.k}, Step{}};
  double* const arrays[1] = {x};
  run_steps<true>(once, arrays);
  *cosine = x[4];
  return x[3];
}

// The steps in an order that makes runs long: each step still comes after the steps whose registers
// it reads, and among the steps whose operands are ready, one of the op and destination of the
// previous step comes first (else the earliest in tape order). Every step computes what it did,
// so the values are the same to the bit; only the dispatches, one per run, are fewer (a derived
// model's sums of products interleave mul, muladd and mulk_add step by step).
std::vector<Step> schedule(const std::vector<Step>& steps, std::size_t registers) {
  const std::size_t m = steps.size();
  const auto at = [](int i) { return static_cast<std::size_t>(i); };
  // The steps that read each step's result, in tape order (next[first[i]] .. next[first[i + 1]]):
  // counted, then filled, in one array rather than a vector per step.
  std::vector<int> writer(registers, -1);
  std::vector<int> pending(m, 0);
  std::vector<int> reader_of;  // per operand read from a step: (writer, reader) pairs
  reader_of.reserve(2 * m);
  for (std::size_t i = 0; i < m; ++i) {
    const Step& s = steps[i];
    const int operands[3] = {s.a, s.b, s.c};
    for (int k = 0; k < operand_count(s.op); ++k) {
      const int w = writer[at(operands[k])];
      if (w < 0) continue;  // an input
      reader_of.push_back(w);
      reader_of.push_back(static_cast<int>(i));
      ++pending[i];
    }
    if (s.dest == 0) {
      writer[at(s.to)] = static_cast<int>(i);
      if (s.op == Op::sincos) writer[at(s.to) + 1] = static_cast<int>(i);
    }
  }
  std::vector<int> first(m + 1, 0);
  for (std::size_t e = 0; e < reader_of.size(); e += 2) ++first[at(reader_of[e]) + 1];
  for (std::size_t i = 0; i < m; ++i) first[i + 1] += first[i];
  std::vector<int> next(reader_of.size() / 2);
  {
    std::vector<int> fill(first.begin(), first.end() - 1);
    for (std::size_t e = 0; e < reader_of.size(); e += 2) next[at(fill[at(reader_of[e])]++)] = reader_of[e + 1];
  }
  // The ready steps, smallest first: all of them in `ready`, and those of each run key in their
  // own heap, ready_by_key[slot[key]] (a key is two bytes; its heap is made when a step of it is
  // first ready). A step taken through its key stays in `ready` until it comes to the top, where
  // it is dropped.
  using Earliest = std::priority_queue<int, std::vector<int>, std::greater<int>>;
  std::vector<int> slot(std::size_t{1} << 16, -1);
  std::vector<Earliest> ready_by_key;
  Earliest ready;
  std::vector<char> taken(m, 0);
  const auto make_ready = [&](int i) {
    ready.push(i);
    int& k = slot[run_key(&steps[at(i)])];
    if (k < 0) {
      k = static_cast<int>(ready_by_key.size());
      ready_by_key.emplace_back();
    }
    ready_by_key[at(k)].push(i);
  };
  for (std::size_t i = 0; i < m; ++i)
    if (pending[i] == 0) make_ready(static_cast<int>(i));
  std::vector<Step> out;
  out.reserve(m);
  unsigned key = ~0u;  // no step's key
  for (;;) {
    while (!ready.empty() && taken[at(ready.top())]) ready.pop();
    if (ready.empty()) break;
    if (key >= slot.size() || slot[key] < 0 || ready_by_key[at(slot[key])].empty())
      key = run_key(&steps[at(ready.top())]);
    Earliest& same = ready_by_key[at(slot[key])];
    const int i = same.top();
    same.pop();
    taken[at(i)] = 1;
    out.push_back(steps[at(i)]);
    for (int e = first[at(i)]; e < first[at(i) + 1]; ++e)
      if (--pending[at(next[at(e)])] == 0) make_ready(next[at(e)]);
  }
  return out;
}

// Constants folded, constant operands made immediates; tape order, every step to a register.
// known[reg] says that the register holds the constant value[reg].
std::vector<Step> fold_constants(const Tape& tape, std::vector<char>& known, std::vector<double>& value) {
  const std::vector<Instruction>& code = tape.code();
  const int inputs = tape.inputs();
  const auto at = [](int reg) { return static_cast<std::size_t>(reg); };
  std::vector<Step> steps;
  for (std::size_t i = 0; i < code.size(); ++i) {
    const Instruction& in = code[i];
    if (in.op == Op::nop) continue;  // the cosine of a sincos
    const int to = inputs + static_cast<int>(i);
    Step step{in.op, 0, to, in.a, in.b, in.c, in.k};
    const int operands[3] = {in.a, in.b, in.c};
    const int count = operand_count(in.op);
    bool constant_operands = in.op != Op::constant;
    for (int j = 0; j < count; ++j) constant_operands = constant_operands && known[at(operands[j])];
    if (constant_operands) {
      double cosine = 0.0;
      const double result = fold(in, value[at(in.a)], value[at(in.b)], value[at(in.c)], &cosine);
      if (in.op == Op::sincos) {
        known[at(to + 1)] = 1;
        value[at(to + 1)] = cosine;
        steps.push_back(Step{Op::constant, 0, to + 1, 0, 0, 0, cosine});
      }
      step = Step{Op::constant, 0, to, 0, 0, 0, result};
    }
    if (step.op == Op::constant) {
      known[at(to)] = 1;
      value[at(to)] = step.k;
      steps.push_back(step);
      continue;
    }
    // A constant operand as the immediate: a + k and k * a commute exactly, a - k is a + (-k),
    // k / a is div_k and a * k + c is mulk_add, all with the same rounding.
    const auto is_known = [&](int reg) { return known[at(reg)] != 0; };
    switch (step.op) {
      case Op::add:
      case Op::mul:
        if (is_known(step.a) || is_known(step.b)) {
          const bool first = is_known(step.a);
          step = Step{step.op == Op::add ? Op::add_k : Op::mul_k, 0, to, first ? step.b : step.a, 0, 0,
                      value[at(first ? step.a : step.b)]};
        }
        break;
      case Op::sub:
        if (is_known(step.b)) step = Step{Op::add_k, 0, to, step.a, 0, 0, -value[at(step.b)]};
        break;
      case Op::div:
        if (is_known(step.a)) step = Step{Op::div_k, 0, to, step.b, 0, 0, value[at(step.a)]};
        break;
      case Op::muladd:
        if (is_known(step.a) || is_known(step.b)) {
          const bool first = is_known(step.a);
          step = Step{Op::mulk_add, 0, to, first ? step.b : step.a, step.c, 0, value[at(first ? step.a : step.b)]};
        }
        break;
      case Op::mulsub:
        // c - k x = (-k) x + c: the negation is exact, and a - b is a + (-b) in IEEE arithmetic.
        if (is_known(step.a) || is_known(step.b)) {
          const bool first = is_known(step.a);
          step = Step{Op::mulk_add, 0, to, first ? step.b : step.a, step.c, 0, -value[at(first ? step.a : step.b)]};
        }
        break;
      default:
        break;
    }
    steps.push_back(step);
  }
  return steps;
}

// Where an output wants a register's value: array (1-based: 0 is the registers) and index.
struct Want {
  int array, index;
};

// Only the steps an output needs (keep), found backwards; and how many kept steps read each register.
void mark_live(const std::vector<Step>& steps, const std::vector<std::vector<Want>>& wants, std::vector<char>& keep,
               std::vector<int>& readers) {
  const std::size_t registers = wants.size();
  const auto at = [](int reg) { return static_cast<std::size_t>(reg); };
  std::vector<char> live(registers, 0);
  keep.assign(steps.size(), 0);
  readers.assign(registers, 0);
  for (std::size_t r = 0; r < registers; ++r) live[r] = !wants[r].empty();
  for (std::size_t i = steps.size(); i-- > 0;) {
    const Step& step = steps[i];
    if (!live[at(step.to)] && !(step.op == Op::sincos && live[at(step.to + 1)])) continue;
    keep[i] = 1;
    const int operands[3] = {step.a, step.b, step.c};
    for (int k = 0; k < operand_count(step.op); ++k) {
      live[at(operands[k])] = 1;
      ++readers[at(operands[k])];
    }
  }
}

// A product a * b (or a * a) read only by a k * x or k * x + c that follows becomes part of it:
// k * (a * b) is mulk, k * (a * b) + c mulk_muladd, which round exactly as the two steps did.
// A parameter times a product of the state, c * p * (a * b) with c * p in the parameter stage,
// then costs one step, as it did when parameters were numbers in the tape.
void fuse_products(std::vector<Step>& steps, const std::vector<std::vector<Want>>& wants, std::vector<char>& keep,
                   const std::vector<int>& readers) {
  const auto at = [](int reg) { return static_cast<std::size_t>(reg); };
  std::vector<int> producer(wants.size(), -1);
  for (std::size_t i = 0; i < steps.size(); ++i)
    if (keep[i]) producer[at(steps[i].to)] = static_cast<int>(i);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    Step& step = steps[i];
    if (!keep[i] || (step.op != Op::mul_k && step.op != Op::mulk_add)) continue;
    const int j = producer[at(step.a)];
    if (j < 0 || readers[at(step.a)] != 1 || !wants[at(step.a)].empty()) continue;
    const Step& product = steps[static_cast<std::size_t>(j)];
    if (product.op != Op::mul && product.op != Op::square) continue;
    const int a = product.a, b = product.op == Op::square ? product.a : product.b;
    if (step.op == Op::mul_k)
      step = Step{Op::mulk, 0, step.to, a, b, 0, step.k};
    else
      step = Step{Op::mulk_muladd, 0, step.to, a, b, step.b, step.k};
    keep[static_cast<std::size_t>(j)] = 0;
  }
}

}  // namespace

PreparedTape PreparedTape::prepare(const Tape& tape, const std::vector<int>& sizes) {
  if (tape.reads_parameters())
    throw std::logic_error("PreparedTape: the tape reads parameters; prepare the tape bind() returns");
  const int inputs = tape.inputs();
  const std::size_t registers = static_cast<std::size_t>(tape.registers());
  const auto at = [](int reg) { return static_cast<std::size_t>(reg); };
  std::vector<char> known(registers, 0);
  std::vector<double> value(registers, 0.0);
  std::vector<Step> steps = fold_constants(tape, known, value);

  // The outputs: constants into the image, the others wanted from their registers.
  PreparedTape p;
  p.steps_.clear();
  p.n_ = tape.coordinates();
  p.registers_ = tape.registers();
  std::vector<std::vector<Want>> wants(registers);
  const std::vector<Output>& outputs = tape.output_list();
  std::size_t j = 0;
  for (std::size_t array = 0; array < sizes.size(); ++array)
    for (int i = 0; i < sizes[array]; ++i, ++j) {
      const Output& o = outputs[j];
      const bool constant = o.reg < 0 || known[at(o.reg)];
      p.image_.push_back(o.reg < 0 ? o.value : constant ? value[at(o.reg)] : 0.0);
      if (!constant) wants[at(o.reg)].push_back(Want{static_cast<int>(array) + 1, i});
    }

  std::vector<char> keep;
  std::vector<int> readers;
  mark_live(steps, wants, keep, readers);
  fuse_products(steps, wants, keep, readers);

  // Each step in place: an output computed once for all is written where it goes; a copy (1 * x,
  // exact) serves an input or a sincos, a clone of its step every further output of a register.
  const int n = tape.coordinates();
  const auto note_read = [&p, n](int reg) {
    if (reg == 0)
      p.reads_[0] = true;
    else if (reg <= n)
      p.reads_[1] = true;
    else if (reg <= 2 * n)
      p.reads_[2] = true;
  };
  const auto place = [&p, &note_read](const Step& step, int dest, int to) {
    Step x = step;
    x.dest = static_cast<std::uint8_t>(dest);
    x.to = to;
    p.steps_.push_back(x);
    const int operands[3] = {x.a, x.b, x.c};
    for (int k = 0; k < operand_count(x.op); ++k) note_read(operands[k]);
    p.calls_ = p.calls_ || calls_library(x.op);
  };
  const auto copy = [&place](int reg, const Want& w) {
    place(Step{Op::mul_k, 0, 0, reg, 0, 0, 1.0}, w.array, w.index);
  };
  for (int r = 0; r < inputs; ++r)
    for (const Want& w : wants[at(r)]) copy(r, w);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (!keep[i]) continue;
    const Step& step = steps[i];
    const std::vector<Want>& want = wants[at(step.to)];
    if (step.op == Op::sincos) {
      place(step, 0, step.to);
      for (const Want& w : want) copy(step.to, w);
      for (const Want& w : wants[at(step.to + 1)]) copy(step.to + 1, w);
      continue;
    }
    std::size_t first = 0;
    if (!want.empty() && readers[at(step.to)] == 0) {
      place(step, want[0].array, want[0].index);
      first = 1;
    } else {
      place(step, 0, step.to);
    }
    for (std::size_t w = first; w < want.size(); ++w) place(step, want[w].array, want[w].index);
  }
  p.steps_ = schedule(p.steps_, registers);
  p.steps_.push_back(Step{});
  return p;
}

namespace {

// The arrays a step of the terms may write: the registers, then A, Q, G, b, b0. Written one
// pointer at a time (store_fence), since every step reads one of them back.
struct TermsArrays {
  double* arrays[6];
  NHDYN_ALWAYS_INLINE TermsArrays(double* registers, const TermsOut& out) {
    arrays[0] = registers;
    store_fence();
    arrays[1] = out.A;
    store_fence();
    arrays[2] = out.Q;
    store_fence();
    arrays[3] = out.G;
    store_fence();
    arrays[4] = out.b;
    store_fence();
    arrays[5] = out.b0;
  }
};

template <int N>
NHDYN_ALWAYS_INLINE void copy_fixed(const double* from, double* to) {
  if constexpr (N > 0) std::memcpy(to, from, N * sizeof(double));
}

}  // namespace

// For a small model the fixed cost of the call dominates (19 outputs for n = 3, s = 1, most of
// them constant): with the sizes known at compile time the input copies and the image copies
// become a few vector moves instead of loops.
template <int N, int S, bool Calls>
void TapeEvaluator::terms_fixed(const TapeEvaluator& self, double t, const double* q, const double* v,
                                   double* scratch, const TermsOut& out) {
  const PreparedTape& p = self.terms_;
  load_inputs(p.reads_, N, t, q, v, scratch);
  const double* image = p.image_.data();
  copy_fixed<N * N>(image, out.A);
  copy_fixed<N>(image + N * N, out.Q);
  copy_fixed<N>(image + N * N + N, out.G);
  copy_fixed<S * N>(image + N * N + 2 * N, out.b);
  copy_fixed<S>(image + N * N + 2 * N + S * N, out.b0);
  run_steps<Calls>(p.steps_.data(), TermsArrays(scratch, out).arrays);
}

template <bool Calls>
void TapeEvaluator::terms_any(const TapeEvaluator& self, double t, const double* q, const double* v,
                                 double* scratch, const TermsOut& out) {
  const PreparedTape& p = self.terms_;
  load_inputs(p.reads_, static_cast<std::size_t>(self.n_), t, q, v, scratch);
  const TermsArrays arrays(scratch, out);
  const double* image = p.image_.data();
  for (int a = 0; a < 5; ++a) {
    const std::size_t size = self.terms_sizes_[a];
    for (std::size_t i = 0; i < size; ++i) arrays.arrays[a + 1][i] = image[i];
    image += size;
  }
  run_steps<Calls>(p.steps_.data(), arrays.arrays);
}

template <bool Calls>
void TapeEvaluator::terms_scatter(const TapeEvaluator& self, double t, const double* q, const double* v,
                                     double* scratch, const TermsOut& out) {
  double* const a_values = scratch + self.values_offset_;
  double* const b_values = a_values + self.terms_sizes_[0];
  terms_any<Calls>(self, t, q, v, scratch, TermsOut{a_values, out.Q, out.G, b_values, out.b0});
  const auto scatter = [](const SparsityPattern& pattern, const double* values, double* dense) {
    const std::size_t rows = static_cast<std::size_t>(pattern.rows);
    std::fill(dense, dense + rows * static_cast<std::size_t>(pattern.cols), 0.0);
    for (int j = 0; j < pattern.cols; ++j)
      for (int k = pattern.outer[static_cast<std::size_t>(j)]; k < pattern.outer[static_cast<std::size_t>(j) + 1]; ++k)
        dense[static_cast<std::size_t>(j) * rows + static_cast<std::size_t>(pattern.inner[static_cast<std::size_t>(k)])] =
            values[k];
  };
  scatter(self.tapes_.sparsity->A, a_values, out.A);
  scatter(self.tapes_.sparsity->b, b_values, out.b);
}

template <bool Calls>
TapeEvaluator::TermsFunction TapeEvaluator::choose_terms(int n, int s) {
  switch (n * 8 + s) {
    case 1 * 8 + 0: return &terms_fixed<1, 0, Calls>;
    case 2 * 8 + 0: return &terms_fixed<2, 0, Calls>;
    case 2 * 8 + 1: return &terms_fixed<2, 1, Calls>;
    case 3 * 8 + 0: return &terms_fixed<3, 0, Calls>;
    case 3 * 8 + 1: return &terms_fixed<3, 1, Calls>;
    case 3 * 8 + 2: return &terms_fixed<3, 2, Calls>;
    case 4 * 8 + 0: return &terms_fixed<4, 0, Calls>;
    case 4 * 8 + 1: return &terms_fixed<4, 1, Calls>;
    case 4 * 8 + 2: return &terms_fixed<4, 2, Calls>;
    case 4 * 8 + 3: return &terms_fixed<4, 3, Calls>;
    default: return &terms_any<Calls>;
  }
}

void TapeEvaluator::terms(double t, const double* q, const double* v, double* scratch,
                             const TermsOut& out) const {
  terms_function_(*this, t, q, v, scratch, out);
}

void TapeEvaluator::sparse_terms(double t, const double* q, const double* v, double* scratch,
                                    const TermsOut& out) const {
  if (sparse_function_ == nullptr)
    throw std::logic_error("TapeEvaluator::sparse_terms: this model was compiled dense (sparsity() is null)");
  sparse_function_(*this, t, q, v, scratch, out);
}

void PreparedTape::run(double t, const double* q, const double* v, double* registers, double* outputs) const {
  load_inputs(reads_, static_cast<std::size_t>(n_), t, q, v, registers);
  const std::size_t m = image_.size();
  for (std::size_t i = 0; i < m; ++i) outputs[i] = image_[i];
  double* arrays[2];
  arrays[0] = registers;
  store_fence();
  arrays[1] = outputs;
  if (calls_)
    run_steps<true>(steps_.data(), arrays);
  else
    run_steps<false>(steps_.data(), arrays);
}

void TapeEvaluator::complement(double t, const double* q, const double* v, double* scratch, double* D) const {
  if (!tapes_.complement) return;
  complement_.run(t, q, v, scratch, D);
}

void TapeEvaluator::position_residual(double t, const double* q, double* scratch, double* phi) const {
  position_residual_.run(t, q, nullptr, scratch, phi);
}

void TapeEvaluator::velocity_residual(double t, const double* q, const double* v, double* scratch,
                                         double* f) const {
  velocity_residual_.run(t, q, v, scratch, f);
}

void TapeEvaluator::program_constraint_terms(double t, const double* q, const double* v, double* scratch,
                                                double* b_p, double* b_p0, double* B) const {
  if (!tapes_.program_constraint_terms) return;
  const PreparedTape& p = program_terms_;
  load_inputs(p.reads_, static_cast<std::size_t>(n_), t, q, v, scratch);
  double* arrays[4];
  arrays[0] = scratch;
  store_fence();
  arrays[1] = b_p;
  store_fence();
  arrays[2] = b_p0;
  store_fence();
  arrays[3] = B;
  const double* image = p.image_.data();
  for (int a = 0; a < 3; ++a) {
    for (std::size_t i = 0; i < program_sizes_[a]; ++i) arrays[a + 1][i] = image[i];
    image += program_sizes_[a];
  }
  if (p.calls_)
    run_steps<true>(p.steps_.data(), arrays);
  else
    run_steps<false>(p.steps_.data(), arrays);
}

void TapeEvaluator::program_constraint_position_residual(double t, const double* q, double* scratch,
                                                            double* phi) const {
  if (!tapes_.program_constraint_position_residual) return;
  program_phi_.run(t, q, nullptr, scratch, phi);
}

void TapeEvaluator::program_constraint_velocity_residual(double t, const double* q, const double* v,
                                                            double* scratch, double* f) const {
  if (!tapes_.program_constraint_velocity_residual) return;
  program_f_.run(t, q, v, scratch, f);
}

double TapeEvaluator::energy(double t, const double* q, const double* v, double* scratch) const {
  if (!tapes_.energy) return 0.0;
  double e = 0.0;
  energy_.run(t, q, v, scratch, &e);
  return e;
}

double TapeEvaluator::energy_function(double t, const double* q, const double* v, double* scratch) const {
  if (!tapes_.energy_function) return energy(t, q, v, scratch);  // T = T2: h = E
  double h = 0.0;
  energy_function_.run(t, q, v, scratch, &h);
  return h;
}

void TapeEvaluator::power(double t, const double* q, const double* v, double* scratch, double* out) const {
  if (!tapes_.power) {
    out[0] = out[1] = 0.0;
    return;
  }
  power_.run(t, q, v, scratch, out);
}

void TapeEvaluator::solution(double t, double* scratch, double* qva) const {
  if (!tapes_.solution) return;
  solution_.run(t, nullptr, nullptr, scratch, qva);
}

void TapeEvaluator::initial_state(double* scratch, double* q0, double* v0) const {
  if (!tapes_.initial_state) return;
  std::vector<double> out(2 * static_cast<std::size_t>(n_));
  initial_state_.run(0.0, nullptr, nullptr, scratch, out.data());
  std::copy(out.begin(), out.begin() + n_, q0);
  std::copy(out.begin() + n_, out.end(), v0);
}

}  // namespace nhdyn
