// Plugin tables, the decomposition plugins (decomposition/emd, eemd, ceemdan, vmd and any external
// one) run through the registry exactly as a pipeline step or `driftlab decompose` runs them, and
// sample entropy (plugins/sample_entropy) with the classifier's declared defaults for m and r.
#include <pybind11/stl.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/builtins.hpp"
#include "plugins/sample_entropy/sample_entropy.hpp"
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

constexpr const char* kSampleEntropy = "classifier/sample_entropy";

py::dict plugin_info(const std::string& name) {
  const PluginInfo& info = registry().info(name);
  py::list rows;
  for (const auto& spec : info.params.params) {
    py::dict row;
    row["key"] = spec.key;
    row["type"] = to_string(spec.type);
    row["default"] = to_python(spec.default_value);
    row["unit"] = spec.unit;
    row["constraint"] = spec.constraint_text();
    row["doc"] = spec.doc;
    rows.append(row);
  }
  py::list rules;
  for (const auto& rule : info.params.rules) rules.append(rule.description);
  py::dict d;
  d["name"] = info.name;
  d["summary"] = info.summary;
  d["reference"] = info.reference;
  d["origin"] = info.origin;
  d["params"] = rows;
  d["rules"] = rules;
  return d;
}

unsigned thread_count(int threads) {
  if (threads < 1) throw ConfigError({"", 0, "threads"}, "must be >= 1, got " + std::to_string(threads));
  return static_cast<unsigned>(threads);
}

struct DecompositionResult {
  std::string plugin;
  py::array imfs, residue;
  py::dict params, diagnostics;
};

DecompositionResult decompose(const std::string& plugin, const InputArray& x, const py::dict& kwargs, int threads,
                              std::optional<double> fs_hz) {
  const Registry& reg = registry();
  if (reg.info(plugin).kind() != "decomposition")
    throw ConfigError({"", 0, "plugin"}, "'" + plugin + "' is not a decomposition plugin");
  const ParamValues values = resolve_keyword_params(reg, plugin, kwargs);
  auto decomposer = reg.create_as<Decomposer>({plugin, values});
  const Eigen::VectorXd signal = vector_view(x, "x");  // the interface takes an owning vector
  RunContext ctx;
  ctx.threads = thread_count(threads);
  if (fs_hz) {
    if (!(*fs_hz > 0.0) || !std::isfinite(*fs_hz)) throw ConfigError({"", 0, "fs_hz"}, "must be a finite rate > 0 Hz");
    ctx.time_s = Eigen::VectorXd::LinSpaced(signal.size(), 0.0, static_cast<double>(signal.size() - 1)) / *fs_hz;
  }
  Decomposition d;
  {
    py::gil_scoped_release release;
    d = decomposer->decompose(signal, ctx);
  }
  py::dict params;
  for (const auto& [k, v] : values.all()) params[py::str(k)] = to_python(v);
  return {plugin, columns_to_numpy(std::move(d.imfs)), to_numpy(std::move(d.residue)), params,
          to_python(ctx.diagnostics)};
}

struct SampleEntropyResult {
  sampen::Result result;
  double r = 0.0;
};

const char* status_name(sampen::Status status) {
  switch (status) {
    case sampen::Status::Finite:
      return "finite";
    case sampen::Status::NoMatches:
      return "no_matches";
    case sampen::Status::Undefined:
      return "undefined";
  }
  return "undefined";
}

// m and r checked against the classifier's declarations (its ParamSpecs), the one place they are stated.
void check_param(const char* key, const ParamValue& value) {
  const ParamSpec* spec = registry().info(kSampleEntropy).params.find(key);
  if (const auto problem = spec->check(value); !problem.empty()) throw ConfigError({"", 0, key}, problem);
}

SampleEntropyResult sample_entropy(const InputArray& x, std::int64_t m, double r) {
  check_param("m", m);
  check_param("r", r);
  const auto samples = vector_view(x, "x");
  const std::span<const double> view(samples.data(), static_cast<std::size_t>(samples.size()));
  py::gil_scoped_release release;
  try {
    return {sampen::sample_entropy_relative(view, static_cast<int>(m), r), r};
  } catch (const std::invalid_argument& e) {  // an empty record: no standard deviation
    throw DataError({"", 0, "x"}, e.what());
  }
}

}  // namespace

