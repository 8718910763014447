// Straight-line code on doubles (tapes): the numeric form of a model compiled from symbols
// (symbolic/compile.hpp). A Tape is a flat array of instructions in single-assignment form with
// no branches and no allocation when it runs, so its cost is one switch dispatch per run of
// instructions of the same op, plus the arithmetic. Registers: r[0] = t, r[1 + i] = q_i,
// r[1 + n + i] = q'_i (the inputs, copied in when the tape starts), then instruction j writes
// register inputs() + j and reads only registers below it. Outputs are registers or constants;
// constant outputs cost no instruction. A `parameter` instruction reads the value of a model
// parameter: the tapes as compiled are parametric, and binding them to values (Tape::bind)
// turns those instructions into constants.
// TapeEvaluator runs such tapes as an Evaluator: all the terms A, Q, G, b, b0 in one
// tape (common subexpressions computed once), the complement D, the residuals and the energy
// in their own, each in a prepared form: what depends on constants and parameters only is
// computed once when the evaluator is bound to parameter values (with_parameters, the "parameter
// stage"), what no output needs is dropped, and results go straight to the output arrays.
// Generated C++ (symbolic/codegen.hpp) prints the same tapes as source code.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/model/evaluator.hpp"

namespace nhdyn {

// One operation. `a`, `b`, `c` are operand registers, `k` an immediate double; r is the register
// the instruction writes. Integer powers are repeated multiplications, never std::pow.
enum class Op : std::uint8_t {
  constant,     // r = k
  add,          // r = a + b
  sub,          // r = a - b
  mul,          // r = a * b
  div,          // r = a / b
  neg,          // r = -a
  add_k,        // r = a + k
  mul_k,        // r = k * a
  mulk,         // r = k * (a * b)
  div_k,        // r = k / a       (k = 1: the reciprocal)
  muladd,       // r = a * b + c   (two roundings: not std::fma)
  mulsub,       // r = c - a * b
  mulk_add,     // r = k * a + b
  mulk_muladd,  // r = k * (a * b) + c
  square,       // r = a * a
  cube,         // r = a * a * a
  powi,         // r = a^k for an integer k != 0, by repeated squaring (negative: 1 / a^-k)
  pow,          // r = std::pow(a, b)
  pow_k,        // r = std::pow(a, k)
  sqrt,
  sin,
  cos,
  sincos,       // r = sin(a) and r + 1 = cos(a); the next instruction is its `nop` companion
  tan,
  exp,
  log,
  abs,
  asin,
  acos,
  atan,
  atan2,        // r = atan2(a, b)
  sinh,
  cosh,
  tanh,
  parameter,    // r = the value of model parameter a (an index, not a register); see Tape::bind
  nop,          // the cos slot of a sincos; never pushed on its own
};

// The table of operations: one row per Op, in its order, read by the interpreter and the tangent
// (operand_count), describe() (op_name) and the C++ printer of jit and codegen
// (tape_printer.hpp). `cpp` is the operation as a C++ expression: {a}, {b}, {c} its operand
// registers, {k} its immediate as a double, {n} the immediate as an integer, {p} the parameter it
// reads. A sincos prints its sine; the cosine is its nop companion's, printed with it.
struct OpInfo {
  Op op;
  const char* name;  // as describe() prints it ("mulk_add", "sin", ...)
  int operands;      // register operands: 0, 1, 2 or 3
  const char* cpp;
};

inline constexpr OpInfo kOps[] = {
    {Op::constant, "constant", 0, "{k}"},
    {Op::add, "add", 2, "{a} + {b}"},
    {Op::sub, "sub", 2, "{a} - {b}"},
    {Op::mul, "mul", 2, "{a} * {b}"},
    {Op::div, "div", 2, "{a} / {b}"},
    {Op::neg, "neg", 1, "-{a}"},
    {Op::add_k, "add_k", 1, "{a} + {k}"},
    {Op::mul_k, "mul_k", 1, "{k} * {a}"},
    {Op::mulk, "mulk", 2, "{k} * ({a} * {b})"},
    {Op::div_k, "div_k", 1, "{k} / {a}"},
    {Op::muladd, "muladd", 3, "{a} * {b} + {c}"},
    {Op::mulsub, "mulsub", 3, "{c} - {a} * {b}"},
    {Op::mulk_add, "mulk_add", 2, "{k} * {a} + {b}"},
    {Op::mulk_muladd, "mulk_muladd", 3, "{k} * ({a} * {b}) + {c}"},
    {Op::square, "square", 1, "{a} * {a}"},
    {Op::cube, "cube", 1, "{a} * {a} * {a}"},
    {Op::powi, "powi", 1, "powi({a}, {n})"},
    {Op::pow, "pow", 2, "std::pow({a}, {b})"},
    {Op::pow_k, "pow_k", 1, "std::pow({a}, {k})"},
    {Op::sqrt, "sqrt", 1, "std::sqrt({a})"},
    {Op::sin, "sin", 1, "std::sin({a})"},
    {Op::cos, "cos", 1, "std::cos({a})"},
    {Op::sincos, "sincos", 1, "std::sin({a})"},
    {Op::tan, "tan", 1, "std::tan({a})"},
    {Op::exp, "exp", 1, "std::exp({a})"},
    {Op::log, "log", 1, "std::log({a})"},
    {Op::abs, "abs", 1, "std::abs({a})"},
    {Op::asin, "asin", 1, "std::asin({a})"},
    {Op::acos, "acos", 1, "std::acos({a})"},
    {Op::atan, "atan", 1, "std::atan({a})"},
    {Op::atan2, "atan2", 2, "std::atan2({a}, {b})"},
    {Op::sinh, "sinh", 1, "std::sinh({a})"},
    {Op::cosh, "cosh", 1, "std::cosh({a})"},
    {Op::tanh, "tanh", 1, "std::tanh({a})"},
    {Op::parameter, "parameter", 0, "{p}"},
    {Op::nop, "nop", 0, ""},
};

// The row of `op` (each row sits at its Op's index: checked where the table is defined).
constexpr const OpInfo& op_info(Op op) { return kOps[static_cast<std::size_t>(op)]; }

// Number of register operands of `op` (0, 1, 2 or 3).
int operand_count(Op op);
// The instruction's name as printed by describe() ("mulk_add", "sin", ...).
const char* op_name(Op op);

struct Instruction {
  Op op = Op::nop;
  std::int32_t a = 0;
  std::int32_t b = 0;
  std::int32_t c = 0;
  double k = 0.0;
};

// An instruction as the interpreter runs it: it writes to[...] of the array `dest` (0: the
// registers; TapeEvaluator lets a step write an output array directly) from operand registers
// a, b, c and immediate k. A sincos is one step; a nop ends a list of steps. Consecutive steps of
// the same op and dest form a run, which costs one dispatch.
struct Step {
  Op op = Op::nop;
  std::uint8_t dest = 0;  // op and dest are the first two bytes: the interpreter reads them at once
  std::int32_t to = 0;
  std::int32_t a = 0;
  std::int32_t b = 0;
  std::int32_t c = 0;
  double k = 0.0;
};

// An output of a tape: register `reg`, or the constant `value` when reg < 0.
struct Output {
  int reg = -1;
  double value = 0.0;
};

class Tape {
 public:
  // A tape of a system with `coordinates` coordinates (its inputs are t, q and q') and
  // `parameters` parameters (read by `parameter` instructions).
  explicit Tape(int coordinates = 0, int parameters = 0);

