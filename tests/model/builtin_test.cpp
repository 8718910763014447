// The built-in models: the registry finds them by name and refuses unknown names with the list;
// each model's shape is consistent and its analytic D and residuals agree with its terms.
#include "nhdyn/model/builtin.hpp"

#include <gtest/gtest.h>

#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/sled.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

TEST(Builtin, ListsThePapersExamples) {
  std::string names;
  for (const BuiltinModelInfo& info : list_builtin_models()) names += info.name + " ";
  EXPECT_EQ(names, "appell sled sled-paper ");
}

TEST(Builtin, UnknownNameListsTheAvailableModels) {
  try {
    make_builtin_model("sleigh");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("'sleigh'"), std::string::npos);
    for (const char* name : {"appell", "sled", "sled-paper"}) EXPECT_NE(message.find(name), std::string::npos);
  }
}

TEST(Builtin, InitialStatesSatisfyTheirConstraints) {
  for (const BuiltinModelInfo& info : list_builtin_models()) {
    const Model model = make_builtin_model(info.name);
    Data data = make_data(model);
    Vector f(model.velocity_constraints());
    model.evaluator->velocity_residual(model.t0, model.q0.data(), model.v0.data(), data.scratch.data(), f.data());
    EXPECT_LT(f.norm(), 1e-14) << info.name;
  }
}

TEST(Builtin, AccelerationFormIsTheTimeDerivativeOfTheVelocityResidual) {
  // b q'' + b0 must be d/dt f(t, q, q') for any q'': check with a finite difference along a
  // short straight path q(t) = q + t v + t^2/2 a for a random acceleration a.
  for (const BuiltinModelInfo& info : list_builtin_models()) {
    const Model model = make_builtin_model(info.name);
    Data data = make_data(model);
    Vector q(3), v(3), a(3);
    q << 0.2, -0.1, 0.4;
    v << 0.9, 0.3, 0.8;
    a << 0.3, -0.7, 0.5;
    ASSERT_EQ(compute_terms(model, data, 0.0, q.data(), v.data()), Status::ok);
    const double analytic = (data.b * a)(0) + data.b0(0);
    const double h = 1e-5;
    auto f_at = [&](double t) {
      Vector qt = q + t * v + 0.5 * t * t * a, vt = v + t * a;
      double f = 0.0;
      model.evaluator->velocity_residual(t, qt.data(), vt.data(), data.scratch.data(), &f);
      return f;
    };
    double derivative = (f_at(h) - f_at(-h)) / (2.0 * h);
    // Appell's b is the paper's: d f/dt divided by 2 z'.
    if (info.name == "appell") derivative /= 2.0 * v(2);
    EXPECT_NEAR(analytic, derivative, 1e-8) << info.name;
  }
}

TEST(Builtin, SledRefusesAnInertiaThatIsNotPositiveDefinite) {
  SledParameters p;
  p.rho = p.a;  // the centre of mass cannot sit farther out than the radius of gyration
  EXPECT_THROW(make_sled_model(SledVariant::centre_of_mass, p), InputError);
}

TEST(ModelShape, DuplicatedNamesAreRefused) {
  Model model = make_builtin_model("sled");
  model.constraints[0].name = "x";
  EXPECT_THROW(make_data(model), ModelError);
}

}  // namespace
}  // namespace nhdyn
