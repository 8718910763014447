// GiNaC's own words for what its evaluation of an expression refused ("power::eval(): division by
// zero", "log_eval(): log(0)") in the user's: the user wrote an expression, not GiNaC's classes.
// Every place that catches an exception of GiNaC while reading or evaluating the user's
// expressions passes its what() through plain_words and adds the place (file:line:column, the
// option) and the expression itself.
// Internal: used by the symbolic front end's sources, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <string>

namespace nhdyn::symbolic {

// What went wrong, in words without GiNaC's class and method names, and what to do.
std::string plain_words(const std::string& what);

}  // namespace nhdyn::symbolic
