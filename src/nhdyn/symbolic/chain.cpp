// The N-trailer chain: the model is written once, as text (names and expressions), and that text
// feeds both SpecBuilder and the model file, so the two cannot drift apart. docs/gallery/chain.md.
#include "nhdyn/symbolic/chain.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::symbolic {
namespace {

struct ChainParameterText {
  std::string name;
  double value = 0.0;
  std::string unit;
  std::string comment;
};

struct ChainConstraintText {
  std::string name;
  ConstraintLevel level = ConstraintLevel::velocity;
  std::string text;
};

struct ChainInitialText {
  std::string coordinate;
  std::string q0;
  std::string v0;
};

// Everything of the model as text, in the order of the file.
struct ChainText {
  std::string name;
  std::string description;
  std::vector<std::string> coordinates;
  std::vector<ChainParameterText> parameters;
  std::vector<std::string> kinetic_energy;  // one term per body; T is their sum
  std::vector<ChainConstraintText> constraints;
  std::vector<ChainInitialText> initial;
  SimulationDefaults defaults;
  double rtol = 1e-10;
  double atol = 1e-12;
};

// (-r/f)^k as an expression in the parameters. The expression reader refuses exponents beyond 64
// (it expands powers symbolically), so larger k are written as (-1)^k exp(k log(r/f)).
std::string ratio_power(int k) {
  if (k == 1) return "(-r/f)";
  if (k <= 64) return fmt::format("(-r/f)^{}", k);
  return fmt::format("{}exp({}*log(r/f))", k % 2 == 1 ? "(-1)*" : "", k);
}

ChainText make_chain_text(const ChainParameters& p) {
  ChainText c;
  const int N = p.bodies;
  c.name = fmt::format("chain-{}", N);
  c.description = fmt::format("{} Chaplygin sleighs on a horizontal plane joined by pins (N-trailer)", N);
  c.parameters = {
      {"m", p.mass, "kg", "mass of each body"},
      {"J", p.inertia, "kg*m^2", "moment of inertia of each body about its centre of mass"},
      {"a", p.com_offset, "m", "blade contact point to centre of mass, along the blade"},
      {"f", p.front_hitch, "m", "blade contact point to the front hitch (ahead)"},
      {"r", p.rear_hitch, "m", "blade contact point to the rear hitch (behind)"},
      {"v0", p.speed, "m/s", "initial speed of every body along its blade"},
      {"w0", p.turn_rate, "rad/s", "initial turning rate of the lead; body i turns at w0 (-r/f)^(i-1)"},
  };
  for (int i = 1; i <= N; ++i) {
    const std::string x = fmt::format("x{}", i), y = fmt::format("y{}", i), th = fmt::format("theta{}", i);
    c.coordinates.insert(c.coordinates.end(), {x, y, th});
    c.kinetic_energy.push_back(fmt::format(
        "m/2*({x}'^2 + {y}'^2) + m*a*{th}'*(cos({th})*{y}' - sin({th})*{x}') + (J + m*a^2)/2*{th}'^2",
        fmt::arg("x", x), fmt::arg("y", y), fmt::arg("th", th)));
    c.constraints.push_back({fmt::format("blade{}", i), ConstraintLevel::velocity,
                             fmt::format("-sin({th})*{x}' + cos({th})*{y}'", fmt::arg("x", x), fmt::arg("y", y),
                                         fmt::arg("th", th))});
    if (i < N) {
      const std::string x2 = fmt::format("x{}", i + 1), y2 = fmt::format("y{}", i + 1),
                        th2 = fmt::format("theta{}", i + 1);
      c.constraints.push_back({fmt::format("pin{}_x", i), ConstraintLevel::position,
                               fmt::format("{} + f*cos({}) - {} + r*cos({})", x2, th2, x, th)});
      c.constraints.push_back({fmt::format("pin{}_y", i), ConstraintLevel::position,
                               fmt::format("{} + f*sin({}) - {} + r*sin({})", y2, th2, y, th)});
    }
    // On the x axis heading along +x; blade i at -(i-1)(f + r).
    c.initial.push_back({x, i == 1 ? "0" : fmt::format("-{}*(f + r)", i - 1), "v0"});
    c.initial.push_back({y, "0", "0"});
    c.initial.push_back({th, "0", i == 1 ? "w0" : fmt::format("w0*{}", ratio_power(i - 1))});
  }
  c.defaults.t_end = p.t_end;
  c.defaults.output_step = 0.01;
  return c;
}

void refuse(const std::string& what, double value, const std::string& limit) {
  throw InputError(fmt::format("chain: {} = {} is out of range: {}", what, value, limit));
}

// A double as a TOML float (TOML needs a '.' or an exponent to read a float).
std::string toml_number(double value) {
  std::string text = fmt::format("{}", value);
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";
  return text;
}

}  // namespace

