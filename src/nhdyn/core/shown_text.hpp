// A text as a message shows it: a value echoed from the command line or a file may carry
// characters that hide themselves or turn the rest of a terminal line around (a zero-width space,
// a right-to-left override) and bytes that are not UTF-8; a message never prints them raw.
#pragma once

#include <string>
#include <string_view>

namespace nhdyn {

// `text` with every visible character as it is, an invisible one (a control or format character:
// zero-width marks, bidirectional overrides and isolates, a byte order mark) as <U+200B>, and a
// byte that is not UTF-8 as <0xFF>. With keep_line_breaks, '\n' stays (a message of several lines).
std::string shown_text(std::string_view text, bool keep_line_breaks = false);

}  // namespace nhdyn
