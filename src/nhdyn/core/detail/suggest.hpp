// "Did you mean ...?": the nearest of a list of known names to a misspelt one, by edit distance.
// Used in the error messages of the model-file loader, the symbolic front end and the parameters.
// Internal: the messages of the model-file loader, the symbolic front end and the parameters.
#pragma once

#include <string>
#include <vector>

namespace nhdyn {

// Levenshtein distance between two names.
int edit_distance(const std::string& a, const std::string& b);

// The known name closest to `name`, or "" when none is close (distance above about a third of
// the length, at least 2).
std::string nearest_name(const std::string& name, const std::vector<std::string>& known);

}  // namespace nhdyn