void check_chain_parameters(const ChainParameters& p) {
  if (p.bodies < 1 || p.bodies > kMaxChainBodies)
    throw InputError(fmt::format(
        "chain: bodies = {} is out of range: give a number of bodies from 1 to {} (a larger chain's dense "
        "matrices do not fit in memory: 8 (3N)^2 bytes each; see docs/gallery/chain.md)",
        p.bodies, kMaxChainBodies));
  const auto positive = [](const char* what, double value) {
    if (!(std::isfinite(value) && value > 0.0)) refuse(what, value, "it must be a positive finite number");
  };
  positive("mass m", p.mass);
  positive("inertia J", p.inertia);
  positive("front hitch f", p.front_hitch);
  positive("rear hitch r", p.rear_hitch);
  positive("end time t_end", p.t_end);
  if (!(std::isfinite(p.com_offset) && p.com_offset >= 0.0))
    refuse("centre-of-mass offset a", p.com_offset, "it must be a finite number >= 0");
  if (!std::isfinite(p.speed)) refuse("speed v0", p.speed, "it must be a finite number");
  if (!std::isfinite(p.turn_rate)) refuse("turning rate w0", p.turn_rate, "it must be a finite number");
  // Body N turns at w0 (-r/f)^(N-1): keep it finite (and within 1e100, where T would overflow).
  const double last = std::abs(p.turn_rate) * std::pow(p.rear_hitch / p.front_hitch, p.bodies - 1);
  if (!(last <= 1e100))
    refuse("turning rate of the last body |w0| (r/f)^(N-1)", last,
           "it must stay below 1e100; give r <= f, or fewer bodies, or w0 = 0");
}

Spec make_chain_spec(const ChainParameters& p) {
  check_chain_parameters(p);
  const ChainText c = make_chain_text(p);
  SpecBuilder b(c.name);
  b.description(c.description);
  for (const std::string& q : c.coordinates) b.coordinate(q);
  for (const ChainParameterText& par : c.parameters) b.parameter(par.name, par.value, par.unit);
  std::string T;
  for (const std::string& term : c.kinetic_energy) T += (T.empty() ? "" : " + ") + term;
  b.kinetic_energy(T);
  for (const ChainConstraintText& con : c.constraints) b.constraint(con.name, con.level, con.text);
  for (const ChainInitialText& init : c.initial) b.initial(init.coordinate, init.q0, init.v0);
  b.defaults(c.defaults);
  b.tolerances(c.rtol, c.atol);
  b.path("x1", "y1");
  return b.build();
}

std::string write_chain_toml(const ChainParameters& p) {
  check_chain_parameters(p);
  const ChainText c = make_chain_text(p);
  std::string out;
  out += fmt::format(
      "# The N-trailer chain with N = {0} (docs/gallery/chain.md), generated by\n"
      "#\n"
      "#     nhdyn example chain --bodies {0}\n"
      "#\n"
      "# (the same model as make_chain_spec in src/nhdyn/symbolic/chain.hpp). N Chaplygin sleighs on a\n"
      "# horizontal plane: body i rests on a blade at P_i = (xi, yi), heads along theta_i, has its centre\n"
      "# of mass a ahead of P_i, its front hitch f ahead and its rear hitch r behind. Body i+1's front\n"
      "# hitch is pinned to body i's rear hitch. n = 3N coordinates, s = 3N - 2 constraints (N blades,\n"
      "# 2 per pin), k = 2 degrees of freedom. No force does work: T is conserved.\n\n",
      p.bodies);
  out += fmt::format("name = \"{}\"\ndescription = \"{}\"\n\n", c.name, c.description);
  out += "coordinates = [";
  for (std::size_t i = 0; i < c.coordinates.size(); ++i)
    out += fmt::format("{}{}\"{}\"", i == 0 ? "" : ",", i % 3 == 0 ? (i == 0 ? "" : "\n  ") : " ", c.coordinates[i]);
  out += "]\n\n";
  out += "# T = sum over the bodies of m/2 |v_C|^2 + J/2 theta'^2, v_C the velocity of the centre of mass.\n";
  out += "kinetic_energy = \"\"\"\n";
  for (std::size_t i = 0; i < c.kinetic_energy.size(); ++i)
    out += fmt::format("{}{}\n", i == 0 ? "  " : "+ ", c.kinetic_energy[i]);
  out += "\"\"\"\n\n[parameters]\n";
  for (const ChainParameterText& par : c.parameters)
    out += fmt::format("{} = {{ value = {}, unit = \"{}\" }}  # {}\n", par.name, toml_number(par.value), par.unit,
                       par.comment);
  out += "\n# Body by body: the blade of body i, then the pin joining body i+1's front hitch to body i's rear hitch.\n";
  for (const ChainConstraintText& con : c.constraints)
    out += fmt::format("[[constraints]]\nname = \"{}\"\n{} = \"{}\"\n", con.name,
                       con.level == ConstraintLevel::position ? "position" : "velocity", con.text);
  out += "\n# All on the x axis heading along +x, moving at v0; the lead turns at w0 and the pins make\n"
         "# body i turn at w0 (-r/f)^(i-1).\n";
  out += "[initial.position]\n";
  for (const ChainInitialText& init : c.initial) out += fmt::format("{} = \"{}\"\n", init.coordinate, init.q0);
  out += "\n[initial.velocity]\n";
  for (const ChainInitialText& init : c.initial) out += fmt::format("{} = \"{}\"\n", init.coordinate, init.v0);
  out += fmt::format("\n[simulation]\nt_end = {}\noutput_step = {}\nrtol = {}\natol = {}\n", toml_number(c.defaults.t_end),
                     toml_number(c.defaults.output_step), toml_number(c.rtol), toml_number(c.atol));
  out += "\n[plot]\npath = [\"x1\", \"y1\"]               # the track of the lead's blade\n";
  return out;
}

}  // namespace nhdyn::symbolic
