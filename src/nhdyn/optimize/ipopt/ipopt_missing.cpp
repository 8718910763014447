// solve_nlp (optimize/nlp.hpp) in a build without IPOPT (NHDYN_WITH_IPOPT=AUTO found none, or OFF):
// the rest of nhdyn builds and runs, and `nhdyn optimize` says how to get the solver.
#include "nhdyn/optimize/nlp.hpp"

namespace nhdyn {

bool nlp_solver_available() { return false; }

NlpResult solve_nlp(Nlp& /*nlp*/, const NlpOptions& /*options*/) {
  NlpResult result;
  result.status = NlpStatus::unavailable;
  result.message = "nhdyn was built without IPOPT: install it (sudo apt-get install coinor-libipopt-dev, or "
                   "scripts/install-deps, which installs it with the test packages) and rebuild: CMake finds it "
                   "with pkg-config (NHDYN_WITH_IPOPT=AUTO)";
  return result;
}

}  // namespace nhdyn
