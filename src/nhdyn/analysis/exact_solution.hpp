// The checks that make a model's exact solution (Evaluator::solution) safe to measure runs
// against: it must exist, be finite, start at the model's initial state, and its q'' must be the
// accelerations the equations of motion give there. compare_formulations runs them before it uses
// an analytic reference (and so does every study built on it). They are not run when a model is
// compiled: a closed form that is only valid for some parameter values (v0/w with w = 0) must not
// stop `nhdyn simulate` of a model that is otherwise fine.
#pragma once

#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Throws InputError when the model has no solution (saying how to give one), ModelError when it
// is not finite at t0, does not start at (q0, q0') to 1e-9 (relative), or its q''(t0) differs from
// the formulation's q'' at the initial state by more than 1e-8 (relative): each names the
// coordinate and both values.
void check_solution(const Model& model);

}  // namespace nhdyn
