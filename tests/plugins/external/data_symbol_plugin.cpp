// A hostile plugin library: `driftlab_register_plugins` is a data symbol, not a function. The host
// must refuse it (calling it would jump into data and crash).
#include "framework/registry.hpp"

extern "C" int driftlab_plugin_interface_version() { return driftlab::kPluginInterfaceVersion; }
extern "C" {
__attribute__((visibility("default"))) unsigned char driftlab_register_plugins[64] = {0xff, 0xff, 0xff, 0xff};
}
