#include "framework/registry.hpp"

#include <dlfcn.h>
#include <elf.h>
#include <link.h>

#include <algorithm>
#include <boost/dll/shared_library.hpp>
#include <cstring>
#include <fstream>
#include <map>

#include "framework/error.hpp"

namespace driftlab {

struct Registry::Impl {
  std::vector<boost::dll::shared_library> libraries;  // outlive the plugin infos below
  std::map<std::string, PluginInfo> plugins;
  std::string loading_origin;  // set while a library registers its plugins
};

namespace {

// Checks a plugin library's ELF headers against the file before it is mapped: a truncated or
// corrupt file would otherwise crash the host inside dlopen (SIGBUS on a page past the end).
// Returns an empty string when the file looks like a complete shared object for this machine.
std::string elf_problem(const std::filesystem::path& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return "cannot read the file: " + ec.message();
  std::ifstream in(path, std::ios::binary);
  ElfW(Ehdr) eh{};
  if (size < sizeof eh || !in.read(reinterpret_cast<char*>(&eh), sizeof eh))
    return "not a shared library (file of " + std::to_string(size) + " bytes is shorter than an ELF header)";
  if (std::memcmp(eh.e_ident, ELFMAG, SELFMAG) != 0) return "not a shared library (no ELF header)";
  if (eh.e_ident[EI_CLASS] != (sizeof(void*) == 8 ? ELFCLASS64 : ELFCLASS32))
    return "shared library of another word size than this driftlab";
  ElfW(Ehdr) self{};
  std::ifstream exe("/proc/self/exe", std::ios::binary);
  if (exe.read(reinterpret_cast<char*>(&self), sizeof self) && self.e_machine != eh.e_machine)
    return "shared library for another processor architecture (e_machine " + std::to_string(eh.e_machine) + ")";
  if (eh.e_type != ET_DYN) return "not a shared library (ELF type " + std::to_string(eh.e_type) + ")";
  const auto within = [&](std::uint64_t offset, std::uint64_t count, std::uint64_t entry) {
    return offset <= size && count * entry <= size - offset;
  };
  if (eh.e_phentsize != sizeof(ElfW(Phdr)) || eh.e_phnum == 0 || !within(eh.e_phoff, eh.e_phnum, eh.e_phentsize))
    return "truncated or corrupt shared library (program headers lie outside the " + std::to_string(size) +
           "-byte file)";
  if (eh.e_shnum != 0 && !within(eh.e_shoff, eh.e_shnum, eh.e_shentsize))
    return "truncated or corrupt shared library (section headers lie outside the " + std::to_string(size) +
           "-byte file)";
  in.seekg(static_cast<std::streamoff>(eh.e_phoff));
  for (unsigned i = 0; i < eh.e_phnum; ++i) {
    ElfW(Phdr) ph{};
    if (!in.read(reinterpret_cast<char*>(&ph), sizeof ph)) return "truncated shared library (program header)";
    if ((ph.p_type == PT_LOAD || ph.p_type == PT_DYNAMIC) && !within(ph.p_offset, 1, ph.p_filesz))
      return "truncated shared library: a segment needs bytes up to offset " +
             std::to_string(ph.p_offset + ph.p_filesz) + ", the file has " + std::to_string(size);
  }
  return "";
}

// The address of an exported symbol, checked to be a function (a data symbol of that name would
// be called as code and crash the host). Empty string on success, else the problem.
std::string function_symbol(void* handle, const char* name, void*& address) {
  dlerror();
  address = dlsym(handle, name);
  if (!address) return std::string("it does not export ") + name;
  Dl_info info{};
  void* entry = nullptr;
  if (dladdr1(address, &info, &entry, RTLD_DL_SYMENT) == 0 || entry == nullptr)
    return std::string("cannot inspect the symbol ") + name;
  const auto* sym = static_cast<const ElfW(Sym)*>(entry);
  if (sym == nullptr) return std::string("cannot inspect the symbol ") + name;
  const auto type = ELF64_ST_TYPE(sym->st_info);
  if (type != STT_FUNC && type != STT_GNU_IFUNC)
    return std::string(name) + " is not a function (a data symbol of that name)";
  return "";
}

}  // namespace

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
    throw ConfigError(
        where, "a plugin with this name is already registered (from " + impl_->plugins.at(info.name).origin + ")");
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
  throw UnknownPluginError(
      {"", 0, name}, "unknown plugin " + quoted_excerpt(name) + " (known: " + (known.empty() ? "none" : known) + ")");
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
  if (const auto problem = elf_problem(path); !problem.empty())
    throw UnknownPluginError(where, "cannot load plugin library: " + problem);
  boost::dll::shared_library library;
  try {
    library.load(path.string(), boost::dll::load_mode::rtld_lazy | boost::dll::load_mode::rtld_local);
  } catch (const std::exception& e) {
    throw UnknownPluginError(where, std::string("cannot load plugin library: ") + e.what());
  }
  void* version_fn = nullptr;
  void* register_fn = nullptr;
  for (const auto& [name, address] : {std::pair<const char*, void**>{"driftlab_plugin_interface_version", &version_fn},
                                      std::pair<const char*, void**>{"driftlab_register_plugins", &register_fn}}) {
    const auto problem = function_symbol(library.native(), name, *address);
    if (!problem.empty())
      throw UnknownPluginError(where, "not a driftlab plugin library: " + problem +
                                          " (a plugin exports the functions driftlab_plugin_interface_version "
                                          "and driftlab_register_plugins)");
  }
  const int version = reinterpret_cast<int (*)()>(version_fn)();
  if (version != kPluginInterfaceVersion)
    throw UnknownPluginError(where, "plugin library was built against interface version " + std::to_string(version) +
                                        ", this driftlab uses version " + std::to_string(kPluginInterfaceVersion));
  impl_->libraries.push_back(library);
  impl_->loading_origin = path.string();
  struct ClearOrigin {
    std::string& origin;
    ~ClearOrigin() { origin.clear(); }
  } clear{impl_->loading_origin};
  try {
    reinterpret_cast<void (*)(Registry&)>(register_fn)(*this);
  } catch (const ConfigError& e) {
    std::vector<Diagnostic> problems = e.problems();
    for (auto& p : problems) {
      if (p.where.file.empty()) p.where.file = path.string();
      p.message = "registering the library's plugins failed: " + p.message;
    }
    throw UnknownPluginError(problems);
  } catch (const std::exception& e) {
    throw UnknownPluginError(where, std::string("registering the library's plugins failed: ") + e.what());
  } catch (...) {
    throw UnknownPluginError(where,
                             "registering the library's plugins failed with an exception that is not a "
                             "std::exception");
  }
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
