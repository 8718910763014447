#include "nhdyn/core/detail/characters.hpp"

#include "nhdyn/core/shown_text.hpp"

#include <fmt/format.h>

#include <cstdint>

namespace nhdyn {

namespace {

// The character that starts at byte `at`: its UTF-8 sequence and code point; `valid` false for a
// byte that starts no well-formed UTF-8 sequence (a stray continuation byte, a truncated or overlong
// sequence, a surrogate, a code point past U+10FFFF): its sequence is then that byte alone.
struct Character {
  std::string_view utf8;
  std::uint32_t code = 0;
  bool valid = true;
};

Character character_at(std::string_view text, std::size_t at) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[at + k]); };
  const unsigned char lead = byte(0);
  const std::size_t length = lead < 0x80 ? 1 : (lead & 0xE0) == 0xC0 ? 2 : (lead & 0xF0) == 0xE0 ? 3
                                          : (lead & 0xF8) == 0xF0 ? 4 : 0;
  Character bad{text.substr(at, 1), lead, false};
  if (length == 0 || at + length > text.size()) return bad;
  std::uint32_t code = length == 1 ? lead : length == 2 ? lead & 0x1Fu : length == 3 ? lead & 0x0Fu : lead & 0x07u;
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(k) & 0xC0) != 0x80) return bad;
    code = (code << 6) | (byte(k) & 0x3Fu);
  }
  constexpr std::uint32_t smallest[] = {0, 0, 0x80, 0x800, 0x10000};  // shorter forms are overlong
  if (code < smallest[length] || (code >= 0xD800 && code <= 0xDFFF) || code > 0x10FFFF) return bad;
  return {text.substr(at, length), code, true};
}

// Control characters, and the format characters that change how the text around them shows or
// hide in it (a soft hyphen, zero-width marks, the Arabic letter mark, the line and paragraph
// separators, the bidirectional overrides U+202A-E and isolates U+2066-9, the byte order mark,
// the tags U+E0000-7F).
bool invisible(std::uint32_t code) {
  return code < 0x20 || code == 0x7f || (code >= 0x80 && code < 0xA0) || code == 0xAD || code == 0x61C ||
         code == 0x180E || (code >= 0x200B && code <= 0x200F) || (code >= 0x2028 && code <= 0x202E) ||
         (code >= 0x2060 && code <= 0x2069) || code == 0xFEFF || (code >= 0xE0000 && code <= 0xE007F);
}

}  // namespace

std::string shown_text(std::string_view text, bool keep_line_breaks) {
  std::string shown;
  for (std::size_t at = 0; at < text.size();) {
    const Character c = character_at(text, at);
    if (keep_line_breaks && c.code == '\n') shown += '\n';
    else if (!c.valid) shown += fmt::format("<0x{:02X}>", static_cast<unsigned char>(c.utf8[0]));
    else if (invisible(c.code)) shown += fmt::format("<U+{:04X}>", c.code);
    else shown += c.utf8;
    at += c.utf8.size();
  }
  return shown;
}

std::string describe_character(std::string_view text, std::size_t at) {
  const Character c = character_at(text, at);
  const std::string_view utf8 = c.utf8;
  const std::uint32_t code = c.code;
  if (!c.valid) return fmt::format("(the byte 0x{:02X}, not UTF-8 text)", static_cast<unsigned char>(utf8[0]));
  if (utf8.size() == 1 && code >= 0x20 && code < 0x7f) return fmt::format("'{}'", utf8);
  struct Known {
    std::uint32_t code;
    const char* name;
    const char* instead;
  };
  static constexpr Known known[] = {
      {0x00A0, "a no-break space", "a plain space"},  {0x2009, "a thin space", "a plain space"},
      {0x202F, "a narrow no-break space", "a plain space"}, {0x200B, "a zero-width space", "nothing"},
      {0x200C, "a zero-width non-joiner", "nothing"}, {0x200D, "a zero-width joiner", "nothing"},
      {0xFEFF, "a byte order mark", "nothing"},       {0x2212, "a minus sign", "'-'"},
      {0x2013, "an en dash", "'-'"},                  {0x00D7, "a multiplication sign", "'*'"},
      {0x00B7, "a middle dot", "'*'"},                {0x2217, "an asterisk operator", "'*'"},
      {0x2019, "a right quotation mark", "a prime '"},  {0x2032, "a prime sign", "a prime '"},
  };
  for (const Known& k : known)
    if (k.code == code) {
      const std::string_view instead = k.instead;
      if (instead == "nothing") return fmt::format("U+{:04X} ({}, invisible): delete it", code, k.name);
      if (instead == "a plain space") return fmt::format("U+{:04X} ({}): write a plain space", code, k.name);
      return fmt::format("'{}' U+{:04X} ({}): write {}", utf8, code, k.name, k.instead);
    }
  if (invisible(code)) return fmt::format("U+{:04X} (an invisible control or format character): delete it", code);
  return fmt::format("'{}' (U+{:04X}): expressions are written in ASCII (names of letters, digits and _)", utf8, code);
}

}  // namespace nhdyn
