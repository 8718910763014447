#include "nhdyn/core/status.hpp"

namespace nhdyn {

std::string_view describe(Status status) {
  switch (status) {
    case Status::ok: return "ok";
    case Status::dependent_constraints: return "dependent or conflicting constraints";
    case Status::inertia_not_positive_definite: return "inertia matrix not positive definite";
    case Status::singular_system: return "singular system of equations";
    case Status::non_finite: return "non-finite value";
    case Status::step_size_underflow: return "step size underflow";
    case Status::too_many_steps: return "too many steps";
    case Status::integrator_failure: return "integrator failure";
    case Status::stopped: return "stopped";
    case Status::projection_failed: return "projection onto the constraints did not converge";
  }
  return "unknown status";
}

}  // namespace nhdyn
