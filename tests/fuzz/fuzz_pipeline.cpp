// libFuzzer harness: the pipeline description parser (framework/pipeline.hpp) with every built-in
// plugin registered. Property oracle: a pipeline that loads writes an effective pipeline that
// loads again and writes itself unchanged (the effective pipeline reloads to itself). Rejections
// must be ConfigError; anything else is a finding.
#include <cstdint>
#include <string>

#include "plugins/builtins.hpp"
#include "framework/error.hpp"
#include "framework/pipeline.hpp"
#include "framework/registry.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  static const Registry* registry = [] {
    auto* r = new Registry();
    register_builtin_plugins(*r);
    return r;
  }();
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const Pipeline p = parse_pipeline(text, "fuzz.yaml", *registry);
    const std::string effective = effective_pipeline_yaml(p, *registry);
    const Pipeline again = parse_pipeline(effective, "effective.yaml", *registry);
    fuzz::require(effective_pipeline_yaml(again, *registry) == effective, "the effective pipeline reloads to itself",
                  effective);
  } catch (const ConfigError&) {
  }
  return 0;
}
