// GiNaC's own words in an error ("power::eval(): division by zero") turned into ours: what
// happened to the expression, for the messages of the model-file reader, compile and [visual].
#include "nhdyn/symbolic/detail/plain_words.hpp"

#include <fmt/format.h>

namespace nhdyn::symbolic {

std::string plain_words(const std::string& what) {
  const auto has = [&](const char* part) { return what.find(part) != std::string::npos; };
  if (has("division by zero"))
    return "the expression divides by zero (1/0, x/(a - a), 0^(-1)): write it so that no denominator is "
           "identically zero";
  if (has("pow(0,0)")) return "the expression contains 0^0, which is undefined: write 1 or 0 as meant";
  if (has("log(0)")) return "the expression contains log(0), which is not finite: take the logarithm of a positive value";
  if (has("pole") || has("singularity"))
    return "the expression is evaluated at a pole of a function (tan(pi/2), atan(i), ...): it is not finite "
           "there; change the constant argument";
  std::string plain = what;
  const std::size_t colons = plain.find("(): ");  // "class::method(): problem" -> "problem"
  if (colons != std::string::npos) plain = plain.substr(colons + 4);
  return fmt::format("the expression cannot be evaluated: {}", plain);
}

}  // namespace nhdyn::symbolic
