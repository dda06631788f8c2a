// A hostile plugin library whose registration throws: the host must report it as an error that
// names the library.
#include <stdexcept>

#include "framework/registry.hpp"

extern "C" int driftlab_plugin_interface_version() { return driftlab::kPluginInterfaceVersion; }
extern "C" void driftlab_register_plugins(driftlab::Registry&) {
  throw std::runtime_error("the hostile fixture refuses to register");
}
