// The contact modes' keys (friction, unilateral, restitution, mode) on [[wheels]] and
// [[knife_edges]] entries (docs/contact-modes.md, "Wheels" and "Knife edges"). A wheel with any
// of them is read as the [[contacts]] disk it is: the same constraints (NAME_contact, NAME_roll1,
// NAME_roll2), contact modes, columns and accelerations at random states, on the default plane
// and on a tilted plane given by the wheel's `normal`. A wheel without them keeps its own rows
// (NAME_slip1, NAME_slip2), and its accelerations and reactions agree with the disk contact's to
// round-off (a wheel is the disk contact, with its rows' names). Bad values are refused
// naming file:line; a knife edge refuses the keys, naming the key's place and why. The Whipple
// bicycle written with disk contacts is the bicycle of wheels, and friction on a wheel that its
// coordinates hold on the ground is refused saying that it needs its height.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "multibody/multibody_support.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/model/contact_forces.hpp"
#include "nhdyn/model/contact_modes.hpp"
#include "nhdyn/symbolic/detail/contact_geometry.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"
#include "support/models.hpp"
#include "support/text.hpp"

// A namespace of its own: the unity build joins this file with the other multibody tests.
namespace nhdyn::wheel_modes_test {
namespace {

using multibody_test::dynamics_at;
using multibody_test::uniform;

// A thin disk whose centre (x, y, z) is free, turned by z-x-y angles (so it may leave the ground);
// `helper` is appended: a [[wheels]] or a [[contacts]] entry.
std::string disk_with(const std::string& helper) { return test::free_disk_text("disk", "mu = 0.5\n", helper); }

const std::string kWheel = "\n[[wheels]]\nname = \"disk\"\nbody = \"disk\"\naxis = \"y\"\nradius = \"r\"\n";
const std::string kContact =
    "\n[[contacts]]\nname = \"disk\"\nbody = \"disk\"\nshape = { disk = \"r\", axis = \"y\" }\n";
const std::string kModes = "friction = \"mu\"\nunilateral = true\nrestitution = 0.5\n";

std::vector<std::string> constraint_names(const Model& model) {
  std::vector<std::string> names;
  for (const Constraint& c : model.constraints) names.push_back(c.name);
  return names;
}

std::vector<std::string> output_names(const Model& model) {
  std::vector<std::string> names;
  for (const DerivedOutput& o : model.outputs.list) names.push_back(o.name);
  return names;
}

// q'' and R of the Do Sanh form at (q, v), as one vector.
std::vector<double> solution_at(const Model& model, const std::vector<double>& q, const std::vector<double>& v) {
  const Data data = dynamics_at(model, q, v);
  std::vector<double> out(data.qdd.data(), data.qdd.data() + data.qdd.size());
  out.insert(out.end(), data.R.data(), data.R.data() + data.R.size());
  return out;
}

// Random states with |theta| < 1.2 (the disk not flat); not on the ground: the equations are
// compared, not a motion.
void random_state(std::mt19937& rng, std::vector<double>& q, std::vector<double>& v) {
  q = {uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, 0.05, 0.3),
       uniform(rng, -3, 3), uniform(rng, -1.2, 1.2), uniform(rng, -3, 3)};
  v.resize(6);
  for (double& x : v) x = uniform(rng, -3, 3);
}

// The largest |a - b| over the largest |b| (relative to the solution's scale).
double relative_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double diff = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    diff = std::max(diff, std::abs(a[i] - b[i]));
    scale = std::max(scale, std::abs(b[i]));
  }
  return diff / scale;
}

TEST(WheelModes, AWheelWithoutTheKeysKeepsItsOwnRows) {
  const Model wheel = load_model_text(disk_with(kWheel), "wheel.toml");
  EXPECT_EQ(constraint_names(wheel), (std::vector<std::string>{"disk_contact", "disk_slip1", "disk_slip2"}));
  EXPECT_EQ(wheel.contact_modes, nullptr);
}

// Without the keys: the same motion as the disk contact, whose rows are rotated alike and whose
// rim is written without the wheel's simplification (round-off apart).
TEST(WheelModes, AWheelWithoutTheKeysMovesAsItsDiskContact) {
  const Model wheel = load_model_text(disk_with(kWheel), "wheel.toml");
  const Model contact = load_model_text(disk_with(kContact), "contact.toml");
  ASSERT_EQ(contact.s(), 3);
  std::mt19937 rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    std::vector<double> q, v;
    random_state(rng, q, v);
    EXPECT_LT(relative_difference(solution_at(wheel, q, v), solution_at(contact, q, v)), 1e-12) << "trial " << trial;
  }
}

