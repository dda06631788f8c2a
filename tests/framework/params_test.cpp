#include "framework/params.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "tests/framework/test_plugins.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;

class ParamsTest : public ::testing::Test {
 protected:
  ParamsTest() { testing_plugins::register_test_plugins(registry_); }
  Registry registry_;
};

TEST_F(ParamsTest, DefaultsFillEveryDeclaredKeyIncludingNestedPlugins) {
  const auto values = params_from_assignments(registry_, "regressor/test_linear", {});
  EXPECT_EQ(values.integer("min_terms"), 1);
  EXPECT_EQ(values.text("method"), "qr");
  EXPECT_EQ(values.plugin("optimizer").name, "optimizer/test_midpoint");
  EXPECT_EQ(values.plugin("optimizer").params.integer("evaluations"), 1);
}

TEST_F(ParamsTest, AssignmentsAreParsedAsYamlIncludingNestedPlugins) {
  const auto values =
      params_from_assignments(registry_, "regressor/test_linear",
                              {"max_terms=5", "optimizer={plugin: optimizer/test_midpoint, params: {evaluations: 4}}"});
  EXPECT_EQ(values.integer("max_terms"), 5);
  EXPECT_EQ(values.plugin("optimizer").params.integer("evaluations"), 4);
}

TEST_F(ParamsTest, UnknownKeysListTheValidKeys) {
  try {
    params_from_assignments(registry_, "filter/test_gain", {"gian=2"});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("gian: unknown parameter of filter/test_gain (valid: gain, offset, jitter, seed)"));
  }
}

TEST_F(ParamsTest, WrongTypesAndOutOfRangeValuesAreRejectedTogether) {
  try {
    params_from_assignments(registry_, "filter/test_gain", {"gain=0", "jitter=maybe", "offset=abc"});
    FAIL();
  } catch (const ConfigError& e) {
    ASSERT_EQ(e.problems().size(), 3u) << e.what();
    EXPECT_THAT(e.what(), HasSubstr("gain: value 0 is out of range: must be (0, 100]"));
    EXPECT_THAT(e.what(), HasSubstr("jitter: expected boolean"));
    EXPECT_THAT(e.what(), HasSubstr("offset: expected real"));
  }
}

TEST_F(ParamsTest, IntegersRejectFractions) {
  EXPECT_THROW(params_from_assignments(registry_, "regressor/test_linear", {"max_terms=2.5"}), ConfigError);
}

TEST_F(ParamsTest, EffectiveYamlRoundTripsThroughTheLoader) {
  const auto values = params_from_assignments(registry_, "regressor/test_linear",
                                              {"method=normal", "optimizer={params: {evaluations: 3}}"});
  const auto yaml = params_to_yaml(registry_, "regressor/test_linear", values);
  std::vector<Diagnostic> problems;
  const auto again = resolve_params(registry_, "regressor/test_linear", yaml, "x", "", problems);
  EXPECT_TRUE(problems.empty());
  EXPECT_EQ(again.text("method"), "normal");
  EXPECT_EQ(again.plugin("optimizer").params.integer("evaluations"), 3);
}

TEST(ParamSpec, DescribesItsConstraint) {
  EXPECT_EQ(param::real("a", 1, "s", "").greater_than(0).constraint_text(), "> 0");
  EXPECT_EQ(param::real("a", 1, "s", "").at_least(0).at_most(2).constraint_text(), "[0, 2]");
  EXPECT_EQ(param::real("a", 1, "s", "").greater_than(0).less_than(2).constraint_text(), "(0, 2)");
  EXPECT_EQ(param::choice("c", "x", {"x", "y"}, "").constraint_text(), "one of: x y");
  EXPECT_EQ(param::boolean("b", true, "").constraint_text(), "any");
}

TEST(ParamSpec, GeneratedInvalidExamplesAreRejected) {
  const std::vector<ParamSpec> specs{param::real("a", 1, "s", "").greater_than(0).at_most(5),
                                     param::integer("n", 3, "1", "").at_least(1),
                                     param::choice("c", "x", {"x", "y"}, ""),
                                     param::reals("v", {1.0}, "1", "").at_least(0), param::boolean("b", true, "")};
  for (const auto& spec : specs) {
    ASSERT_TRUE(spec.check(spec.default_value).empty()) << spec.key;
    for (const auto& bad : invalid_examples(spec))
      EXPECT_FALSE(spec.check(bad.value).empty())
          << spec.key << " accepted " << format_value(bad.value) << " (" << bad.why << ")";
  }
}

}  // namespace
}  // namespace driftlab
