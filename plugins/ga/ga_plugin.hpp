// optimizer/ga as an Optimizer object built from the kernel's configuration (plugins/ga/ga.hpp),
// for code that runs the shared tuning loop (plugins/tuning/tuning.hpp search()) without a registry:
// models/calibration's RBF tuning. The registry's optimizer/ga is the same class, built from its
// parameters. ConfigError for bounds the kernel refuses.
#pragma once

#include <memory>

#include "framework/plugin.hpp"
#include "plugins/ga/ga.hpp"

namespace driftlab {

// config.threads is replaced by the context's thread count on each minimize().
std::unique_ptr<Optimizer> make_ga_optimizer(const ga::Config& config);

}  // namespace driftlab