// With the keys: the wheel is the disk contact (the same text into the same builder).
void expect_same_model(const std::string& wheel_entry, const std::string& contact_entry) {
  const Model wheel = load_model_text(disk_with(wheel_entry), "wheel.toml");
  const Model contact = load_model_text(disk_with(contact_entry), "contact.toml");
  EXPECT_EQ(constraint_names(wheel), (std::vector<std::string>{"disk_contact", "disk_roll1", "disk_roll2"}));
  EXPECT_EQ(constraint_names(wheel), constraint_names(contact));
  ASSERT_NE(wheel.contact_modes, nullptr);
  ASSERT_NE(contact.contact_modes, nullptr);
  ASSERT_EQ(wheel.contact_modes->contacts.size(), 1u);
  EXPECT_EQ(wheel.contact_modes->contacts[0].name, "disk");
  EXPECT_TRUE(wheel.contact_modes->contacts[0].friction);
  EXPECT_TRUE(wheel.contact_modes->contacts[0].unilateral);
  EXPECT_EQ(contact_force_columns(wheel), contact_force_columns(contact));
  EXPECT_EQ(output_names(wheel), output_names(contact));
  EXPECT_EQ(output_names(wheel).front(), "disk_X");  // the contact point, as a contact has it
  std::mt19937 rng(11);
  for (int trial = 0; trial < 10; ++trial) {
    std::vector<double> q, v;
    random_state(rng, q, v);
    // One text into one builder; two loads in one process differ in GiNaC's term order only.
    // 1e-13: the term orders differ from run to run (GiNaC orders by hashes of addresses), and
    // so does the last bit; 1.2e-14 has been seen.
    EXPECT_LT(relative_difference(solution_at(wheel, q, v), solution_at(contact, q, v)), 1e-13) << "trial " << trial;
  }
}

TEST(WheelModes, AWheelWithTheKeysIsItsDiskContact) {
  expect_same_model(kWheel + kModes, kContact + kModes);
}

// The wheel's normal is the contact's plane (through the origin, as both are): a plane tilted by
// atan(3/4) about y, not normal to gravity.
TEST(WheelModes, TheWheelsNormalIsTheContactsPlane) {
  const std::string normal = "normal = [3, 0, 4]\n";  // not of unit length: normalized as the contact's
  expect_same_model(kWheel + normal + kModes,
                    kContact + "ground = { plane = [3, 0, 4] }\n" + kModes);
  // Without the keys the wheel on that plane moves as the disk contact on it too.
  const Model wheel = load_model_text(disk_with(kWheel + normal), "wheel.toml");
  const Model contact =
      load_model_text(disk_with(kContact + "ground = { plane = [3, 0, 4] }\n"), "contact.toml");
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<double> q, v;
    random_state(rng, q, v);
    EXPECT_LT(relative_difference(solution_at(wheel, q, v), solution_at(contact, q, v)), 1e-12) << "trial " << trial;
  }
}

// A wheel's normal written in a parameter that makes it vertical at the file's value: --set tilts
// the plane (the normal is not frozen to the axis it has at the file's values). The wheel so tilted
// moves as the wheel on the plane [3, 0, 4] (alpha = atan(3/4)).
TEST(WheelModes, SetTiltsAWheelsPlaneThatIsLevelInTheFile) {
  const std::string normal = "normal = [\"sin(alpha)\", 0, \"cos(alpha)\"]\n";
  const Model level = load_model_text(test::free_disk_text("disk", "mu = 0.5\nalpha = 0.0\n", kWheel + normal),
                                      "level.toml", {{"alpha", std::atan(0.75)}});
  const Model tilted = load_model_text(disk_with(kWheel + "normal = [3, 0, 4]\n"), "tilted.toml");
  std::mt19937 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<double> q, v;
    random_state(rng, q, v);
    EXPECT_LT(relative_difference(solution_at(level, q, v), solution_at(tilted, q, v)), 1e-12) << "trial " << trial;
  }
}

