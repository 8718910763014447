// The provenance of a run (io/provenance.hpp) made from what the front door knows: the model's
// source (its file's text, hashed), its parameter values and initial state, and the run's options;
// and the check `nhdyn report` makes before it draws a CSV: the model it is given is the one the
// run used (same hash), with the run's parameters applied again (no --set needed).
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/provenance.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// calc_text_hash of a model file's text, of "builtin:NAME" for a built-in model.
std::string calc_model_hash(const ModelSource& source);

// The provenance of a run of `model` (loaded from `source`, its parameters and q0, v0 as run) with
// `options`; `evaluator` is the evaluator's name as chosen (interpreted, compiled, auto).
Provenance make_provenance(const Model& model, const ModelSource& source, const SimulationOptions& options,
                           std::string_view evaluator);

// The provenance of a command other than simulate (batch, compare, sweep, linearize, the
// studies): the model's part of make_provenance (version, model, file, hash, parameters and
// initial state as loaded), then `command` ("# run: command=sweep, ...") and the command's own
// options as given, in order. The same header, so that every CSV nhdyn writes says what made it.
Provenance make_command_provenance(const Model& model, const ModelSource& source, std::string_view command,
                                   std::vector<std::pair<std::string, std::string>> options);

// The overrides that load `source` as the run recorded in `provenance` (the CSV `csv`) had it:
// every parameter at its value as run. Throws InputError when the model is not the run's: its hash
// differs (the message names both hashes, the model names if they differ, and each parameter whose
// value in the file is not the run's, or that one of them lacks) with what to do.
ParameterOverrides check_provenance(const Provenance& provenance, const ModelSource& source, const std::string& csv);

}  // namespace nhdyn
