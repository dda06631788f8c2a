// The plugin registry: built-in plugins (registered by an explicit function, safe with static
// linking) and external plugins loaded from shared libraries with Boost.DLL.
//
// An external plugin library exports two C symbols:
//   extern "C" int driftlab_plugin_interface_version();   // must return kPluginInterfaceVersion
//   extern "C" void driftlab_register_plugins(driftlab::Registry&);
// See tests/plugins/external/moving_average_plugin.cpp for a complete example.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "framework/params.hpp"
#include "framework/plugin.hpp"

namespace driftlab {

class Registry;

struct PluginInfo {
  std::string name;       // "kind/name"
  std::string summary;    // one line
  std::string reference;  // paper or standard it implements, may be empty
  ParamTable params;
  std::function<std::unique_ptr<Plugin>(const ParamValues&, const Registry&)> make;
  std::string origin = "built-in";  // or the path of the library it came from

  std::string kind() const;  // the part before '/'
};

class Registry {
 public:
  Registry();
  ~Registry();
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  // Throws ConfigError on a malformed name, an unknown kind or a duplicate.
  void add(PluginInfo info);

  bool contains(const std::string& name) const;
  // Throws UnknownPluginError listing the known plugins of that kind.
  const PluginInfo& info(const std::string& name) const;
  // Sorted by name; all kinds when `kind` is empty.
  std::vector<const PluginInfo*> list(const std::string& kind = "") const;

  // Creates a plugin from validated parameters.
  std::unique_ptr<Plugin> create(const std::string& name, const ParamValues& params) const;
  std::unique_ptr<Plugin> create(const PluginSpec& spec) const { return create(spec.name, spec.params); }
  // Creates and checks the kind's interface, e.g. create_as<Optimizer>(spec).
  template <class Interface>
  std::unique_ptr<Interface> create_as(const PluginSpec& spec) const {
    auto plugin = create(spec);
    if (auto* typed = dynamic_cast<Interface*>(plugin.get())) {
      plugin.release();
      return std::unique_ptr<Interface>(typed);
    }
    throw_wrong_interface(spec.name);
  }

  // Loads one plugin library. Throws UnknownPluginError when the file is missing, is not a
  // driftlab plugin, or was built against another interface version.
  void load_library(const std::filesystem::path& path);
  // Loads every *.so in a directory (non-recursive, sorted by file name).
  void load_directory(const std::filesystem::path& dir);
  // Loads every directory of a ':'-separated list (e.g. $DRIFTLAB_PLUGIN_PATH); empty is fine.
  void load_path_list(const std::string& dirs);

 private:
  [[noreturn]] void throw_wrong_interface(const std::string& name) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace driftlab
