// The text of `nhdyn equations` read back: every expression it prints (T, V, A, Q, G, each
// constraint's b and b0, each program's b_p0, E) is parsed again and evaluated at a point where
// no term vanishes, and must equal the derived expression there. This checks what the printer does
// on its own to the expressions: the sign it gives each sum inside a product (and the -1 that goes
// with it), the merging of like terms and like factors, cos(-x) = cos(x) and sin(-x) = -sin(x), the
// tangents folded back. The bicycle's entries are printed as derived, nested products of sums, so
// every one of those rules is used there; the other examples go through simplify() first.
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "gallery/gallery.hpp"
#include "support/equation_reader.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/equations.hpp"

namespace nhdyn::gallery {
namespace {

using GiNaC::ex;

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// "[ a  b + c  d ]" -> {"a", "b + c", "d"}: cells are set apart by two spaces or more.
std::vector<std::string> cells_of(const std::string& row) {
  const std::size_t open = row.find("[ "), close = row.rfind(" ]");
  std::vector<std::string> out;
  std::string cell;
  for (std::size_t i = open + 2; i < close; ++i) {
    if (row[i] == ' ' && row[i + 1] == ' ') {
      if (!cell.empty()) out.push_back(cell);
      cell.clear();
      while (i + 1 < close && row[i + 1] == ' ') ++i;
      continue;
    }
    cell += row[i];
  }
  if (!cell.empty() && cell != " ") out.push_back(cell);
  return out;
}

// Reads every expression of the file's text display and compares it with the derivation's.
// Returns how many were compared.
int expect_text_reads_back(const std::string& file) {
  const symbolic::Spec spec = load_model_file(example_path(file));
  const symbolic::Derivation d = symbolic::derive(spec);
  const std::string text = symbolic::format_equations(spec, d, symbolic::EquationFormat::text);
  const test::EquationReader reader(spec);
  int compared = 0;
  const auto expect_same = [&](const std::string& printed, const ex& derived, const std::string& what) {
    const double got = test::equation_value_at(spec, reader.read(printed)).real();
    const double want = test::equation_value_at(spec, derived).real();
    EXPECT_NEAR(got, want, 1e-9 * (1.0 + std::abs(want))) << file << ": " << what << " printed as " << printed;
    ++compared;
  };
  const std::vector<std::string> lines = lines_of(text);
  int constraint = -1, program = -1;
  for (std::size_t l = 0; l < lines.size(); ++l) {
    const std::string& line = lines[l];
    if (line.rfind("  T = ", 0) == 0) expect_same(line.substr(6), spec.kinetic_energy, "T");
    if (line.rfind("  V = ", 0) == 0) expect_same(line.substr(6), spec.potential_energy, "V");
    if (line.rfind("  E = ", 0) == 0) expect_same(line.substr(6), spec.kinetic_energy + spec.potential_energy, "E");
    if (line.rfind("  Q_", 0) == 0 || line.rfind("  G_", 0) == 0) {  // "  G_x   = ..."
      const std::size_t space = line.find(' ', 4), equals = line.find(" = ");
      const std::string name = line.substr(4, space - 4);
      const auto at = std::find(spec.coordinates.begin(), spec.coordinates.end(), name);
      if (at == spec.coordinates.end()) {
        ADD_FAILURE() << file << ": no coordinate '" << name << "'";
        continue;
      }
      const GiNaC::matrix& v = line[2] == 'Q' ? d.Q : d.G;
      expect_same(line.substr(equals + 3), v(static_cast<unsigned>(at - spec.coordinates.begin()), 0),
                  line.substr(2, space - 2));
    }
    if (line.rfind("Inertia matrix A", 0) == 0) {
      for (int i = 0; i < spec.n(); ++i) {
        const std::vector<std::string> cells = cells_of(lines[l + 1 + static_cast<std::size_t>(i)]);
        EXPECT_EQ(cells.size(), static_cast<std::size_t>(spec.n())) << file << ": row " << i << " of A";
        for (std::size_t j = 0; j < cells.size(); ++j)
          expect_same(cells[j], d.A(static_cast<unsigned>(i), static_cast<unsigned>(j)),
                      "A(" + std::to_string(i) + "," + std::to_string(j) + ")");
      }
    }
    if (line.rfind("    b  = [", 0) == 0) {
      ++constraint;
      const std::vector<std::string> cells = cells_of(line);
      EXPECT_EQ(cells.size(), static_cast<std::size_t>(spec.n())) << file << ": b of constraint " << constraint;
      for (std::size_t j = 0; j < cells.size(); ++j)
        expect_same(cells[j], d.b(static_cast<unsigned>(constraint), static_cast<unsigned>(j)), "b");
    }
    if (line.rfind("    b0 = ", 0) == 0) expect_same(line.substr(9), d.b0(static_cast<unsigned>(constraint), 0), "b0");
    if (line.rfind("    b_p0 = ", 0) == 0)
      expect_same(line.substr(11), d.b_p0(static_cast<unsigned>(++program), 0), "b_p0");
  }
  EXPECT_EQ(constraint + 1, spec.s()) << file;
  EXPECT_EQ(program + 1, spec.m()) << file;
  return compared;
}

TEST(EquationsText, TheBicycleReadsBack) {
  // T, V, E, 8 x 8 of A, 8 of Q and G, 5 constraints of b (8 each) and b0.
  EXPECT_EQ(expect_text_reads_back("whipple_bicycle.toml"), 3 + 64 + 16 + 5 * 9);
}

TEST(EquationsText, TheBicycleWithAProgramReadsBack) {
  EXPECT_GT(expect_text_reads_back("bicycle_roll_program.toml"), 3 + 64 + 16 + 5 * 9);
}

TEST(EquationsText, TheSmallExamplesReadBack) {
  for (const char* file : {"knife_edge.toml", "chaplygin_sleigh.toml", "double_pendulum.toml", "slider_crank.toml",
                           "rolling_disk.toml", "rolling_disk_bodies.toml", "roller_racer.toml", "diff_drive.toml"}) {
    SCOPED_TRACE(file);
    EXPECT_GT(expect_text_reads_back(file), 4);
  }
}

}  // namespace
}  // namespace nhdyn::gallery