// The tilted wheel's derivation takes square roots of quotients; GiNaC's gcd once failed on them in
// some loads only, as its term order varies between loads (symbolic/simplify.cpp, split_root).
// Loaded again and again, it loads every time, to the same equations.
TEST(WheelModes, TheTiltedWheelLoadsEveryTime) {
  const std::string text = disk_with(kWheel + "normal = [3, 0, 4]\n");
  const Model first = load_model_text(text, "wheel.toml");
  std::mt19937 rng(5);
  std::vector<double> q, v;
  random_state(rng, q, v);
  const std::vector<double> expected = solution_at(first, q, v);
  for (int load = 0; load < 12; ++load) {
    const Model again = load_model_text(text, "wheel.toml");
    EXPECT_LT(relative_difference(solution_at(again, q, v), expected), 1e-13) << "load " << load;
  }
}

// Drawn as a wheel with the contact point's track a contact has, with the keys or without.
TEST(WheelModes, AWheelWithTheKeysIsDrawnAsAWheelWithItsTrack) {
  const auto kinds = [](const std::string& text) {
    std::vector<std::string> out;
    for (const symbolic::VisualItem& item : load_model_string(text, "wheel.toml").visual.items) {
      if (item.kind == symbolic::VisualKind::wheel) out.push_back("wheel " + item.name);
      if (item.kind == symbolic::VisualKind::track) out.push_back("track " + item.name);
    }
    std::sort(out.begin(), out.end());  // the scene's order does not matter
    return out;
  };
  EXPECT_EQ(kinds(disk_with(kWheel)), (std::vector<std::string>{"track disk", "wheel disk"}));
  EXPECT_EQ(kinds(disk_with(kWheel + kModes)), (std::vector<std::string>{"track disk", "wheel disk"}));
}

TEST(WheelModes, EachKeyAloneMakesTheWheelAContact) {
  for (const std::string key :
       {"friction = 0.3\n", "unilateral = true\n", "restitution = 0\n", "mode = \"rolling\"\n"}) {
    const Model wheel = load_model_text(disk_with(kWheel + key), "wheel.toml");
    EXPECT_EQ(constraint_names(wheel), (std::vector<std::string>{"disk_contact", "disk_roll1", "disk_roll2"})) << key;
    EXPECT_NE(wheel.contact_modes, nullptr) << key;
  }
}

