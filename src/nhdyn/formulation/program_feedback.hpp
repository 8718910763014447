// The feedback of program motion (docs/derivations/program-motion.md section 5): the programs are
// solved at acceleration level as b_p q'' + b_p0 + 2 alpha f_p + beta^2 phi_p = 0 (P6), a computed-
// torque law with PD feedback on the program residuals, so that the tracking error is a damped
// oscillator driven by the integration defect (P7) instead of drifting. Kept apart from
// program_motion.hpp so that FormulationOptions can hold it.
#pragma once

namespace nhdyn {

struct ProgramFeedback {
  bool enabled = false;
  double alpha = 0.0;  // [1/s], damping of the velocity-level program residual
  double beta = 0.0;   // [1/s], stiffness of the position-level program residual
};

// The largest gain accepted [1/s]: a time constant of a nanosecond. Beyond it the feedback makes
// the motion stiffer than any step can follow, and beta^2 times a residual soon overflows (1e200
// was accepted and then failed as "divides by zero or overflows").
inline constexpr double kMaxProgramFeedback = 1e9;

// Throws InputError unless both gains are finite, non-negative and at most kMaxProgramFeedback,
// naming the gain and value.
void check_program_feedback(const ProgramFeedback& feedback);

}  // namespace nhdyn
