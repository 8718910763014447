// Specs and Derivations of the sled and of Appell's particle built by hand from GiNaC expressions
// (docs/derivations/sled.md and appell.md), without SpecBuilder or derive(), so that the compiler
// and the code generator are tested on their own. Parameter values and initial states are those
// of the hand-written models (model/sled.cpp, model/appell.cpp), given through their parameter
// structs. Used by tests/symbolic/compile_test.cpp, tests/codegen/ and bench/compile_bench.cpp.
#pragma once

#include <ginac/ginac.h>

#include <string>

#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::testing {

struct HandBuilt {
  symbolic::Spec spec;
  symbolic::Derivation derivation;
};

inline void add_parameter(symbolic::Spec& spec, const std::string& name, double value, const std::string& unit) {
  spec.symbols.add_parameter(name);
  spec.parameters.push_back({name, value, unit, {}});
}

inline void add_coordinate(symbolic::Spec& spec, const std::string& name) {
  spec.symbols.add_coordinate(name);
  spec.coordinates.push_back(name);
}

// The sled with the centre-of-mass potential and the regular blade constraint
// -sin(phi) x' + cos(phi) y' = 0 (docs/notation.md section 6; docs/derivations/sled.md 1-5).
inline HandBuilt make_hand_built_sled(const SledParameters& p = {}) {
  using GiNaC::ex;
  HandBuilt out;
  symbolic::Spec& spec = out.spec;
  spec.name = "sled";
  spec.description = "Sled on an inclined plane, centre-of-mass potential";
  for (const char* name : {"x", "y", "phi"}) add_coordinate(spec, name);
  add_parameter(spec, "m", p.m, "kg");
  add_parameter(spec, "a", p.a, "m");
  add_parameter(spec, "rho", p.rho, "m");
  add_parameter(spec, "alpha", p.alpha, "rad");
  add_parameter(spec, "g", p.g, "m/s^2");
  const symbolic::SymbolTable& S = spec.symbols;
  const ex m = S.parameter("m"), a = S.parameter("a"), rho = S.parameter("rho"), alpha = S.parameter("alpha"),
           g = S.parameter("g");
  const ex x = S.coordinate(0), phi = S.coordinate(2);
  const ex xd = S.velocity(0), yd = S.velocity(1), w = S.velocity(2);
  const ex sn = GiNaC::sin(phi), cs = GiNaC::cos(phi);

  spec.kinetic_energy = m / 2 * (xd * xd + yd * yd) - m * a * sn * xd * w + m * a * cs * yd * w +
                        m * rho * rho / 2 * w * w;
  spec.potential_energy = -m * g * GiNaC::sin(alpha) * (x + a * cs);
  spec.forces = {0, 0, 0};
  const ex f = -sn * xd + cs * yd;
  spec.constraints.push_back({"blade", ConstraintLevel::velocity, f, "-sin(phi) x' + cos(phi) y' = 0", {}});
  spec.complement = GiNaC::matrix{{cs, sn, 0}, {0, 0, 1}};
  spec.q0 = {0, 0, 0};
  spec.v0 = {1, 0, 1};
  spec.defaults = {10.0, 0.01};
  spec.path = std::make_pair(std::string("x"), std::string("y"));

  symbolic::Derivation& d = out.derivation;
  d.A = GiNaC::matrix{{m, 0, -m * a * sn}, {0, m, m * a * cs}, {-m * a * sn, m * a * cs, m * rho * rho}};
  d.Q = GiNaC::matrix{{m * g * GiNaC::sin(alpha)}, {0}, {-m * g * a * GiNaC::sin(alpha) * sn}};
  d.G = GiNaC::matrix{{m * a * cs * w * w}, {m * a * sn * w * w}, {0}};
  d.b = GiNaC::matrix{{-sn, cs, 0}};
  d.b0 = GiNaC::matrix{{-(cs * xd + sn * yd) * w}};
  d.D = *spec.complement;
  d.f = {f};
  d.energy = spec.kinetic_energy + spec.potential_energy;
  return out;
}

// Appell's particle with f = z'^2 - a^2 (x'^2 + y'^2) = 0 differentiated as is: b = df/dq',
// b0 = 0 (the hand-written model divides this row by 2 z'; docs/derivations/appell.md).
inline HandBuilt make_hand_built_appell(const AppellParameters& p = {}) {
  using GiNaC::ex;
  HandBuilt out;
  symbolic::Spec& spec = out.spec;
  spec.name = "appell";
  spec.description = "Appell's particle: nonlinear nonholonomic constraint z'^2 = a^2 (x'^2 + y'^2), z down";
  for (const char* name : {"x", "y", "z"}) add_coordinate(spec, name);
  add_parameter(spec, "m", p.m, "kg");
  add_parameter(spec, "g", p.g, "m/s^2");
  add_parameter(spec, "a", p.a, "");
  const symbolic::SymbolTable& S = spec.symbols;
  const ex m = S.parameter("m"), g = S.parameter("g"), a = S.parameter("a");
  const ex z = S.coordinate(2);
  const ex xd = S.velocity(0), yd = S.velocity(1), zd = S.velocity(2);

  spec.kinetic_energy = m / 2 * (xd * xd + yd * yd + zd * zd);
  spec.potential_energy = -m * g * z;
  spec.forces = {0, 0, 0};
  const ex f = zd * zd - a * a * (xd * xd + yd * yd);
  spec.constraints.push_back({"appell", ConstraintLevel::velocity, f, "z'^2 - a^2 (x'^2 + y'^2) = 0", {}});
  spec.complement = GiNaC::matrix{{1, 0, a * a * xd / zd}, {0, 1, a * a * yd / zd}};
  spec.q0 = {0, 0, 0};
  spec.v0 = {1, GiNaC::numeric(1, 2), a * GiNaC::sqrt(GiNaC::numeric(5, 4))};
  spec.defaults = {10.0, 0.01};
  spec.path = std::make_pair(std::string("x"), std::string("y"));

  symbolic::Derivation& d = out.derivation;
  d.A = GiNaC::matrix{{m, 0, 0}, {0, m, 0}, {0, 0, m}};
  d.Q = GiNaC::matrix{{0}, {0}, {m * g}};
  d.G = GiNaC::matrix{{0}, {0}, {0}};
  d.b = GiNaC::matrix{{GiNaC::diff(f, S.velocity(0)), GiNaC::diff(f, S.velocity(1)), GiNaC::diff(f, S.velocity(2))}};
  d.b0 = GiNaC::matrix{{0}};
  d.D = *spec.complement;
  d.f = {f};
  d.energy = spec.kinetic_energy + spec.potential_energy;
  return out;
}

}  // namespace nhdyn::testing