// The message loading `text` as wheel.toml throws ("" if none).
std::string error_of(const std::string& text) {
  try {
    load_model_text(text, "wheel.toml");
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

// "wheel.toml:LINE:" for the line of `text` that starts with `line_start` (the last such line).
std::string place_of(const std::string& text, const std::string& line_start) {
  int line = 0, found = 0;
  std::size_t at = 0;
  while (at < text.size()) {
    ++line;
    const std::size_t end = std::min(text.find('\n', at), text.size());
    if (text.compare(at, line_start.size(), line_start) == 0) found = line;
    at = end + 1;
  }
  EXPECT_GT(found, 0) << line_start;
  return "wheel.toml:" + std::to_string(found) + ":";
}

void expect_refused(const std::string& entry, const std::string& line_start, const std::vector<std::string>& parts) {
  const std::string text = disk_with(entry);
  const std::string message = error_of(text);
  ASSERT_FALSE(message.empty()) << "no error for:\n" << entry;
  EXPECT_TRUE(message.starts_with(place_of(text, line_start))) << message;
  for (const std::string& part : parts) EXPECT_TRUE(test::contains(message, part)) << message << "\n  lacks: " << part;
}

TEST(WheelModes, BadValuesOnAWheelAreRefusedWithTheirPlace) {
  // Type errors name the key's line; the values the contact checks name the entry's.
  expect_refused(kWheel + "unilateral = \"yes\"\n", "unilateral", {"wheel 'disk': unilateral must be true or false"});
  expect_refused(kWheel + "friction = [0.1, 0.2, 0.3]\n", "friction", {"friction must be one coefficient or two"});
  expect_refused(kWheel + "mode = 1\n", "mode", {"wheel 'disk': mode must be a string"});
  expect_refused(kWheel + "friction = -0.1\n", "[[wheels]]", {"contact 'disk'", "friction", "-0.1", ">= 0"});
  expect_refused(kWheel + "friction = [0.2, 0.3]\n", "[[wheels]]", {"mu_s = 0.2 below mu_k = 0.3"});
  expect_refused(kWheel + "restitution = 1.5\n", "[[wheels]]", {"restitution", "between 0"});
  expect_refused(kWheel + "mode = \"hover\"\n", "[[wheels]]", {"unknown mode 'hover'"});
  expect_refused(kWheel + "mode = \"sliding\"\n", "[[wheels]]", {"mode = \"sliding\" needs a friction coefficient"});
  expect_refused(kWheel + "friction = 0.3\nmode = \"free\"\n", "[[wheels]]",
                 {"mode = \"free\" needs unilateral = true"});
  expect_refused(kWheel + "frictoin = 0.3\n", "frictoin", {"unknown key 'frictoin'", "did you mean 'friction'"});
}

// The Chaplygin sleigh of tests/support/models.hpp with KEY added to its [[knife_edges]] entry.
std::string sled_with(const std::string& key) {
  std::string text = test::kFlatSledBodies;
  text.insert(text.find("\n[initial]") + 1, key);
  return text;
}

TEST(WheelModes, AKnifeEdgeRefusesTheKeysSayingWhy) {
  EXPECT_EQ(error_of(sled_with("")), "");
  for (const std::string key : {"friction", "unilateral", "restitution", "mode"}) {
    const std::string value = key == "unilateral" ? "true" : key == "mode" ? "\"sliding\"" : "0.3";
    const std::string text = sled_with(key + " = " + value + "\n");
    const std::string message = error_of(text);
    // The key's own line and column: the value after "KEY = ".
    EXPECT_TRUE(message.starts_with(place_of(text, key) + std::to_string(key.size() + 4) + ": knife edge 'blade': '" +
                                    key + "' is not a key of a knife edge"))
        << message;
    for (const char* part : {"no normal force", "mu N", "docs/contact-modes.md", "Remove the key", "[[wheels]]"})
      EXPECT_TRUE(test::contains(message, part)) << message << "\n  lacks: " << part;
  }
}

// The Whipple bicycle of examples/whipple_bicycle.toml, its two [[wheels]] entries written as the
// [[contacts]] disks they are, `rear_keys` added to the rear one. Its coordinates hold the rear
// wheel on the ground (the rear frame's height is no coordinate), so that disk's gap, rR cos(phi) -
// rR sqrt(cos(phi)^2), is zero in every position without simplifying to 0.
std::string bicycle_text() { return test::read_text(test::example("whipple_bicycle.toml")); }

std::string bicycle_of_disks(const std::string& rear_keys) {
  std::string text = bicycle_text();
  const auto replace = [&](const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  };
  replace("[[wheels]]\nname = \"rear\"\nbody = \"rear_wheel\"\naxis = \"y\"\nradius = \"rR\"\n",
          "[[contacts]]\nname = \"rear\"\nbody = \"rear_wheel\"\nshape = { disk = \"rR\", axis = \"y\" }\n" + rear_keys);
  replace("[[wheels]]\nname = \"front\"\nbody = \"front_wheel\"\naxis = \"y\"\nradius = \"rF\"\n",
          "[[contacts]]\nname = \"front\"\nbody = \"front_wheel\"\nshape = { disk = \"rF\", axis = \"y\" }\n");
  return text;
}

// A gap that vanishes in every position adds no row, as a wheel's contact does not: the bicycle of
// disk contacts has the rows of the bicycle of wheels (it was refused, its rear_contact a zero row
// of b), and the same q'' and R at random states.
TEST(WheelModes, TheBicycleOfDiskContactsIsTheBicycleOfWheels) {
  const Model wheels = load_model_text(bicycle_text(), "wheels.toml");
  const Model disks = load_model_text(bicycle_of_disks(""), "disks.toml");
  EXPECT_EQ(constraint_names(wheels),
            (std::vector<std::string>{"rear_slip1", "rear_slip2", "front_contact", "front_slip1", "front_slip2"}));
  EXPECT_EQ(constraint_names(disks),
            (std::vector<std::string>{"rear_roll1", "rear_roll2", "front_contact", "front_roll1", "front_roll2"}));
  std::mt19937 rng(17);
  for (int trial = 0; trial < 10; ++trial) {
    // x, y, psi, phi, theta, delta, thetaR, thetaF: leaning, steered and pitched within a bicycle's range.
    const std::vector<double> q = {uniform(rng, -2, 2),     uniform(rng, -2, 2),     uniform(rng, -3, 3),
                                   uniform(rng, -0.6, 0.6), uniform(rng, -0.2, 0.2), uniform(rng, -0.8, 0.8),
                                   uniform(rng, -3, 3),     uniform(rng, -3, 3)};
    std::vector<double> v(8);
    for (double& x : v) x = uniform(rng, -3, 3);
    EXPECT_LT(relative_difference(solution_at(disks, q, v), solution_at(wheels, q, v)), 1e-12) << "trial " << trial;
  }
}

// Friction needs the gap's row (the normal force is its multiplier): where the coordinates hold the
// wheel on the ground, the run is refused at the entry, saying which coordinate to add.
TEST(WheelModes, FrictionOnAWheelTheCoordinatesHoldOnTheGroundIsRefusedSayingWhatToAdd) {
  for (const bool as_wheel : {true, false}) {
    std::string text = as_wheel ? bicycle_text() : bicycle_of_disks("friction = 0.8\n");
    if (as_wheel) text.insert(text.find("radius = \"rR\"\n") + 14, "friction = 0.8\n");
    const std::string entry = as_wheel ? "[[wheels]]" : "[[contacts]]";
    const std::size_t at = text.find(entry);
    ASSERT_NE(at, std::string::npos);
    const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
    const std::string message = error_of(text);
    EXPECT_TRUE(message.starts_with("wheel.toml:" + std::to_string(line) + ":1: contact 'rear'")) << message;
    for (const std::string part : {"friction and unilateral need the contact's gap as a constraint",
                                   "its gap is zero for every position", "its height"})
      EXPECT_TRUE(test::contains(message, part)) << message << "\n  lacks: " << part;
  }
}

// A disk leaning by theta about x on the plane z = 0, its centre free; `entry` its [[wheels]] or
// [[contacts]] table, `initial` the [initial] position.
std::string leaning_disk(const std::string& entry, const std::string& initial) {
  return "name = \"leaning\"\ncoordinates = [\"x\", \"y\", \"z\", \"psi\", \"theta\", \"phi\"]\n"
         "gravity = [0, 0, \"-g\"]\n\n[parameters]\nm = 0.5\nr = 0.2\ng = 9.81\ntheta0 = 2.0\n\n"
         "[[frames]]\nname = \"disk\"\ntranslation = [\"x\", \"y\", \"z\"]\n"
         "rotations = [[\"z\", \"psi\"], [\"x\", \"theta\"], [\"y\", \"phi\"]]\n\n"
         "[[bodies]]\nname = \"disk\"\nframe = \"disk\"\nmass = \"m\"\ninertia = [\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]\n\n" +
         entry + "\n[initial]\nposition = " + initial + "\n";
}

const std::string kLeaningWheel = "[[wheels]]\nname = \"wheel\"\nbody = \"disk\"\naxis = \"y\"\nradius = \"r\"\n";

// A wheel's rim is written with |axle x normal| = cos(theta), the sign of the reference
// configuration (theta = 0): a start at theta0 = 2, past lying flat from there, is refused at the
// wheel's line (the rim point written as the lowest would be the highest). The [[contacts]] disk
// keeps the root and starts there.
TEST(WheelModes, AWheelStartingTurnedPastLyingFlatIsRefusedSayingWhy) {
  const std::string initial = "{ x = 0, y = 0, z = \"-r*cos(theta0)\", psi = 0, theta = \"theta0\", phi = 0 }";
  const std::string text = leaning_disk(kLeaningWheel, initial);
  const std::string message = error_of(text);
  EXPECT_TRUE(message.starts_with(place_of(text, "[[wheels]]") + "1: wheel 'wheel': at the start the wheel is turned past "
                                  "lying flat from its reference configuration"))
      << message;
  for (const std::string part : {"is written as cos(theta)", "is -0.416 at the start"})
    EXPECT_TRUE(test::contains(message, part)) << message << "\n  lacks: " << part;
  std::string contact = kLeaningWheel;
  contact.replace(contact.find("[[wheels]]"), 10, "[[contacts]]");
  contact.replace(contact.find("axis = \"y\"\nradius = \"r\"\n"), 24, "shape = { disk = \"r\", axis = \"y\" }\n");
  EXPECT_EQ(error_of(leaning_disk(contact, initial)), "");
  // Leaning by 1.5608 (cos = 0.01) or more toward flat: refused as lying flat at the start.
  const std::string flat = error_of(
      leaning_disk(kLeaningWheel, "{ x = 0, y = 0, z = \"r*cos(1.5608)\", psi = 0, theta = 1.5608, phi = 0 }"));
  EXPECT_TRUE(test::contains(flat, "the disk lies flat")) << flat;
  EXPECT_TRUE(test::contains(flat, "at the start (|axle x normal| = 0.01, below 0.01)")) << flat;
}

// An axle along the plane's normal in every position (a disk turned about z only, axis = "z") has
// no lowest rim point: refused naming the entry (it was an internal error, a division by zero).
TEST(WheelModes, AnAxleAlwaysAlongTheNormalIsRefused) {
  const std::string frames = "name = \"flat\"\ncoordinates = [\"x\", \"y\", \"psi\"]\ngravity = [0, 0, \"-g\"]\n\n"
                             "[parameters]\nm = 0.5\nr = 0.2\ng = 9.81\n\n[[frames]]\nname = \"disk\"\n"
                             "translation = [\"x\", \"y\", 0]\nrotations = [[\"z\", \"psi\"]]\n\n[[bodies]]\n"
                             "name = \"disk\"\nframe = \"disk\"\nmass = \"m\"\ninertia = [1, 1, 2]\n\n";
  for (const std::string entry : {"[[wheels]]\nname = \"wheel\"\nbody = \"disk\"\naxis = \"z\"\nradius = \"r\"\n",
                                  "[[contacts]]\nname = \"wheel\"\nbody = \"disk\"\nshape = { disk = \"r\", axis = \"z\" }\n"}) {
    const std::string message = error_of(frames + entry);
    EXPECT_TRUE(test::contains(message, "the axle is along the plane's normal in every position")) << message;
    EXPECT_TRUE(test::contains(message, "give as `axis` the axle of the body's frame")) << message;
  }
}

// A gap that depends on t alone (a ball whose height is prescribed, r + A sin(10 pi t), which
// vanishes at every tenth of a second) is not taken for a zero: its row is refused as one that
// does not involve the coordinates, as it was.
TEST(WheelModes, AGapOfTimeAloneIsNotTakenForZero) {
  const std::string text = "name = \"shaken\"\ncoordinates = [\"x\", \"y\", \"a\", \"b\", \"c\"]\n"
                           "gravity = [0, 0, \"-g\"]\n\n[parameters]\nm = 1\nr = 0.1\ng = 9.81\nA = 0.02\n\n"
                           "[[frames]]\nname = \"ball\"\ntranslation = [\"x\", \"y\", \"r + A*sin(10*pi*t)\"]\n"
                           "rotations = [[\"x\", \"a\"], [\"y\", \"b\"], [\"z\", \"c\"]]\n\n[[bodies]]\n"
                           "name = \"ball\"\nframe = \"ball\"\nmass = \"m\"\n"
                           "inertia = [\"2/5*m*r^2\", \"2/5*m*r^2\", \"2/5*m*r^2\"]\n\n"
                           "[[contacts]]\nname = \"ball\"\nbody = \"ball\"\nshape = { sphere = \"r\" }\n";
  const std::string message = error_of(text);
  EXPECT_TRUE(test::contains(message, "constraint 'ball_contact' does not involve the velocities")) << message;
}

// A plane normal written with parameters, normal = [0, "-k", "k"], normalizes through sqrt(k^2):
// a root of parameters, not the rim's, which stays a root and is not watched (a watch on it would
// stop a run at once for k = 0.005). The rim's sqrt(cos(theta)^2) becomes cos(theta), watched.
TEST(WheelModes, OnlyTheRootsOfTheCoordinatesAreWrittenWithoutTheRoot) {
  symbolic::SpecBuilder b("roots");
  b.coordinate("theta").parameter("k", 0.005).parameter("r", 0.2);
  const symbolic::Spec& spec = b.current();
  std::vector<GiNaC::ex> roots;
  const GiNaC::ex parameters = b.parse("sqrt(k^2)*cos(theta)");
  EXPECT_TRUE(symbolic::contact_roots_of_squares(parameters, spec, roots).is_equal(parameters));
  EXPECT_TRUE(roots.empty());
  const GiNaC::ex rim = b.parse("r*sqrt(cos(theta)^2)");
  EXPECT_TRUE(symbolic::contact_roots_of_squares(rim, spec, roots).is_equal(b.parse("r*cos(theta)")));
  ASSERT_EQ(roots.size(), 1u);
  EXPECT_TRUE(roots[0].is_equal(b.parse("cos(theta)")));
  // Negative where every coordinate is 0: -u, positive there.
  roots.clear();
  EXPECT_TRUE(symbolic::contact_roots_of_squares(b.parse("sqrt(sin(theta - 2)^2)"), spec, roots)
                  .is_equal(b.parse("-sin(theta - 2)")));
}
}  // namespace
}  // namespace nhdyn::wheel_modes_test
