#include "python/src/convert.hpp"

#include <pybind11/stl.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "framework/error.hpp"
#include "framework/params_io.hpp"

namespace driftlab::python {
namespace {

// An array whose memory is `owner`'s: the capsule deletes it when numpy releases the array.
template <class Storage>
py::array owned_array(std::unique_ptr<Storage> owner, std::vector<py::ssize_t> shape) {
  double* data = owner->data();
  py::capsule capsule(owner.get(), [](void* p) { delete static_cast<Storage*>(p); });
  owner.release();
  return py::array_t<double>(std::move(shape), data, capsule);
}

YAML::Node to_yaml(py::handle value) {
  if (value.is_none()) return YAML::Node(YAML::NodeType::Null);
  if (py::isinstance<py::bool_>(value)) return YAML::Node(value.cast<bool>());
  if (py::isinstance<py::int_>(value)) return YAML::Node(value.cast<std::int64_t>());
  if (py::isinstance<py::float_>(value)) return YAML::Node(value.cast<double>());
  if (py::isinstance<py::str>(value)) return YAML::Node(value.cast<std::string>());
  if (py::isinstance<py::dict>(value)) {
    YAML::Node map(YAML::NodeType::Map);
    for (const auto& [k, v] : value.cast<py::dict>()) map[py::str(k).cast<std::string>()] = to_yaml(v);
    return map;
  }
  if (py::isinstance<py::sequence>(value)) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const auto& item : value.cast<py::sequence>()) list.push_back(to_yaml(item));
    return list;
  }
  // numpy scalars and other numbers: through their float value (integral ones stay integral).
  const double number = value.cast<double>();
  if (std::floor(number) == number && std::abs(number) < 9.0e15) return YAML::Node(static_cast<std::int64_t>(number));
  return YAML::Node(number);
}

}  // namespace

Eigen::Map<const Eigen::VectorXd> vector_view(const InputArray& array, const char* name) {
  if (array.ndim() != 1)
    throw DataError({"", 0, name},
                    "expected a 1-D array of samples, got " + std::to_string(array.ndim()) + " dimensions");
  const Eigen::Map<const Eigen::VectorXd> x(array.data(), array.shape(0));
  for (Eigen::Index i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]))
      throw DataError({"", 0, name}, "sample " + std::to_string(i) + " is " + (std::isnan(x[i]) ? "NaN" : "infinite") +
                                         " (every sample must be finite)");
  return x;
}

py::array to_numpy(Eigen::VectorXd&& values) {
  const auto n = static_cast<py::ssize_t>(values.size());
  return owned_array(std::make_unique<Eigen::VectorXd>(std::move(values)), {n});
}

py::array columns_to_numpy(Eigen::MatrixXd&& columns) {
  const auto rows = static_cast<py::ssize_t>(columns.rows()), cols = static_cast<py::ssize_t>(columns.cols());
  return owned_array(std::make_unique<Eigen::MatrixXd>(std::move(columns)), {cols, rows});
}

py::object to_python(const nlohmann::json& value) {
  switch (value.type()) {
    case nlohmann::json::value_t::null:
      return py::none();
    case nlohmann::json::value_t::boolean:
      return py::bool_(value.get<bool>());
    case nlohmann::json::value_t::number_integer:
      return py::int_(value.get<std::int64_t>());
    case nlohmann::json::value_t::number_unsigned:
      return py::int_(value.get<std::uint64_t>());
    case nlohmann::json::value_t::number_float:
      return py::float_(value.get<double>());
    case nlohmann::json::value_t::string:
      return py::str(value.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list list;
      for (const auto& item : value) list.append(to_python(item));
      return list;
    }
    case nlohmann::json::value_t::object: {
      py::dict dict;
      for (const auto& [k, v] : value.items()) dict[py::str(k)] = to_python(v);
      return dict;
    }
    default:
      return py::none();  // binary and discarded values do not occur in reports
  }
}

py::object to_python(const ParamValue& value) {
  return std::visit(
      [](const auto& v) -> py::object {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, std::shared_ptr<const PluginSpec>>) {
          py::dict params;
          for (const auto& [k, p] : v->params.all()) params[py::str(k)] = to_python(p);
          py::dict spec;
          spec["plugin"] = v->name;
          spec["params"] = params;
          return spec;
        } else {
          return py::cast(v);
        }
      },
      value);
}

ParamValues resolve_keyword_params(const Registry& registry, const std::string& plugin, const py::dict& params) {
  YAML::Node node(YAML::NodeType::Map);
  for (const auto& [k, v] : params) node[py::str(k).cast<std::string>()] = to_yaml(v);
  std::vector<Diagnostic> problems;
  ParamValues values = resolve_params(registry, plugin, node, plugin, "", problems);
  if (!problems.empty()) throw ConfigError(std::move(problems));
  return values;
}

}  // namespace driftlab::python
