#include "framework/registry.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>

#include "plugins/builtins.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "framework/pipeline.hpp"
#include "tests/framework/test_plugins.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;

const std::filesystem::path kGoodPlugins = DRIFTLAB_TEST_PLUGIN_DIR;
const std::filesystem::path kBadPlugins = DRIFTLAB_TEST_BAD_PLUGIN_DIR;

std::vector<std::string> names(const Registry& r, const std::string& kind = "") {
  std::vector<std::string> out;
  for (const auto* info : r.list(kind)) out.push_back(info->name);
  return out;
}

TEST(BuiltinPlugins, AreExactlyTheDocumentedSet) {
  Registry registry;
  register_builtin_plugins(registry);
  EXPECT_THAT(names(registry),
              ::testing::ElementsAre("classifier/sample_entropy", "decomposition/ceemdan", "decomposition/eemd",
                                     "decomposition/emd", "decomposition/vmd", "effect/hysteresis",
                                     "effect/mode_split_drift", "effect/periodic_disturbance",
                                     "effect/scale_factor_temperature", "effect/temperature_rate", "effect/thermal_lag",
                                     "effect/warmup_transient", "filter/kalman", "filter/rate_of_change", "filter/tfpf",
                                     "filter/wavelet", "optimizer/ga", "optimizer/pagmo", "regressor/elm",
                                     "regressor/polynomial", "regressor/rbf", "regressor/svr"));
}

TEST(Registry, RejectsMalformedNamesUnknownKindsAndDuplicates) {
  Registry registry;
  testing_plugins::register_test_plugins(registry);
  const auto make = [](const ParamValues& p, const Registry&) -> std::unique_ptr<Plugin> {
    return std::make_unique<testing_plugins::Gain>(p);
  };
  EXPECT_THROW(registry.add({.name = "gain", .make = make}), ConfigError);
  EXPECT_THROW(registry.add({.name = "smoother/gain", .make = make}), ConfigError);
  EXPECT_THROW(registry.add({.name = "filter/test_gain", .make = make}), ConfigError);
}

TEST(Registry, NamesTheKnownPluginsOfAKindWhenOneIsUnknown) {
  Registry registry;
  testing_plugins::register_test_plugins(registry);
  try {
    registry.info("filter/nope");
    FAIL();
  } catch (const UnknownPluginError& e) {
    EXPECT_THAT(e.what(), HasSubstr("filter/nope: unknown plugin 'filter/nope' (known: filter/test_gain)"));
  }
}

TEST(Registry, CreatesNestedPluginsThroughTheirKindInterface) {
  Registry registry;
  testing_plugins::register_test_plugins(registry);
  auto optimizer = registry.create_as<Optimizer>(
      {"optimizer/test_midpoint", params_from_assignments(registry, "optimizer/test_midpoint", {})});
  RunContext ctx;
  const auto r =
      optimizer->minimize([](const Eigen::VectorXd& x) { return x.squaredNorm(); }, {{"a", 1.0, 3.0, false}}, ctx);
  EXPECT_DOUBLE_EQ(r.best[0], 2.0);
  EXPECT_THROW(registry.create_as<Filter>({"optimizer/test_midpoint", {}}), ConfigError);
}

TEST(ExternalPlugins, AreLoadedFromADirectoryAndRunFromAPipelineByName) {
  Registry registry;
  registry.load_directory(kGoodPlugins);
  ASSERT_TRUE(registry.contains("filter/moving_average"));
  EXPECT_THAT(registry.info("filter/moving_average").origin, HasSubstr("driftlab_test_moving_average"));

  const auto pipeline =
      load_pipeline(std::filesystem::path(DRIFTLAB_TEST_DATA) / "pipelines" / "external.yaml", registry);
  TimeSeries record(Eigen::VectorXd::LinSpaced(21, 0.0, 2.0));
  Eigen::VectorXd rate = Eigen::VectorXd::Zero(21);
  rate[10] = 7.0;  // an impulse: a 7-point centred average spreads it to 1.0 over samples 7..13
  record.set_channel({role::kRate, "rad/s", "test", rate});
  nlohmann::json report;
  const auto out = run_pipeline(pipeline, registry, record, {}, report).at("smoothed").sum();
  for (Eigen::Index i = 0; i < 21; ++i) EXPECT_DOUBLE_EQ(out[i], (i >= 7 && i <= 13) ? 1.0 : 0.0) << i;
}

TEST(ExternalPlugins, ValidateTheirParametersLikeBuiltins) {
  Registry registry;
  registry.load_directory(kGoodPlugins);
  try {
    params_from_assignments(registry, "filter/moving_average", {"window=4"});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("window: window must be odd"));
  }
}

TEST(ExternalPlugins, AreFoundThroughAColonSeparatedPathList) {
  Registry registry;
  registry.load_path_list("::" + kGoodPlugins.string() + ":");
  EXPECT_TRUE(registry.contains("filter/moving_average"));
}

TEST(ExternalPlugins, FromAMissingFileGetAClearError) {
  Registry registry;
  try {
    registry.load_library(kBadPlugins / "libdriftlab_test_does_not_exist.so");
    FAIL();
  } catch (const UnknownPluginError& e) {
    EXPECT_THAT(e.what(), HasSubstr("plugin library does not exist"));
  }
}

TEST(ExternalPlugins, ThatAreNotPluginsGetAClearError) {
  Registry registry;
  try {
    registry.load_library(kBadPlugins / "libdriftlab_test_not_a.so");
    FAIL();
  } catch (const UnknownPluginError& e) {
    EXPECT_THAT(e.what(), HasSubstr("not a driftlab plugin library"));
  }
}

TEST(ExternalPlugins, BuiltAgainstAnotherInterfaceVersionGetAClearError) {
  Registry registry;
  try {
    registry.load_library(kBadPlugins / "libdriftlab_test_wrong_version.so");
    FAIL();
  } catch (const UnknownPluginError& e) {
    EXPECT_THAT(e.what(), HasSubstr("built against interface version 42, this driftlab uses version 1"));
  }
}

}  // namespace
}  // namespace driftlab
