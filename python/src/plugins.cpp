#include <pybind11/stl.h>

#include <cstdlib>
#include <memory>

#include "framework/registry.hpp"
#include "plugins/builtins.hpp"
#include "python/src/bindings.hpp"
#include "python/src/convert.hpp"

namespace driftlab::python {

const Registry& registry() {
  static const std::unique_ptr<Registry> instance = [] {
    auto r = std::make_unique<Registry>();
    register_builtin_plugins(*r);
    if (const char* path = std::getenv("DRIFTLAB_PLUGIN_PATH")) r->load_path_list(path);
    return r;
  }();
  return *instance;
}

namespace {

// One row per parameter of the plugin's table: what signatures and docstrings are made from.
py::list plugin_params(const std::string& name) {
  py::list rows;
  for (const auto& spec : registry().info(name).params.params) {
    py::dict row;
    row["key"] = spec.key;
    row["type"] = to_string(spec.type);
    row["default"] = to_python(spec.default_value);
    row["unit"] = spec.unit;
    row["constraint"] = spec.constraint_text();
    row["doc"] = spec.doc;
    rows.append(row);
  }
  return rows;
}

}  // namespace

void bind_plugins(py::module_& m) {
  m.def("plugins", [](const std::string& kind) {
    std::vector<std::string> names;
    for (const auto* info : registry().list(kind)) names.push_back(info->name);
    return names;
  }, py::arg("kind") = "", "Names of the registered plugins (\"kind/name\"), of one kind when given.");
  m.def("plugin_params", &plugin_params, py::arg("name"),
        "The parameter table of a plugin: one dict per parameter with key, type, default, unit, constraint, doc.");
}

}  // namespace driftlab::python
