// The code generator's text: what the header contains and what it must not, deterministic output,
// identifiers and namespaces. That the generated code compiles and computes what the interpreted
// program does is tested end to end in tests/codegen/.
#include "nhdyn/symbolic/codegen.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "codegen/hand_built_specs.hpp"
#include "nhdyn/core/error.hpp"
#include "support/text.hpp"

namespace nhdyn::symbolic {
namespace {

using testing::HandBuilt;
using testing::make_hand_built_appell;
using testing::make_hand_built_sled;

using nhdyn::test::contains;

TEST(Codegen, HeaderImplementsTheEvaluatorAndTheModelMaker) {
  const HandBuilt built = make_hand_built_sled();
  const std::string code = generate_code(built.spec, built.derivation);
  EXPECT_TRUE(contains(code, "#pragma once")) << code;
  EXPECT_TRUE(contains(code, "#include \"nhdyn/model/evaluator.hpp\""));
  EXPECT_TRUE(contains(code, "#include \"nhdyn/model/model.hpp\""));
  EXPECT_FALSE(contains(code, "ginac")) << code;
  EXPECT_TRUE(contains(code, "namespace nhdyn {\nnamespace generated {\n"));
  EXPECT_TRUE(contains(code, "class SledEvaluator final : public ::nhdyn::Evaluator"));
  EXPECT_TRUE(contains(code, "inline ::nhdyn::Model make_sled_model(const SledParameters& p = {})"));
  // The parameters are a struct with the values as defaults, read by the evaluator at run time.
  EXPECT_TRUE(contains(code, "struct SledParameters {\n  double m = 1.0;  // [kg]\n")) << code;
  EXPECT_TRUE(contains(code, "std::shared_ptr<const ::nhdyn::Evaluator> with_parameters(")) << code;
  EXPECT_TRUE(contains(code, "bool has_complement() const override { return true; }"));
  EXPECT_TRUE(contains(code, "bool has_energy() const override { return true; }"));
  EXPECT_TRUE(contains(code, "model.constraints.push_back({\"blade\", ::nhdyn::ConstraintLevel::velocity, "
                             "\"-sin(phi) x' + cos(phi) y' = 0\"});"));
  EXPECT_TRUE(contains(code, "model.path = ::nhdyn::PlanarPath{0, 1};"));
  // One sin and one cos of phi in the terms, shared by every entry.
  const std::size_t terms = code.find("void terms("), complement = code.find("complement(");
  const std::string terms_body = code.substr(terms, complement - terms);
  EXPECT_EQ(terms_body.find("std::sin("), terms_body.rfind("std::sin(")) << terms_body;
  // t is not read: the parameter is left unnamed so that the code compiles without warnings.
  EXPECT_TRUE(contains(terms_body, "void terms(double /*t*/, const double* q, const double* v,")) << terms_body;
}

TEST(Codegen, DoublesAreWrittenWithFullPrecision) {
  SledParameters p;
  p.m = 0.1;
  p.g = 1.0 / 3.0;
  const HandBuilt built = make_hand_built_sled(p);
  const std::string code = generate_code(built.spec, built.derivation);
  EXPECT_TRUE(contains(code, "double m = 0.10000000000000001;")) << code;
  EXPECT_TRUE(contains(code, "double g = 0.33333333333333331;")) << code;
  EXPECT_TRUE(contains(code, "model.v0[0] = 1.0;")) << code;
}

TEST(Codegen, OutputIsDeterministic) {
  const HandBuilt first = make_hand_built_appell();
  const std::string a = generate_code(first.spec, first.derivation);
  EXPECT_EQ(a, generate_code(first.spec, first.derivation));
  // Symbols made in another order get other GiNaC hashes, hence another term order inside GiNaC.
  std::vector<GiNaC::symbol> noise;
  for (int i = 0; i < 23; ++i) noise.emplace_back("noise");
  const HandBuilt second = make_hand_built_appell();
  EXPECT_EQ(a, generate_code(second.spec, second.derivation));
}

TEST(Codegen, NamespaceAndIdentifierAreConfigurable) {
  HandBuilt built = make_hand_built_sled();
  built.spec.name = "sled-paper 2";
  CodegenOptions options;
  options.namespace_name = "lab::models";
  std::string code = generate_code(built.spec, built.derivation, options);
  EXPECT_TRUE(contains(code, "namespace lab {\nnamespace models {\n")) << code;
  EXPECT_TRUE(contains(code, "make_sled_paper_2_model(")) << code;
  EXPECT_TRUE(contains(code, "class SledPaper2Evaluator")) << code;
  EXPECT_TRUE(contains(code, "model.name = \"sled-paper 2\";")) << code;
  options.namespace_name = "";
  options.identifier = "my_sled";
  code = generate_code(built.spec, built.derivation, options);
  EXPECT_FALSE(contains(code, "namespace ")) << code;
  EXPECT_TRUE(contains(code, "make_my_sled_model(")) << code;
  options.identifier = "2sled";
  EXPECT_THROW(generate_code(built.spec, built.derivation, options), InputError);
  options.identifier = "";
  options.namespace_name = "lab::3d";
  EXPECT_THROW(generate_code(built.spec, built.derivation, options), InputError);
  options.namespace_name = "std";
  EXPECT_THROW(generate_code(built.spec, built.derivation, options), InputError);
  // Inside a::std the generated std::shared_ptr named a::std::shared_ptr: the header did not compile.
  for (const char* hiding : {"a::std", "lab::std::models"}) {
    options.namespace_name = hiding;
    try {
      generate_code(built.spec, built.derivation, options);
      ADD_FAILURE() << hiding << " accepted";
    } catch (const InputError& e) {
      EXPECT_TRUE(contains(e.what(), "has a part 'std' that would hide the standard library")) << e.what();
    }
  }
}

TEST(Codegen, IdentifiersAreSanitized) {
  EXPECT_EQ(make_identifier("sled"), "sled");
  EXPECT_EQ(make_identifier("sled-paper"), "sled_paper");
  EXPECT_EQ(make_identifier("  two  words!"), "two_words");
  EXPECT_EQ(make_identifier("3d pendulum"), "model_3d_pendulum");
  EXPECT_EQ(make_identifier("class"), "class_");
  EXPECT_EQ(make_identifier("__x__"), "x");
  EXPECT_EQ(make_identifier("ç"), "model");
  EXPECT_EQ(make_identifier(""), "model");
}

TEST(Codegen, StringsAreEscaped) {
  HandBuilt built = make_hand_built_sled();
  built.spec.description = "a \"quoted\" \\ line\nnext";
  const std::string code = generate_code(built.spec, built.derivation);
  EXPECT_TRUE(contains(code, "model.description = \"a \\\"quoted\\\" \\\\ line\\nnext\";")) << code;
}

TEST(Codegen, CompilerErrorsPassThrough) {
  HandBuilt built = make_hand_built_sled();
  built.derivation.Q(0, 0) = GiNaC::zeta(built.spec.symbols.coordinate(0));
  EXPECT_THROW(generate_code(built.spec, built.derivation), ModelError);
}

}  // namespace
}  // namespace nhdyn::symbolic
