// Derived outputs of a model: named expressions in t, q, q', q'', the generalized reactions R and
// the parameters (a model file's [outputs], and a multibody model's automatic positions and
// velocities of its points and frame origins), each written as one more column of the results
// after the standard ones (io/results.hpp). Compiled by the symbolic layer (symbolic/outputs.hpp)
// into one tape (straight-line code, model/tape.hpp) that reads the parameters, so --set applies to outputs too;
// make_data binds it to the Model's parameter values, compute_outputs runs it after the dynamics.
//
//     [outputs] / multibody points --symbolic/outputs--> Model::outputs --make_data--> Data::outputs
//                                                          --compute_outputs--> Data::outputs.values
//
// A tape that reads q'' or R (an output's, or an event's, model/event.hpp) uses the "dynamics
// layout" below: it is a Tape of 2n coordinates whose coordinate inputs are [q; q''] and whose
// velocity inputs are [q'; R]. Its caller packs those from a solved state (pack_dynamics_inputs).
#pragma once

#include <string>
#include <vector>

#include "nhdyn/core/types.hpp"
#include "nhdyn/model/tape.hpp"

namespace nhdyn {

struct Model;
struct Data;

struct DerivedOutput {
  std::string name;        // the column's name
  std::string expression;  // as the user wrote it (automatic outputs: what it is, e.g. "x of point P")
  std::string where;       // "file:line:column" where it was written, for messages; "" if unknown
  bool automatic = false;  // a multibody model's own (docs/multibody.md), not written by the user
  bool dynamics = false;   // reads q'' or R: needs the solved dynamics at the state
};

struct ModelOutputs {
  std::vector<DerivedOutput> list;  // in column order
  // One output per entry of `list`, in the dynamics layout (2n coordinates: [q; q''], [q'; R]);
  // reads the model's parameters (bind before running). Empty tape when `list` is.
  Tape tape = Tape();
  // `tape` compiled (jit::make_compiled), run in its place when set; null for the interpreter.
  std::shared_ptr<const NativeTape> native;
  int count() const { return static_cast<int>(list.size()); }
};

// The evaluation state of the outputs for one Data (make_output_data, from make_data).
struct OutputData {
  PreparedTape tape;        // ModelOutputs::tape bound to the parameter values, prepared
  std::vector<double> x, xd;       // 2n each: [q; q''] and [q'; R] (pack_dynamics_inputs)
  std::vector<double> registers;   // tape.registers()
  std::vector<double> stage;       // ModelOutputs::native's parameter stage (empty without it)
  Vector values;                   // one per output (compute_outputs)
};

// Binds the model's outputs to its current parameter values and sizes the workspace (allocates;
// make_data calls it).
OutputData make_output_data(const Model& model);

// Copies q, q', q'' and R (n each) into the dynamics layout's inputs x = [q; q''], xd = [q'; R]
// (2n each).
void pack_dynamics_inputs(int n, const double* q, const double* v, const double* qdd, const double* R, double* x,
                          double* xd);

// Fills data.outputs.values from data.t, q, q', q'' and R: call compute_dynamics (or
// compute_acceleration) at the state first; the outputs read its q'' and R as they are. Allocates
// nothing.
void compute_outputs(const Model& model, Data& data);

}  // namespace nhdyn
