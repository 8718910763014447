// The scene a model built in C++ through MultibodyBuilder draws (symbolic/multibody.hpp): its
// bodies and wheels are drawn by the builder, so a wheel (and the body it rolls with) added from
// C++ appears in the report's scene as the same wheel written in a model file does — the same
// kind, name, radius and axle, at the same origin and turned by the same rotation (the two specs
// have symbol tables of their own: positions are compared by value at random states, sizes at the
// parameters' values), over the ground's grid. A wheel given as a contact (mode keys) is drawn as
// a wheel too.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "multibody/multibody_support.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"
#include "nhdyn/symbolic/visual.hpp"
#include "support/models.hpp"

// A namespace of its own: the unity build joins this file with the other multibody tests.
namespace nhdyn::builder_scene_test {
namespace {

using multibody_test::evaluate;
using multibody_test::uniform;

// A thin disk whose centre (x, y, z) is free, turned by z-x-y angles, rolling on the ground with
// its axle along its frame's y axis; in a model file, and through the C++ API.
const std::string kRim = "\n[[wheels]]\nname = \"rim\"\nbody = \"disk\"\naxis = \"y\"\nradius = \"r\"\n";
const std::string kDisk = test::free_disk_text("disk", "", kRim);

symbolic::Spec disk_from_cpp() {
  symbolic::SpecBuilder b("disk");
  for (const char* q : {"x", "y", "z", "psi", "theta", "phi"}) b.coordinate(q);
  b.parameter("m", 0.5).parameter("r", 0.2).parameter("g", 9.81);
  symbolic::MultibodyBuilder mb(b);
  mb.gravity({"0", "0", "-g"})
      .frame("disk", "ground", {"x", "y", "z"}, {{"z", "psi", {}}, {"x", "theta", {}}, {"y", "phi", {}}})
      .body("disk", "disk", "m", {"0", "0", "0"},
            {{{"m*r^2/4", "0", "0"}, {"0", "m*r^2/2", "0"}, {"0", "0", "m*r^2/4"}}})
      .rolling_wheel("rim", "disk", "y", "r");
  mb.apply();
  for (const char* q : {"x", "y", "psi", "theta", "phi"}) b.initial(q, "0", "0");
  b.initial("z", "r", "0");
  return b.build();
}

const symbolic::VisualItem* find(const symbolic::Spec& spec, symbolic::VisualKind kind) {
  for (const symbolic::VisualItem& item : spec.visual.items)
    if (item.kind == kind) return &item;
  return nullptr;
}

// `a` of spec `sa` and `b` of spec `sb` draw the same: kind, name, axle, size and inertia at the
// parameters' values, origin and rotation at random states.
void expect_same_drawing(const symbolic::Spec& sa, const symbolic::VisualItem& a, const symbolic::Spec& sb,
                         const symbolic::VisualItem& b) {
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.axis, b.axis);
  const std::vector<double> none(6, 0.0);
  EXPECT_DOUBLE_EQ(evaluate(sa, a.size, none, none), evaluate(sb, b.size, none, none));
  ASSERT_EQ(a.inertia.size(), b.inertia.size());
  for (std::size_t k = 0; k < a.inertia.size(); ++k)
    EXPECT_DOUBLE_EQ(evaluate(sa, a.inertia[k], none, none), evaluate(sb, b.inertia[k], none, none));
  ASSERT_EQ(a.at.size(), 3u);
  ASSERT_EQ(b.at.size(), 3u);
  ASSERT_EQ(a.other.size(), 9u);
  ASSERT_EQ(b.other.size(), 9u);
  std::mt19937 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<double> q(6), v(6);
    for (double& x : q) x = uniform(rng, -2, 2);
    for (double& x : v) x = uniform(rng, -3, 3);
    for (std::size_t k = 0; k < 3; ++k)
      EXPECT_NEAR(evaluate(sa, a.at[k], q, v), evaluate(sb, b.at[k], q, v), 1e-14) << "origin " << k;
    for (std::size_t k = 0; k < 9; ++k)
      EXPECT_NEAR(evaluate(sa, a.other[k], q, v), evaluate(sb, b.other[k], q, v), 1e-14) << "rotation " << k;
  }
}

TEST(BuilderScene, AWheelAddedFromCppIsDrawnAsTheSameWheelFromAFile) {
  const symbolic::Spec file = load_model_string(kDisk, "disk.toml");
  const symbolic::Spec cpp = disk_from_cpp();
  const symbolic::VisualItem* from_file = find(file, symbolic::VisualKind::wheel);
  const symbolic::VisualItem* from_cpp = find(cpp, symbolic::VisualKind::wheel);
  ASSERT_NE(from_file, nullptr);
  ASSERT_NE(from_cpp, nullptr);
  expect_same_drawing(file, *from_file, cpp, *from_cpp);
  // The disk of radius r = 0.2 about the frame's y axis.
  EXPECT_EQ(from_cpp->axis, 1);
  EXPECT_DOUBLE_EQ(evaluate(cpp, from_cpp->size, std::vector<double>(6), std::vector<double>(6)), 0.2);
  EXPECT_TRUE(cpp.visual.ground);
  EXPECT_FALSE(cpp.visual.planar);
}