  int coordinates() const { return n_; }
  int parameters() const { return parameters_; }
  // The input registers: t, q_i, q'_i; inputs() = 1 + 2 n of them.
  int inputs() const { return 1 + 2 * n_; }
  static constexpr int time_register() { return 0; }
  int coordinate_register(int i) const;  // throws std::invalid_argument out of [0, n)
  int velocity_register(int i) const;

  // Appends an instruction and returns the register it writes. Throws std::invalid_argument when
  // an operand register is not written yet, a powi exponent is not a nonzero integer of magnitude
  // at most 2^20, or op is `nop`. A sincos also appends its companion: it returns the register of
  // the sine, the cosine is the next one.
  int push(Op op, int a = 0, int b = 0, int c = 0, double k = 0.0);
  int push_constant(double value) { return push(Op::constant, 0, 0, 0, value); }
  // Appends `r = parameter index`; throws std::invalid_argument out of [0, parameters()).
  int push_parameter(int index) { return push(Op::parameter, index); }
  // Appends the next output: a register, or a constant (which costs no instruction).
  void add_output(int reg);
  void add_constant_output(double value);

  // Number of registers run() needs: the inputs, then one per instruction.
  int registers() const { return inputs() + static_cast<int>(code_.size()); }
  int outputs() const { return static_cast<int>(outputs_.size()); }
  const std::vector<Instruction>& code() const { return code_; }
  const std::vector<Output>& output_list() const { return outputs_; }
  // Number of instructions with this op.
  int count(Op op) const;
  bool reads_time() const { return reads_[0]; }
  bool reads_coordinates() const { return reads_[1]; }
  bool reads_velocities() const { return reads_[2]; }
  bool reads_parameters() const { return reads_parameters_; }

