// A plugin library built against another interface version: loading it must fail clearly.
#include "framework/registry.hpp"

extern "C" int driftlab_plugin_interface_version() { return driftlab::kPluginInterfaceVersion + 41; }
extern "C" void driftlab_register_plugins(driftlab::Registry&) {}
