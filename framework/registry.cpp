#include "framework/registry.hpp"

#include <algorithm>
#include <boost/dll/shared_library.hpp>
#include <map>

#include "framework/error.hpp"

namespace driftlab {

struct Registry::Impl {
  std::vector<boost::dll::shared_library> libraries;  // outlive the plugin infos below
  std::map<std::string, PluginInfo> plugins;
  std::string loading_origin;  // set while a library registers its plugins
};

std::string PluginInfo::kind() const { return name.substr(0, name.find('/')); }

Registry::Registry() : impl_(std::make_unique<Impl>()) {}
Registry::~Registry() = default;

void Registry::add(PluginInfo info) {
  const auto slash = info.name.find('/');
  const Location where{impl_->loading_origin, 0, info.name};
  if (slash == std::string::npos || slash == 0 || slash + 1 == info.name.size() ||
      info.name.find('/', slash + 1) != std::string::npos)
    throw ConfigError(where, "plugin names are kind/name");
  const auto& kinds = plugin_kinds();
  if (std::find(kinds.begin(), kinds.end(), info.kind()) == kinds.end())
    throw ConfigError(where, "unknown plugin kind '" + info.kind() + "'");
  if (impl_->plugins.count(info.name))
    throw ConfigError(where, "a plugin with this name is already registered (from " +
                                 impl_->plugins.at(info.name).origin + ")");
  if (!info.make) throw ConfigError(where, "plugin has no factory");
  if (!impl_->loading_origin.empty()) info.origin = impl_->loading_origin;
  impl_->plugins.emplace(info.name, std::move(info));
}

bool Registry::contains(const std::string& name) const { return impl_->plugins.count(name) != 0; }

const PluginInfo& Registry::info(const std::string& name) const {
  auto it = impl_->plugins.find(name);
  if (it != impl_->plugins.end()) return it->second;
  const auto kind = name.substr(0, name.find('/'));
  std::string known;
  for (const auto* p : list(kind)) known += (known.empty() ? "" : ", ") + p->name;
  if (known.empty())
    for (const auto* p : list()) known += (known.empty() ? "" : ", ") + p->name;
  throw UnknownPluginError({"", 0, name}, "unknown plugin (known: " + (known.empty() ? "none" : known) + ")");
}

std::vector<const PluginInfo*> Registry::list(const std::string& kind) const {
  std::vector<const PluginInfo*> out;
  for (const auto& [name, info] : impl_->plugins)
    if (kind.empty() || info.kind() == kind) out.push_back(&info);
  return out;
}

std::unique_ptr<Plugin> Registry::create(const std::string& name, const ParamValues& params) const {
  return info(name).make(params, *this);
}

void Registry::throw_wrong_interface(const std::string& name) const {
  throw ConfigError({"", 0, name}, "plugin does not implement the interface of its kind");
}

void Registry::load_library(const std::filesystem::path& path) {
  const Location where{path.string(), 0, ""};
  if (!std::filesystem::exists(path)) throw UnknownPluginError(where, "plugin library does not exist");
  boost::dll::shared_library library;
  try {
    library.load(path.string(), boost::dll::load_mode::rtld_lazy | boost::dll::load_mode::rtld_local);
  } catch (const std::exception& e) {
    throw UnknownPluginError(where, std::string("cannot load plugin library: ") + e.what());
  }
  if (!library.has("driftlab_plugin_interface_version") || !library.has("driftlab_register_plugins"))
    throw UnknownPluginError(where, "not a driftlab plugin library (it does not export "
                                    "driftlab_plugin_interface_version and driftlab_register_plugins)");
  const int version = library.get<int()>("driftlab_plugin_interface_version")();
  if (version != kPluginInterfaceVersion)
    throw UnknownPluginError(where, "plugin library was built against interface version " + std::to_string(version) +
                                        ", this driftlab uses version " + std::to_string(kPluginInterfaceVersion));
  impl_->libraries.push_back(library);
  impl_->loading_origin = path.string();
  try {
    library.get<void(Registry&)>("driftlab_register_plugins")(*this);
  } catch (...) {
    impl_->loading_origin.clear();
    throw;
  }
  impl_->loading_origin.clear();
}

void Registry::load_directory(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw UnknownPluginError({dir.string(), 0, ""}, "plugin directory does not exist");
  std::vector<std::filesystem::path> libs;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.is_regular_file() && entry.path().extension() == ".so") libs.push_back(entry.path());
  std::sort(libs.begin(), libs.end());
  for (const auto& lib : libs) load_library(lib);
}

void Registry::load_path_list(const std::string& dirs) {
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const auto end = std::min(dirs.find(':', start), dirs.size());
    if (end > start) load_directory(dirs.substr(start, end - start));
    start = end + 1;
  }
}

}  // namespace driftlab