  // The tape with every `parameter` instruction replaced by the constant values[index]
  // (`count` values, at least parameters()); register numbers and outputs stay as they are. A
  // tape that reads no parameter comes back as it is.
  Tape bind(const double* values, std::size_t count) const;

  // Runs the tape: q and v hold coordinates() values (v may be null when the tape reads no
  // velocity), `registers` registers() doubles, `outputs` outputs() doubles. Allocates nothing.
  // Throws std::logic_error for a tape that reads parameters: bind() it first.
  void run(double t, const double* q, const double* v, double* registers, double* outputs) const;
  // The same without writing the outputs: register outputs stay in registers[output_list()[i].reg].
  void execute(double t, const double* q, const double* v, double* registers) const;

  // One line per instruction ("r9 = mul q2 r8"), then the outputs: for debugging and tests.
  std::string describe() const;
  // "t", "q2", "v0" for an input register, "r12" otherwise.
  std::string register_name(int reg) const;

 private:
  void note_read(int reg);

  int n_ = 0;
  int parameters_ = 0;
  bool reads_parameters_ = false;
  std::vector<Instruction> code_;
  std::vector<Step> steps_;  // code_ as the interpreter runs it, ended by a nop
  bool calls_ = false;       // an instruction calls the math library (sin, pow, sqrt...)
  std::vector<Output> outputs_;
  bool reads_[3] = {false, false, false};  // t, q, q'
};

// A tape ready to run, prepared from a tape whose parameters are bound (Tape::bind) as
// TapeEvaluator prepares its own (below: constants folded, products fused, dead steps left out,
// steps grouped by op): the same values to the bit, in fewer steps. Its steps write destination 0
// (the registers) or 1 + i (the i-th output array), end with a nop, and every output has its place
// in `image` (its constant, 0 where a step writes it), copied before the steps run. The tapes run
// at every output row beside the evaluator's (contact forces, derived outputs) are run this way.
class PreparedTape {
 public:
  // A tape without outputs: run() writes nothing.
  PreparedTape() = default;
  // `tape`, whose outputs fill one array. Throws std::logic_error for a tape that reads parameters.
  explicit PreparedTape(const Tape& tape) : PreparedTape(prepare(tape, {tape.outputs()})) {}
  // `tape`, whose outputs fill arrays of the given sizes one after the other.
  static PreparedTape prepare(const Tape& tape, const std::vector<int>& sizes);

  int outputs() const { return static_cast<int>(image_.size()); }
  int registers() const { return registers_; }
  // The number of steps run() runs (a sincos counts one).
  int steps() const { return static_cast<int>(steps_.size()) - 1; }
  // Tape::run's inputs and outputs (one output array): `registers` holds registers() doubles.
  // Allocates nothing.
  void run(double t, const double* q, const double* v, double* registers, double* outputs) const;