TEST(BuilderScene, ABodyAddedFromCppIsDrawnAsTheSameBodyFromAFile) {
  const symbolic::Spec file = load_model_string(kDisk, "disk.toml");
  const symbolic::Spec cpp = disk_from_cpp();
  const symbolic::VisualItem* from_file = find(file, symbolic::VisualKind::body);
  const symbolic::VisualItem* from_cpp = find(cpp, symbolic::VisualKind::body);
  ASSERT_NE(from_file, nullptr);
  ASSERT_NE(from_cpp, nullptr);
  expect_same_drawing(file, *from_file, cpp, *from_cpp);
  // Its mass and its inertia m r^2 / 2 about the axle.
  const std::vector<double> none(6, 0.0);
  EXPECT_DOUBLE_EQ(evaluate(cpp, from_cpp->size, none, none), 0.5);
  EXPECT_DOUBLE_EQ(evaluate(cpp, from_cpp->inertia[4], none, none), 0.5 * 0.2 * 0.2 / 2);
}

// The scene's items in order: the builder draws the body and the wheel when they are given, among
// the items the file adds itself (the frame's axes), as before the drawing moved into the builder.
TEST(BuilderScene, TheFilesSceneKeepsTheOrderOfItsSections) {
  const symbolic::Spec file = load_model_string(kDisk, "disk.toml");
  std::vector<symbolic::VisualKind> kinds;
  for (const symbolic::VisualItem& item : file.visual.items) kinds.push_back(item.kind);
  // The wheel is the disk contact it is: its plane and its contact point's track, then the wheel.
  EXPECT_EQ(kinds, (std::vector<symbolic::VisualKind>{symbolic::VisualKind::frame, symbolic::VisualKind::body,
                                                      symbolic::VisualKind::plane, symbolic::VisualKind::track,
                                                      symbolic::VisualKind::wheel}));
}

// A wheel's or a knife edge's own plane (`normal`) is drawn as the plane it is: a plane item whose
// axes (t1, t2, n, as the columns of `other`) are orthonormal with n the given normal, normalized;
// a wheel without a normal draws the level plane (which the report shows as its z = 0 grid).
TEST(BuilderScene, AWheelsAndAKnifeEdgesPlaneIsDrawnInItsAxes) {
  const auto plane_axes = [](const std::string& text) {
    const symbolic::Spec spec = load_model_string(text, "plane.toml");
    const symbolic::VisualItem* plane = find(spec, symbolic::VisualKind::plane);
    std::vector<double> axes;
    if (plane == nullptr) return axes;
    for (const GiNaC::ex& e : plane->other) axes.push_back(evaluate(spec, e, std::vector<double>(static_cast<std::size_t>(spec.n()), 0.1), std::vector<double>(static_cast<std::size_t>(spec.n()), 0.0)));
    return axes;
  };
  const auto check = [](const std::vector<double>& axes, const std::array<double, 3>& n, const std::string& what) {
    ASSERT_EQ(axes.size(), 9u) << what;
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(axes[static_cast<std::size_t>(3 * i + 2)], n[static_cast<std::size_t>(i)], 1e-15) << what;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        double dot = 0.0;
        for (int i = 0; i < 3; ++i) dot += axes[static_cast<std::size_t>(3 * i + a)] * axes[static_cast<std::size_t>(3 * i + b)];
        EXPECT_NEAR(dot, a == b ? 1.0 : 0.0, 1e-15) << what << " axes " << a << ", " << b;
      }
  };
  check(plane_axes(test::free_disk_text("disk", "", kRim + "normal = [3, 0, 4]\n")), {0.6, 0.0, 0.8}, "wheel");
  std::string sled = test::kFlatSledBodies;
  sled.insert(sled.find("axis = \"x\"\n") + 11, "normal = [0, 1, 1]\n");
  check(plane_axes(sled), {0.0, std::sqrt(0.5), std::sqrt(0.5)}, "knife edge");
  // On the default plane: the level plane opposite to gravity (the report draws it as its grid of z = 0).
  check(plane_axes(kDisk), {0.0, 0.0, 1.0}, "wheel on the default plane");
}

// A wheel with a mode key is the disk contact it is, and still drawn as a wheel (by the builder,
// MultibodyBuilder::wheel_drawing), after its contact point's track.
TEST(BuilderScene, AWheelGivenAsAContactIsDrawnAsTheSameWheel) {
  const symbolic::Spec plain = load_model_string(kDisk, "disk.toml");
  const std::string with_mode = test::free_disk_text("disk", "", kRim + "friction = 0.5\n");
  const symbolic::Spec contact = load_model_string(with_mode, "disk.toml");
  const symbolic::VisualItem* a = find(plain, symbolic::VisualKind::wheel);
  const symbolic::VisualItem* b = find(contact, symbolic::VisualKind::wheel);
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(a->where, b->where);
  ASSERT_FALSE(contact.visual.items.empty());
  EXPECT_EQ(contact.visual.items.back().kind, symbolic::VisualKind::wheel);
  EXPECT_EQ(contact.visual.items[contact.visual.items.size() - 2].kind, symbolic::VisualKind::track);
}

}  // namespace
}  // namespace nhdyn::builder_scene_test
