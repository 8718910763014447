// A character of a text that a parser refused, as a message shows it: an ASCII one as it is; any
// other with its code point, and those pasted from papers and word processors (a no-break space,
// a zero-width space, a minus sign) with what to write instead, an invisible one never raw.
// Internal: the messages of the expression readers (symbolic/spec_builder.cpp, model/parameters.cpp).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace nhdyn {

// The character (a whole UTF-8 sequence) that starts at byte `at` of `text`, described.
std::string describe_character(std::string_view text, std::size_t at);

}  // namespace nhdyn