 private:
  friend class TapeEvaluator;  // runs the steps into its own output arrays (the terms' five)
  std::vector<Step> steps_{Step{}};        // ended by a nop
  bool calls_ = false;                     // a step calls the math library
  bool reads_[3] = {false, false, false};  // t, q, q'
  std::vector<double> image_;
  int n_ = 0;
  int registers_ = 0;
};

// The tapes of a compiled model, with the output each must have (n coordinates, s
// constraints, p of them at position level, r = number at position or velocity level). Each may
// read the model's parameters (in the order of Model::parameters).
struct ModelTapes {
  // outputs: A (n x n, col-major), Q (n), G (n), b (s x n, col-major), b0 (s); with a sparsity,
  // only its nonzeros of A and b (compressed columns) in their places
  Tape terms;
  std::optional<Tape> complement;  // outputs: D, k x n col-major (k = n - s)
  Tape position_residual;         // outputs: phi (p); reads no velocity
  Tape velocity_residual;         // outputs: f (r)
  std::optional<Tape> energy;     // one output: T + V
  std::optional<Tape> solution;   // outputs: q (n), q' (n), q'' (n) of the exact motion; reads only t
  std::optional<TermsSparsity> sparsity;  // the nonzeros of A and b that terms writes, if not all
  std::optional<Tape> initial_state = std::nullopt;  // outputs: q0 (n), q'0 (n); reads parameters only
  int parameters = 0;                // number of parameters the tapes may read
  // Program motion (docs/derivations/program-motion.md), with m programs: outputs b_p (m x n
  // col-major), b_p0 (m), B (n x m col-major); the programs' position residuals (reading no
  // velocity) and velocity residuals. Absent when m = 0.
  int program_constraints = 0;       // m
  std::optional<Tape> program_constraint_terms = std::nullopt;
  std::optional<Tape> program_constraint_position_residual = std::nullopt;
  std::optional<Tape> program_constraint_velocity_residual = std::nullopt;
  // The energy balance (docs/derivations/energy-balance.md), for a model whose energy tape is
  // E = T + V of any system (not only a conservative one): h where it differs from E, and the
  // power Q_nc . q', -dL/dt|explicit where it is not identically zero.
  bool energy_balance = false;
  std::optional<Tape> energy_function = std::nullopt;  // one output: h = q' . dT/dq' - T + V
  std::optional<Tape> power = std::nullopt;            // outputs: Q_nc . q', -dL/dt|explicit
};

// An Evaluator that runs straight-line tapes. It keeps the parametric tapes (shared by every
// evaluator bound from them) and the values it computes with; each tape is bound to those
// values and prepared once, when the evaluator is built (with_parameters builds another):
// - an instruction whose operands are all constants or parameters becomes a constant, computed by
//   the interpreter itself so to the same bits (a parameter-only subexpression costs nothing per
//   call: this is the parameter stage);
// - a constant operand of add, sub, mul, div, muladd or mulsub becomes the immediate of add_k,
//   mul_k, div_k or mulk_add, which round alike;
// - a product a * b (or a * a) read only by a k * x or k * x + c becomes part of it, mulk or
//   mulk_muladd, k * (a * b) [+ c] as before (the compiler emits a parameter coefficient times a
//   state product as (c p) * s for this);
// - constant outputs go to an image copied whole before the instructions run; an instruction
//   whose result is an output and no operand writes the output array itself (a further output of
//   the same value costs one more instruction: its clone, or a copy 1 * x of an input or sincos);
// - instructions that no output needs are left out;
// - the steps are reordered, each still after the steps it reads, so that steps of one op and
//   destination follow each other: the interpreter dispatches once per such run (a derived model's
//   terms interleave mul, muladd and mulk_add step by step; the bicycle's 3963 steps are 215 runs).
// Tapes that call no math library function run in an interpreter without those calls, whose
// fixed cost per call is lower. The prepared form computes the same values as the tapes, to the
// bit. scratch_size() is the largest register count of the tapes.
class TapeEvaluator final : public Evaluator {
 public:
  // Throws std::invalid_argument when a tape's output count or coordinate count does not
  // match n and s, the position residual reads velocities, or there are fewer `parameters` than
  // tapes.parameters.
  TapeEvaluator(int n, int s, ModelTapes tapes, std::vector<double> parameters = {});
  // The same tapes bound to other values (no copy of the parametric tapes).
  TapeEvaluator(const TapeEvaluator& other, std::vector<double> parameters);

  int n() const { return n_; }
  int s() const { return s_; }
  // The tapes bound to this evaluator's parameter values: `parameter` instructions are
  // constants (what linearization's tangents and tests run).
  const ModelTapes& tapes() const { return tapes_; }
  // The tapes as compiled, reading the parameters (generated code prints these).
  const ModelTapes& parametric_tapes() const { return *parametric_; }
  const std::vector<double>& parameter_values() const { return parameters_; }

  std::shared_ptr<const Evaluator> with_parameters(const double* values, std::size_t count) const override;
  bool has_initial_state() const override { return tapes_.initial_state.has_value(); }
  void initial_state(double* scratch, double* q0, double* v0) const override;
  // Number of operations the prepared terms run per call (a sincos counts one).
  int terms_operations() const { return terms_.steps(); }

