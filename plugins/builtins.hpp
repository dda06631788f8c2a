// The built-in plugins (DESIGN.md §3): every plugin of plugins/ registered through one explicit
// function, safe with static linking; a test asserts the exact set of names.
#pragma once

#include "framework/registry.hpp"

namespace driftlab {

// Registers every built-in plugin with `registry`.
void register_builtin_plugins(Registry& registry);

}  // namespace driftlab
