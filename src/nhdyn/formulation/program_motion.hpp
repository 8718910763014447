// Program motion (docs/derivations/program-motion.md): the accelerations q'' and the actuator
// forces u that make the motion follow m prescribed programs b_p q'' + b_p0 = 0, each realized by
// its actuator (a column of B), with the physical constraints keeping their ideal reactions:
//     [ D A   -D B ] [ q'' ]   [ D (Q + G) ]
//     [ b      0   ] [     ] = [   -b0     ]                                             (P2)
//     [ b_p    0   ] [  u  ]   [  -b_p0    ]
// solved with the Do Sanh factorization of M = [D A; b] alone (section 4): q''_0 = M^-1 [D (Q + G);
// -b0] (the motion without actuators), P B = M^-1 [D B; 0] (m more solves), then the m x m system
// S u = -(b_p q''_0 + b_p0) with S = b_p P B (P4, P5), and q'' = q''_0 + P B u. (P2) is regular if
// and only if S is; a singular S is refused with the programs involved.
#pragma once

#include <string>

#include "nhdyn/core/status.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Requires compute_terms for the current state and a dense Data made for sanh (or every method)
// for a model with programs (model.m() > 0). Evaluates the programs' terms b_p, b_p0, B (and with
// `feedback` enabled their residuals, into data.motion.feedback), the complement D of `complement`,
// factorizes M once and writes data.D, data.motion (u, q''_0, P B, S), data.qdd and the physical
// reactions data.R = A q'' - Q - G - B u (P3). Allocates nothing. Returns Status::singular_system
// with data.failed_quantity "stacked matrix [D A; b]" or "program matrix S = b_p P B" (S is tested
// with its rows and columns scaled to unit length, so that the units of the programs and actuators
// do not decide), and Status::non_finite for a program term that is not finite; explain_failure
// (diagnosis.hpp) gives the words, through explain_program_failure.
Status compute_program_motion(const Model& model, Data& data, Complement complement, const ProgramFeedback& feedback);

// Requires compute_program_motion for the current state. Writes data.motion.phi (position-level
// programs), data.motion.f (position- and velocity-level programs) and data.motion.e = b_p q'' + b_p0
// (every program, without feedback). Allocates nothing.
void compute_program_residuals(const Model& model, Data& data);

// The words for a failed compute_program_motion whose data.failed_quantity names the program
// matrix S: the actuators the constraints absorb (D B_j = 0), or the smallest singular value of the
// scaled S and the programs with the largest entries of its left singular vector. Cold path.
std::string explain_program_failure(const Model& model, const Data& data);

// Before a run (cold path, throws ModelError): the initial state must satisfy every position- and
// velocity-level program to `tolerance` (each violated one listed with its residual, as for the
// constraints) and S must be regular there (with explain_program_failure's words).
void check_programs_at_initial_state(const Model& model, Data& data, const FormulationOptions& options, double t,
                                     const Vector& q, const Vector& v, double tolerance);

}  // namespace nhdyn