  std::size_t scratch_size() const override { return scratch_; }
  // The Evaluator interface; each call runs one tape and writes its outputs. A sparse terms
  // tape fills a dense A and b by zeroing them and scattering its nonzeros (through scratch).
  void terms(double t, const double* q, const double* v, double* scratch, const TermsOut& out) const override;
  const TermsSparsity* sparsity() const override {
    return tapes_.sparsity ? &*tapes_.sparsity : nullptr;
  }
  void sparse_terms(double t, const double* q, const double* v, double* scratch, const TermsOut& out) const override;
  bool has_complement() const override { return tapes_.complement.has_value(); }
  void complement(double t, const double* q, const double* v, double* scratch, double* D) const override;
  void position_residual(double t, const double* q, double* scratch, double* phi) const override;
  void velocity_residual(double t, const double* q, const double* v, double* scratch, double* f) const override;
  bool has_energy() const override { return tapes_.energy.has_value(); }
  double energy(double t, const double* q, const double* v, double* scratch) const override;
  bool has_program_constraints() const override { return tapes_.program_constraint_terms.has_value(); }
  void program_constraint_terms(double t, const double* q, const double* v, double* scratch, double* b_p,
                                double* b_p0, double* B) const override;
  void program_constraint_position_residual(double t, const double* q, double* scratch, double* phi) const override;
  void program_constraint_velocity_residual(double t, const double* q, const double* v, double* scratch,
                                            double* f) const override;
  bool has_energy_balance() const override { return tapes_.energy_balance && tapes_.energy.has_value(); }
  bool power_is_zero() const override { return !tapes_.power.has_value(); }
  bool energy_function_is_energy() const override { return !tapes_.energy_function.has_value(); }
  double energy_function(double t, const double* q, const double* v, double* scratch) const override;
  void power(double t, const double* q, const double* v, double* scratch, double* out) const override;
  bool has_solution() const override { return tapes_.solution.has_value(); }
  void solution(double t, double* scratch, double* qva) const override;

 private:

  // The whole terms() call, with the sizes fixed at compile time for n <= 4 (terms_fixed) or not:
  // the input copies and the image copies then become a few moves instead of loops.
  using TermsFunction = void (*)(const TapeEvaluator& self, double t, const double* q, const double* v,
                                 double* scratch, const TermsOut& out);
  template <int N, int S, bool Calls>
  static void terms_fixed(const TapeEvaluator& self, double t, const double* q, const double* v,
                          double* scratch, const TermsOut& out);
  template <bool Calls>
  static void terms_any(const TapeEvaluator& self, double t, const double* q, const double* v,
                        double* scratch, const TermsOut& out);
  template <bool Calls>
  static void terms_scatter(const TapeEvaluator& self, double t, const double* q, const double* v,
                            double* scratch, const TermsOut& out);
  template <bool Calls>
  static TermsFunction choose_terms(int n, int s);

  void build();

  int n_ = 0;
  int s_ = 0;
  std::shared_ptr<const ModelTapes> parametric_;
  std::vector<double> parameters_;
  ModelTapes tapes_;  // *parametric_ bound to parameters_
  std::size_t scratch_ = 0;
  PreparedTape terms_, complement_, position_residual_, velocity_residual_, energy_, solution_, initial_state_;
  PreparedTape program_terms_, program_phi_, program_f_;  // program motion (empty without programs)
  std::size_t program_sizes_[3] = {0, 0, 0};          // outputs of program_terms_: b_p, b_p0, B
  PreparedTape energy_function_, power_;
  TermsFunction terms_function_ = nullptr;
  std::size_t terms_sizes_[5] = {0, 0, 0, 0, 0};  // outputs of terms: A, Q, G, b, b0 (nonzeros when sparse)
  std::size_t values_offset_ = 0;  // where terms_scatter keeps the nonzeros in scratch
  TermsFunction sparse_function_ = nullptr;
};

// A Tape turned into machine code by the compiled evaluator (jit/compiled_evaluator.hpp): the
// same outputs as Tape::run with the same parameter values, in the same order of operations, so
// the same rounding. model/ only calls it (the contact forces, the derived outputs: the rows of a
// compiled model go through compiled code, as its terms do); jit::make_compiled makes it.
class NativeTape {
 public:
  virtual ~NativeTape() = default;
  // What depends on the parameters alone, computed once per parameter change into stage_size()
  // doubles; `parameters` in the model's order (Tape::bind's).
  virtual std::size_t stage_size() const = 0;
  virtual void stage(const double* parameters, double* stage) const = 0;
  // One call: Tape::run's inputs and outputs, with the stage in place of the registers.
  virtual void run(const double* stage, double t, const double* q, const double* v, double* outputs) const = 0;
};

}  // namespace nhdyn
