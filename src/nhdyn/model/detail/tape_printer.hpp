// A Tape printed as straight-line C++: the one printer of the compiled evaluator's source
// (jit/detail/source.hpp) and of the headers `nhdyn codegen` writes (symbolic/codegen.hpp). Each
// instruction becomes `const double rN = <expression>;`, the expression read from the table of
// operations (kOps in tape.hpp), so that the printed code does the tape's operations in its
// order and rounds as the interpreter does (when compiled without contraction into fused
// multiply-adds).
//
// The parameter stage: what depends on parameters and constants only is computed once per
// parameter change (jit: a function of its own writing an array; codegen: the evaluator's
// constructor writing members), and a call reads the stage registers it needs from there. The two
// users differ only in spelling, given by a TapePrintStyle: how a double, a parameter and a
// stored stage register are written, and whether constants are declared as registers or written
// as literals where they are read.
// Internal: used by jit/ and symbolic/codegen.cpp, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "nhdyn/model/tape.hpp"

namespace nhdyn {

struct TapePrintStyle {
  std::function<std::string(double)> literal;        // a double as a C++ literal of type double
  std::function<std::string(int)> parameter;         // model parameter i as C++ ("p[3]", "p_.mass")
  std::function<std::string(int, int)> stored;       // stage register r, stored in place `slot` (0, 1, ...)
  bool declare_constants = false;  // constants as `const double rN = k;` where read, else literals inline
};

class TapePrinter {
 public:
  // hoist = false: no stage, every instruction in the call (a tape that runs once anyway).
  TapePrinter(const Tape& tape, TapePrintStyle style, bool hoist = true);

  const Tape& tape() const { return tape_; }

  // Number of stage registers a call reads (their places are 0 .. stored_count() - 1, in register order).
  int stored_count() const { return stored_count_; }
  // Each stored register as (register, place), in register order.
  std::vector<std::pair<int, int>> stored_registers() const;
  // Stored register r as C++ (style.stored with its place).
  std::string stored(int r) const { return style_.stored(r, place_[static_cast<std::size_t>(r)]); }

  // The statements of the stage (in_stage) or of a call, each line starting with `indent`. The
  // stage ends by storing the registers a call reads (`stored(r, place) = rN;`).
  std::string statements(bool in_stage, std::string_view indent) const;

  // A register as C++ in the stage or in a call: the inputs t, q[i], v[i]; a stored stage
  // register, in a call, as style.stored; a constant as its literal unless declared; else rN.
  std::string reg(int r, bool in_stage) const;

  // Output j of the tape as C++ in a call: its register, or its literal when constant.
  std::string output(int j) const;

 private:
  std::string expression(const Instruction& in, bool in_stage) const;

  const Tape& tape_;
  TapePrintStyle style_;
  std::vector<char> stage_;          // register -> computed in the stage
  std::vector<char> constant_;       // register -> a constant instruction
  std::vector<char> read_by_stage_;  // register -> read by a stage instruction
  std::vector<char> read_by_call_;   // register -> read by a call's instruction or an output
  std::vector<int> place_;           // register -> its place among the stored ones, -1 if none
  int stored_count_ = 0;
};

}  // namespace nhdyn