void bind_plugins(py::module_& m) {
  m.def(
      "plugins",
      [](const std::string& kind) {
        std::vector<std::string> names;
        for (const auto* info : registry().list(kind)) names.push_back(info->name);
        return names;
      },
      py::arg("kind") = "", "Names of the registered plugins (\"kind/name\"), of one kind when given.");
  m.def("plugin_info", &plugin_info, py::arg("name"),
        "A plugin's summary, reference and parameter table (one dict per parameter: key, type, default, unit, "
        "constraint, doc), as `driftlab plugins describe` prints it.");

  py::class_<DecompositionResult>(m, "Decomposition",
                                  "IMFs (or modes) and residue of a signal: x = imfs.sum(axis=0) + residue.")
      .def_readonly("plugin", &DecompositionResult::plugin, "the decomposition plugin that ran")
      .def_readonly("imfs", &DecompositionResult::imfs,
                    "shape (K, N): one IMF per row, highest frequency first, in the unit of x")
      .def_readonly("residue", &DecompositionResult::residue, "shape (N,): x minus the IMFs, in the unit of x")
      .def_readonly("params", &DecompositionResult::params, "every parameter the plugin ran with, defaults included")
      .def_readonly("diagnostics", &DecompositionResult::diagnostics,
                    "what the plugin reports: sifts per IMF and orthogonality index (EMD family), iterations, "
                    "convergence and centre frequencies (VMD; in Hz when fs_hz was given)")
      .def("__repr__", [](const DecompositionResult& d) {
        return "<driftlab.Decomposition " + d.plugin + ": " + std::to_string(d.imfs.shape(0)) + " IMFs of " +
               std::to_string(d.residue.shape(0)) + " samples>";
      });
  m.def("decompose", &decompose, py::arg("plugin"), py::arg("x"), py::arg("params"), py::arg("threads"),
        py::arg("fs_hz"),
        "Runs a decomposition plugin on x with keyword parameters `params` (validated against its table). "
        "Use driftlab.emd, eemd, ceemdan, vmd or driftlab.decompose, which document the parameters.");

  py::class_<SampleEntropyResult>(m, "SampleEntropy",
                                  "SampEn(m, r) = -ln(A / B) with its pair counts (Richman & Moorman 2000, "
                                  "PhysioNet sampen.c counting)")
      .def_property_readonly(
          "value", [](const SampleEntropyResult& s) { return s.result.value; },
          "-ln(A / B); inf when A = 0 or B = 0 (see status)")
      .def_property_readonly(
          "a", [](const SampleEntropyResult& s) { return s.result.a; },
          "A: template pairs i < j matching over m + 1 samples")
      .def_property_readonly(
          "b", [](const SampleEntropyResult& s) { return s.result.b; },
          "B: template pairs i < j matching over m samples")
      .def_property_readonly(
          "n", [](const SampleEntropyResult& s) { return s.result.n; }, "number of samples")
      .def_property_readonly(
          "m", [](const SampleEntropyResult& s) { return s.result.m; }, "template length")
      .def_readonly("r", &SampleEntropyResult::r, "tolerance as a multiple of the population standard deviation")
      .def_property_readonly(
          "tolerance", [](const SampleEntropyResult& s) { return s.result.tolerance; },
          "absolute tolerance r x SD, in the unit of x")
      .def_property_readonly(
          "status", [](const SampleEntropyResult& s) { return status_name(s.result.status); },
          "'finite'; 'no_matches' (A = 0 < B); 'undefined' (B = 0)")
      .def("__repr__", [](const SampleEntropyResult& s) {
        return "<driftlab.SampleEntropy " + std::to_string(s.result.value) + " (A = " + std::to_string(s.result.a) +
               ", B = " + std::to_string(s.result.b) + ", m = " + std::to_string(s.result.m) + ")>";
      });
  m.def("sample_entropy", &sample_entropy, py::arg("x"), py::arg("m"), py::arg("r"),
        "SampEn(m, r) of x (use driftlab.sample_entropy, which documents it and has the defaults).");
}

}  // namespace driftlab::python
