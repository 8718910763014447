#include "nhdyn/model/output.hpp"

#include <algorithm>

#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

OutputData make_output_data(const Model& model) {
  OutputData d;
  const int n = model.n();
  d.x.assign(static_cast<std::size_t>(2 * n), 0.0);
  d.xd.assign(static_cast<std::size_t>(2 * n), 0.0);
  d.values = Vector::Zero(model.outputs.count());
  if (model.outputs.list.empty()) return d;
  std::vector<double> values;
  for (const Parameter& p : model.parameters) values.push_back(p.value);
  const Tape& tape = model.outputs.tape;
  d.tape = PreparedTape(tape.bind(values.data(), values.size()));
  d.registers.assign(static_cast<std::size_t>(d.tape.registers()), 0.0);
  if (model.outputs.native) {
    d.stage.assign(model.outputs.native->stage_size() + 1, 0.0);  // + 1: data() of an empty stage
    model.outputs.native->stage(values.data(), d.stage.data());
  }
  return d;
}

void pack_dynamics_inputs(int n, const double* q, const double* v, const double* qdd, const double* R, double* x,
                          double* xd) {
  std::copy(q, q + n, x);
  std::copy(qdd, qdd + n, x + n);
  std::copy(v, v + n, xd);
  std::copy(R, R + n, xd + n);
}

void compute_outputs(const Model& model, Data& data) {
  OutputData& o = data.outputs;
  if (model.outputs.list.empty()) return;
  pack_dynamics_inputs(model.n(), data.q.data(), data.v.data(), data.qdd.data(), data.R.data(), o.x.data(),
                       o.xd.data());
  if (model.outputs.native)
    model.outputs.native->run(o.stage.data(), data.t, o.x.data(), o.xd.data(), o.values.data());
  else
    o.tape.run(data.t, o.x.data(), o.xd.data(), o.registers.data(), o.values.data());
}

}  // namespace nhdyn
