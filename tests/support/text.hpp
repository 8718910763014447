// Small helpers the test files of several folders share: reading a file whole, finding a part
// of a text, splitting a CSV line, the path of an example, evenly spaced times. One definition
// here, because the test folders are compiled as unity batches (docs/design.md, "Build and CI"),
// where two files' helpers of the same name would collide.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace nhdyn::test {

// The bytes of a file; "" when it cannot be read (the test's own checks then fail by name).
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A CSV's text after its provenance header (io/provenance.hpp): the leading '#' lines removed, so
// that the column names come first. A text without them is returned as it is.
inline std::string csv_body(const std::string& text) {
  std::size_t at = 0;
  while (at < text.size() && text[at] == '#') {
    const std::size_t end = text.find('\n', at);
    if (end == std::string::npos) return {};
    at = end + 1;
  }
  return text.substr(at);
}

// Replaces the first `from` in `text` by `to`; a test failure naming `from` when it is not there
// (an example file edited so that a test's edit no longer applies).
inline void replace_once(std::string& text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// The fields of one CSV line as written by nhdyn (no quoting: its names hold no comma).
inline std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream in(line);
  for (std::string field; std::getline(in, field, ',');) fields.push_back(field);
  return fields;
}

#ifdef NHDYN_SOURCE_DIR
// The path of a file of examples/.
inline std::string example(const std::string& name) {
  return (std::filesystem::path(NHDYN_SOURCE_DIR) / "examples" / name).string();
}
#endif

// count times from a to b, both included.
inline std::vector<double> linspace(double a, double b, int count) {
  std::vector<double> t(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) t[static_cast<std::size_t>(i)] = a + (b - a) * i / (count - 1);
  return t;
}

}  // namespace nhdyn::test
