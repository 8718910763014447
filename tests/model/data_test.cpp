// make_data refuses a model whose dense matrices cannot fit in memory, before allocating them,
// with the sizes, the limit and the way out in the message.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/data.hpp"

namespace nhdyn {
namespace {

// Terms of a free particle per coordinate: enough for a Model of any size.
class UnitEvaluator final : public Evaluator {
 public:
  void terms(double, const double*, const double*, double*, const TermsOut&) const override {}
};

Model model_of_size(int n, int s) {
  Model m;
  m.name = "big";
  for (int i = 0; i < n; ++i) m.coordinates.push_back("q" + std::to_string(i));
  for (int i = 0; i < s; ++i) m.constraints.push_back({"c" + std::to_string(i), ConstraintLevel::velocity, ""});
  m.q0 = Vector::Zero(n);
  m.v0 = Vector::Zero(n);
  m.evaluator = std::make_shared<UnitEvaluator>();
  return m;
}

TEST(DenseMemory, BytesFollowTheMatricesOfData) {
  // n = 1000, s = 998: 8 (5e6 + 2 (1998)^2 + 6 * 998e3 + 2 * 998^2) bytes.
  const double expected = 8.0 * (5e6 + 2.0 * 1998.0 * 1998.0 + 6.0 * 998e3 + 2.0 * 998.0 * 998.0);
  EXPECT_DOUBLE_EQ(dense_data_bytes(1000, 998), expected);
  // Quadratic: ten times the size, a hundred times the memory.
  EXPECT_DOUBLE_EQ(dense_data_bytes(10000, 9980) / dense_data_bytes(1000, 998), 100.0);
}

TEST(DenseMemory, ATooLargeModelIsRefusedWithTheLimit) {
  const Model m = model_of_size(3000, 2998);
  EXPECT_NO_THROW(check_dense_memory(m, 1e12));
  try {
    check_dense_memory(m, 1e8);  // 0.1 GB against the 1.51 GB needed
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("model 'big' is too large"), std::string::npos) << what;
    EXPECT_NE(what.find("n = 3000"), std::string::npos) << what;
    EXPECT_NE(what.find("1.51 GB"), std::string::npos) << what;
    EXPECT_NE(what.find("0.1 GB"), std::string::npos) << what;
    // With s ~ n the matrices take 8 (5 + 8 + 6 + 2) n^2 = 168 n^2 bytes: n = sqrt(1e8 / 168) = 771.
    EXPECT_NE(what.find("about n = 771 coordinates"), std::string::npos) << what;
    EXPECT_NE(what.find("sparse path"), std::string::npos) << what;
  }
}

TEST(DenseMemory, MakeDataRefusesBeforeAllocating) {
  // 300000 coordinates would need 7 TB: more than any machine this runs on.
  const Model m = model_of_size(300000, 0);
  ASSERT_GT(physical_memory_bytes(), 0.0);
  ASSERT_GT(dense_data_bytes(300000, 0), physical_memory_bytes());
  EXPECT_THROW(make_data(m), ModelError);
}

}  // namespace
}  // namespace nhdyn
