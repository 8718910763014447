// The provenance header (io/provenance.hpp): what format_provenance writes, parse_provenance
// reads back exactly (values to the last bit), and a header cut short or altered is refused with
// the missing line named.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/provenance.hpp"

namespace {

std::vector<std::string> provenance_comments(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    EXPECT_EQ(line.substr(0, 2), "# ") << line;
    out.push_back(line.substr(1));
  }
  return out;
}

nhdyn::Provenance sample_provenance() {
  nhdyn::Provenance p;
  p.version = nhdyn::nhdyn_version_text();
  p.model = "sled";
  p.model_file = "examples/sled.toml";
  p.model_hash = nhdyn::calc_text_hash("m = 1\n");
  p.parameters = {{"m", 2.0}, {"alpha", std::acos(-1.0) / 6}, {"tiny", -1.25e-300}};
  p.initial = {{"x", 0.1}, {"x'", -1.0 / 3.0}};
  p.run = {{"method", "sanh"}, {"rtol", "1e-08"}, {"events", "wrap:atan2(y, x)"}};
  return p;
}

TEST(Provenance, ReadsBackWhatItWritesToTheLastBit) {
  const nhdyn::Provenance p = sample_provenance();
  const std::string text = nhdyn::format_provenance(p);
  const auto back = nhdyn::parse_provenance(provenance_comments(text), "run.csv");
  ASSERT_TRUE(back.has_value()) << text;
  EXPECT_EQ(back->version, p.version);
  EXPECT_EQ(back->model, "sled");
  EXPECT_EQ(back->model_file, "examples/sled.toml");
  EXPECT_EQ(back->model_hash, p.model_hash);
  EXPECT_EQ(back->parameters, p.parameters);  // exact: the shortest round-trip form
  EXPECT_EQ(back->initial, p.initial);
  ASSERT_EQ(back->run.size(), 3u);
  EXPECT_EQ(back->run[2].second, "wrap:atan2(y,x)");  // ", " separates options; one inside a value loses its blank
}

TEST(Provenance, HashTellsTextsApartAndIsStable) {
  EXPECT_EQ(nhdyn::calc_text_hash(""), "fnv1a64:cbf29ce484222325");  // FNV-1a's offset basis
  EXPECT_EQ(nhdyn::calc_text_hash("a"), "fnv1a64:af63dc4c8601ec8c");  // the published FNV-1a 64 value of "a"
  EXPECT_NE(nhdyn::calc_text_hash("m = 1\n"), nhdyn::calc_text_hash("m = 2\n"));
}

TEST(Provenance, NoneWithoutItsFirstLine) {
  EXPECT_FALSE(nhdyn::parse_provenance({}, "a.csv").has_value());
  EXPECT_FALSE(nhdyn::parse_provenance({" nhdyn: simulation of 'x' failed at t = 1: why"}, "a.csv").has_value());
}

TEST(Provenance, TruncatedOrAlteredIsRefusedNamingTheLine) {
  const std::vector<std::string> whole = provenance_comments(nhdyn::format_provenance(sample_provenance()));
  const auto message = [](const std::vector<std::string>& lines) {
    try {
      nhdyn::parse_provenance(lines, "run.csv");
    } catch (const nhdyn::InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  // Cut after the model hash: the parameters line is the first one missing.
  std::string m = message({whole.begin(), whole.begin() + 4});
  EXPECT_NE(m.find("run.csv: the provenance header is truncated: it has no 'parameters' line"), std::string::npos) << m;
  // Every line but the last.
  m = message({whole.begin(), whole.end() - 1});
  EXPECT_NE(m.find("its last line '# end of provenance' is missing"), std::string::npos) << m;
  // A parameter value that is not a number.
  std::vector<std::string> altered = whole;
  altered[4] = " parameters: m=two";
  m = message(altered);
  EXPECT_NE(m.find("gives m = 'two', which is not a number"), std::string::npos) << m;
}

}  // namespace
