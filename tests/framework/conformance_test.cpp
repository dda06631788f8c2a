// One conformance test over every built-in plugin, driven by the parameter tables alone.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "plugins/builtins.hpp"
#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"

namespace driftlab {
namespace {

class EveryBuiltinPlugin : public ::testing::TestWithParam<std::string> {
 protected:
  static const Registry& registry() {
    static const Registry* r = [] {
      auto* reg = new Registry;
      register_builtin_plugins(*reg);
      return reg;
    }();
    return *r;
  }
};

std::vector<std::string> builtin_names() {
  Registry r;
  register_builtin_plugins(r);
  std::vector<std::string> out;
  for (const auto* info : r.list()) out.push_back(info->name);
  return out;
}

TEST_P(EveryBuiltinPlugin, IsConstructibleFromItsDefaults) {
  const auto values = params_from_assignments(registry(), GetParam(), {});
  EXPECT_NE(registry().create(GetParam(), values), nullptr);
}

TEST_P(EveryBuiltinPlugin, RejectsAGeneratedInvalidValueForEveryConstraintNamingTheParameter) {
  const auto& info = registry().info(GetParam());
  for (const auto& spec : info.params.params) {
    for (const auto& bad : invalid_examples(spec)) {
      EXPECT_FALSE(spec.check(bad.value).empty()) << spec.key << " accepted " << format_value(bad.value);
      if (spec.type == driftlab::ParamType::Plugin) continue;
      const std::string assignment = spec.key + "=" + format_value(bad.value);
      try {
        params_from_assignments(registry(), GetParam(), {assignment});
        ADD_FAILURE() << GetParam() << " accepted " << assignment << " (" << bad.why << ")";
      } catch (const ConfigError& e) {
        bool named = false;
        for (const auto& p : e.problems()) named = named || p.where.field == spec.key;
        EXPECT_TRUE(named) << e.what();
      }
    }
  }
}

TEST_P(EveryBuiltinPlugin, DescribesItselfCompletely) {
  const auto& info = registry().info(GetParam());
  EXPECT_FALSE(info.summary.empty());
  EXPECT_FALSE(info.reference.empty()) << "built-ins name the paper or standard they implement";
  for (const auto& spec : info.params.params) {
    EXPECT_FALSE(spec.doc.empty()) << spec.key;
    EXPECT_TRUE(spec.type == driftlab::ParamType::Plugin || !spec.unit.empty())
        << spec.key << " states a unit ('1' if none)";
    EXPECT_THAT(spec.key, ::testing::MatchesRegex("[a-z][a-z0-9_]*")) << "snake_case keys";
    EXPECT_TRUE(spec.check(spec.default_value).empty()) << spec.key << ": default violates its own constraint";
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryBuiltinPlugin, ::testing::ValuesIn(builtin_names()), [](const auto& test_info) {
  std::string n = test_info.param;
  std::replace(n.begin(), n.end(), '/', '_');
  return n;
});

}  // namespace
}  // namespace driftlab
