// Reads the text notation of `nhdyn equations` back into GiNaC and evaluates expressions at a
// generic point: the tests that check what the printer does to an expression (signs chosen,
// terms and factors merged) compare the printed text with the expression there.
#pragma once

#include <ginac/ginac.h>

#include <complex>
#include <stdexcept>
#include <string>

namespace nhdyn::test {

// The Spec (symbolic/spec.hpp) is a template parameter: tests/support sits below the symbolic
// module in the layer table, and only the tests that use this header link it.

// The printed notation into GiNaC's: x'' and x' become names of their own, " + " and " - " the
// operators, any other space between two factors a product; I is the imaginary unit.
class EquationReader {
 public:
  template <class Spec>
  explicit EquationReader(const Spec& spec) {
    table_["t"] = spec.symbols.time();
    table_["pi"] = GiNaC::Pi;
    table_["I"] = GiNaC::I;
    for (int i = 0; i < spec.n(); ++i) {
      const std::string& name = spec.coordinates[static_cast<std::size_t>(i)];
      table_[name] = spec.symbols.coordinate(i);
      table_[name + "__v"] = spec.symbols.velocity(i);
      table_[name + "__a"] = spec.symbols.acceleration(i);
    }
    for (const auto& p : spec.parameters) table_[p.name] = spec.symbols.parameter(p.name);
  }

  GiNaC::ex read(const std::string& text) const {
    // By hand: std::regex recurses per character and overflows the stack on the bicycle's lines.
    std::string out;
    for (std::size_t i = 0; i < text.size(); ++i) {
      const char c = text[i];
      if (c == '\'') {
        const bool two = i + 1 < text.size() && text[i + 1] == '\'';
        out += two ? "__a" : "__v";
        i += two ? 1 : 0;
      } else if (c == ' ' && text.compare(i, 3, " + ") == 0) {
        out += '+';
        i += 2;
      } else if (c == ' ' && text.compare(i, 3, " - ") == 0) {
        out += '-';
        i += 2;
      } else {
        out += c == ' ' ? '*' : c;
      }
    }
    GiNaC::parser parse(table_, true);
    return parse(out);
  }

 private:
  GiNaC::symtab table_;
};

// The value of e at the spec's parameters and a state where no coordinate, velocity or
// acceleration is 0, 1 or a multiple of pi/2.
template <class Spec>
std::complex<double> equation_value_at(const Spec& spec, const GiNaC::ex& e) {
  GiNaC::lst point;
  point.append(spec.symbols.time() == 0.7);
  for (int i = 0; i < spec.n(); ++i) {
    point.append(spec.symbols.coordinate(i) == 0.31 + 0.173 * i);
    point.append(spec.symbols.velocity(i) == -0.53 + 0.241 * i);
    point.append(spec.symbols.acceleration(i) == 0.77 - 0.189 * i);
  }
  for (const auto& p : spec.parameters) point.append(spec.symbols.parameter(p.name) == p.value);
  const GiNaC::ex v = GiNaC::evalf(e.subs(point));
  if (!GiNaC::is_a<GiNaC::numeric>(v)) throw std::runtime_error("not a number at the point");
  const GiNaC::numeric& n = GiNaC::ex_to<GiNaC::numeric>(v);
  return {n.real().to_double(), n.imag().to_double()};
}

}  // namespace nhdyn::test
