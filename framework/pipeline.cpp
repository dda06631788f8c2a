#include "framework/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <regex>
#include <set>

#include "framework/error.hpp"
#include "framework/parallel.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "framework/regular_file.hpp"
#include "framework/yaml_io.hpp"

namespace driftlab {
namespace {

int line_of(const YAML::Node& node) { return yaml_line(node); }

// Output names become CSV columns (name + unit suffix) that driftlab must read back: identifiers,
// and none that would read back as the record's own channels.
const std::set<std::string>& reserved_output_names() {
  static const std::set<std::string> names{"t",           "time",           "rate",     "true_rate",
                                           "temperature", "temp",           "die_temp", "die_temperature",
                                           "drive_freq",  "drive_frequency"};
  return names;
}

struct RawStep {
  PipelineStep step;
  std::vector<std::pair<std::string, int>> refs;  // (reference, line), every input
};

std::int64_t derived_seed(std::int64_t pipeline_seed, const std::string& step_name) {
  std::uint64_t h = 1469598103934665603ull ^ static_cast<std::uint64_t>(pipeline_seed);
  for (unsigned char c : step_name) h = (h ^ c) * 1099511628211ull;
  h ^= h >> 33;
  return static_cast<std::int64_t>(h & 0x7fffffffull);
}

class Parser {
 public:
  Parser(const Registry& registry, std::string file, std::vector<Diagnostic> problems = {})
      : registry_(registry), file_(std::move(file)), problems_(std::move(problems)) {}

  Pipeline parse(const YAML::Node& root) {
    Pipeline p;
    p.file = file_;
    if (!root.IsMap()) {
      problem(root, "", "expected a map with format, inputs, steps and outputs");
      finish();
    }
    for (const auto& kv : root) {
      const auto key = scalar_text(kv.first).value_or("?");
      if (key != "format" && key != "seed" && key != "inputs" && key != "steps" && key != "outputs" &&
          key != "stages" && key != "reference")
        problem(kv.first, key, "unknown key (expected format, seed, inputs, steps, outputs, stages, reference)");
    }
    const auto format = root["format"];
    if (!format)
      problem(root, "format", std::string("missing (expected ") + kPipelineFormat + ")");
    else if (!format.IsScalar() || format.Scalar() != kPipelineFormat)
      problem(format, "format",
              "unsupported format '" + (format.IsScalar() ? format.Scalar() : std::string("?")) + "' (expected " +
                  kPipelineFormat + ")");
    if (const auto seed = root["seed"]) {
      try {
        p.seed = seed.as<std::int64_t>();
        if (p.seed < 0) problem(seed, "seed", "must be >= 0");
      } catch (const YAML::Exception&) {
        problem(seed, "seed", "expected a non-negative integer");
      }
    }
    read_inputs(root["inputs"], p);
    auto raw = read_steps(root["steps"], p);
    read_outputs(root["outputs"], p);
    read_stages(root["stages"], p);
    read_reference(root["reference"], p);
    check_references(raw, p);
    order_steps(raw, p);
    finish();
    return p;
  }

 private:
  void problem(const YAML::Node& node, const std::string& key, const std::string& message) {
    problems_.push_back({{file_, line_of(node), key}, message});
  }
  void finish() {
    if (!problems_.empty()) throw ConfigError(problems_);
  }

  void read_inputs(const YAML::Node& node, Pipeline& p) {
    if (!node) {
      p.inputs = {{"rate", role::kRate}};
      return;
    }
    if (!node.IsMap()) return problem(node, "inputs", "expected a map of input name to channel role");
    for (const auto& kv : node) {
      const auto name = scalar_text(kv.first);
      if (!name) {
        problem(kv.first, "inputs", "expected an input name, got " + yaml_shape(kv.first));
        continue;
      }
      if (!kv.second.IsScalar()) {
        problem(kv.second, "inputs." + *name, "expected a channel role, got " + yaml_shape(kv.second));
        continue;
      }
      p.inputs[*name] = kv.second.Scalar();
    }
  }

  std::vector<RawStep> read_steps(const YAML::Node& node, Pipeline& p) {
    std::vector<RawStep> raw;
    if (!node || !node.IsSequence() || node.size() == 0) {
      problem(node ? node : YAML::Node(), "steps", "expected a non-empty list of steps");
      return raw;
    }
    static const std::regex name_re("[A-Za-z_][A-Za-z0-9_]*");
    std::map<std::string, int> seen;
    for (std::size_t i = 0; i < node.size(); ++i) {
      const auto s = node[i];
      const std::string where = "steps[" + std::to_string(i) + "]";
      if (!s.IsMap()) {
        problem(s, where, "expected a map with name, plugin, inputs, params");
        continue;
      }
      RawStep r;
      r.step.line = line_of(s);
      for (const auto& kv : s) {
        const auto key = scalar_text(kv.first).value_or("?");
        if (key != "name" && key != "plugin" && key != "inputs" && key != "params" && key != "sum")
          problem(kv.first, where + "." + key, "unknown key (expected name, plugin, inputs, params, or sum)");
      }
      if (!s["name"] || !s["name"].IsScalar() || !std::regex_match(s["name"].Scalar(), name_re)) {
        problem(s["name"] ? s["name"] : s, where + ".name", "expected an identifier (letters, digits, _)");
      } else {
        r.step.name = s["name"].Scalar();
        if (auto it = seen.find(r.step.name); it != seen.end())
          problem(s["name"], where + ".name",
                  "duplicate step name '" + r.step.name + "' (first used on line " + std::to_string(it->second) + ")");
        else
          seen[r.step.name] = line_of(s["name"]);
      }
      const std::string label = r.step.name.empty() ? where : r.step.name;
      if (s["sum"]) {
        read_sum(s, label, r);
      } else {
        read_plugin_step(s, label, p, r);
      }
      raw.push_back(std::move(r));
    }
    return raw;
  }

  void read_sum(const YAML::Node& s, const std::string& label, RawStep& r) {
    if (s["plugin"] || s["params"] || s["inputs"])
      problem(s, label, "a sum step takes only `name` and `sum: [references]`");
    const auto list = s["sum"];
    if (!list.IsSequence() || list.size() == 0) return problem(list, label + ".sum", "expected a list of references");
    for (const auto& ref : list) {
      if (!ref.IsScalar()) {
        problem(ref, label + ".sum", "expected a reference (input name or step.output), got " + yaml_shape(ref));
        continue;
      }
      r.step.inputs["terms"].push_back(ref.Scalar());
      r.refs.emplace_back(ref.Scalar(), line_of(ref));
    }
  }

  void read_plugin_step(const YAML::Node& s, const std::string& label, Pipeline& p, RawStep& r) {
    const auto plugin = s["plugin"];
    if (!plugin || !plugin.IsScalar()) return problem(plugin ? plugin : s, label + ".plugin", "missing plugin name");
    r.step.plugin = plugin.Scalar();
    if (!registry_.contains(r.step.plugin)) {
      try {
        registry_.info(r.step.plugin);
      } catch (const ConfigError& e) {
        problem(plugin, label + ".plugin", e.problems().front().message);
      }
      return;
    }
    const auto& info = registry_.info(r.step.plugin);
    const auto& ports = ports_of_kind(info.kind());
    if (ports.outputs.empty())
      return problem(plugin, label + ".plugin", info.kind() + " plugins cannot run as pipeline steps");
    const auto inputs = s["inputs"];
    if (inputs && !inputs.IsMap()) problem(inputs, label + ".inputs", "expected a map of port to reference");
    if (inputs && inputs.IsMap()) {
      for (const auto& kv : inputs) {
        const auto port = scalar_text(kv.first).value_or("?");
        const auto spec =
            std::find_if(ports.inputs.begin(), ports.inputs.end(), [&](const PortSpec& ps) { return ps.name == port; });
        if (spec == ports.inputs.end()) {
          std::string valid;
          for (const auto& ps : ports.inputs) valid += (valid.empty() ? "" : ", ") + ps.name;
          problem(kv.first, label + ".inputs." + port,
                  "unknown input port of a " + info.kind() + " step (valid: " + valid + ")");
          continue;
        }
        if (kv.second.IsSequence() && !spec->many)
          problem(kv.second, label + ".inputs." + port, "this port takes a single reference");
        const auto add = [&](const YAML::Node& ref) {
          if (!ref.IsScalar())
            return problem(ref, label + ".inputs." + port,
                           "expected a reference (input name or step.output), got " + yaml_shape(ref));
          r.step.inputs[port].push_back(ref.Scalar());
          r.refs.emplace_back(ref.Scalar(), line_of(ref));
        };
        if (kv.second.IsSequence())
          for (const auto& ref : kv.second) add(ref);
        else if (kv.second.IsScalar())
          add(kv.second);
        else
          problem(kv.second, label + ".inputs." + port, "expected a reference (input name or step.output)");
      }
    }
    for (const auto& ps : ports.inputs)
      if (ps.required && !r.step.inputs.count(ps.name))
        problem(inputs ? inputs : s, label + ".inputs." + ps.name, "required input port is not connected");

    const auto params = s["params"];
    r.step.params = resolve_params(registry_, r.step.plugin, params, file_, label + ".params", problems_);
    if (info.params.find("seed") && !(params && params.IsMap() && params["seed"]))
      r.step.params.set("seed", derived_seed(p.seed, r.step.name));
  }

  void read_outputs(const YAML::Node& node, Pipeline& p) {
    if (!node || !node.IsMap() || node.size() == 0)
      return problem(node ? node : YAML::Node(), "outputs", "expected a map of output name to step.output");
    static const std::regex name_re("[A-Za-z_][A-Za-z0-9_]*");
    for (const auto& kv : node) {
      const auto name = scalar_text(kv.first);
      if (!name || !std::regex_match(*name, name_re)) {
        problem(kv.first, "outputs",
                "output name " + yaml_shape(kv.first) +
                    " must be an identifier (letters, digits, _): it becomes a CSV column");
        continue;
      }
      if (reserved_output_names().count(*name)) {
        problem(kv.first, "outputs." + *name,
                "output name is reserved: its CSV column would read back as the record's own '" + *name +
                    "' channel; choose another name");
        continue;
      }
      if (!kv.second.IsScalar()) {
        problem(kv.second, "outputs." + *name, "expected a step.output reference, got " + yaml_shape(kv.second));
        continue;
      }
      if (p.outputs.emplace(*name, kv.second.Scalar()).second) p.output_order.push_back(*name);
      output_refs_.emplace_back(kv.second.Scalar(), line_of(kv.second));
    }
  }

  void read_stages(const YAML::Node& node, Pipeline& p) {
    if (!node) return;
    if (!node.IsMap() || node.size() == 0)
      return problem(node, "stages", "expected a map of output name to label, got " + yaml_shape(node));
    for (const auto& kv : node) {
      const auto name = scalar_text(kv.first);
      if (!name || !p.outputs.count(*name)) {
        problem(kv.first, "stages", "stage " + yaml_shape(kv.first) + " is not one of the pipeline's outputs");
        continue;
      }
      const auto label = scalar_text(kv.second);
      if (!label || label->empty()) {
        problem(kv.second, "stages." + *name, "expected a label (text), got " + yaml_shape(kv.second));
        continue;
      }
      p.stages.push_back({*name, *label});
    }
  }

  void read_reference(const YAML::Node& node, Pipeline& p) {
    if (!node) return;
    if (!node.IsMap())
      return problem(node, "reference", "expected a map with source and rows, got " + yaml_shape(node));
    PipelineReference ref;
    for (const auto& kv : node) {
      const auto key = scalar_text(kv.first).value_or("?");
      if (key != "source" && key != "rows" && key != "figures" && key != "record")
        problem(kv.first, "reference." + key, "unknown key (expected source, rows, figures, record)");
    }
    if (const auto record = node["record"]) {
      const std::string expected =
          "expected {sample_rate_hz: x, duration_s: y, temperature_range_c: [min, max]} (Hz, s, degC)";
      PipelineReference::Record r;
      const auto number = [&](const YAML::Node& v, const std::string& where, double& out) {
        double x = 0.0;
        if (!v || !YAML::convert<double>::decode(v, x) || !std::isfinite(x))
          return problem(v ? v : record, where, "expected a finite number");
        out = x;
      };
      if (!record.IsMap()) {
        problem(record, "reference.record", expected + ", got " + yaml_shape(record));
      } else {
        for (const auto& kv : record) {
          const auto key = scalar_text(kv.first).value_or("?");
          if (key != "sample_rate_hz" && key != "duration_s" && key != "temperature_range_c")
            problem(kv.first, "reference.record." + key, "unknown key; " + expected);
        }
        number(record["sample_rate_hz"], "reference.record.sample_rate_hz", r.sample_rate_hz);
        number(record["duration_s"], "reference.record.duration_s", r.duration_s);
        const auto range = record["temperature_range_c"];
        if (!range || !range.IsSequence() || range.size() != 2) {
          problem(range ? range : record, "reference.record.temperature_range_c", "expected [min, max] in degC");
        } else {
          number(range[0], "reference.record.temperature_range_c", r.temperature_min_c);
          number(range[1], "reference.record.temperature_range_c", r.temperature_max_c);
        }
        if (!(r.sample_rate_hz > 0.0) || !(r.duration_s > 0.0) || !(r.temperature_min_c < r.temperature_max_c))
          problem(record, "reference.record", "needs a rate > 0 Hz, a duration > 0 s and min < max degC");
        else
          ref.record = r;
      }
    }
    if (const auto figures = node["figures"]) {
      std::string known;
      for (const auto& f : kReferenceFigures) known += (known.empty() ? "" : ", ") + f;
      if (!figures.IsMap())
        problem(figures, "reference.figures",
                "expected a map of report figure (" + known +
                    ") to the publication's "
                    "figure, got " +
                    yaml_shape(figures));
      else
        for (const auto& kv : figures) {
          const auto key = scalar_text(kv.first).value_or("?");
          const auto text = scalar_text(kv.second);
          if (std::find(kReferenceFigures.begin(), kReferenceFigures.end(), key) == kReferenceFigures.end())
            problem(kv.first, "reference.figures." + key, "unknown figure (expected one of " + known + ")");
          else if (!text || text->empty())
            problem(kv.second, "reference.figures." + key, "expected the publication's figure (text, e.g. Fig. 10)");
          else
            ref.figures[key] = *text;
        }
    }
    const auto source = scalar_text(node["source"]);
    if (!source || source->empty())
      problem(node["source"] ? node["source"] : node, "reference.source", "expected the publication and table (text)");
    else
      ref.source = *source;
    const auto rows = node["rows"];
    if (!rows || !rows.IsMap() || rows.size() == 0)
      return problem(rows ? rows : node, "reference.rows",
                     "expected a map of row (original or an output) to {B_deg_h, N_deg_h_rtHz}");
    for (const auto& kv : rows) {
      const auto name = scalar_text(kv.first);
      if (!name || (*name != "original" && !p.outputs.count(*name))) {
        problem(kv.first, "reference.rows", "row " + yaml_shape(kv.first) + " is neither original nor an output");
        continue;
      }
      const std::string where = "reference.rows." + *name;
      if (!kv.second.IsMap()) {
        problem(kv.second, where, "expected {B_deg_h: x, N_deg_h_rtHz: y}, got " + yaml_shape(kv.second));
        continue;
      }
      for (const auto& field : kv.second) {
        const auto key = scalar_text(field.first).value_or("?");
        if (key != "B_deg_h" && key != "N_deg_h_rtHz")
          problem(field.first, where + "." + key, "unknown key (expected B_deg_h, N_deg_h_rtHz)");
      }
      PipelineReference::Row row;
      for (const auto& [field, value] : {std::pair{"B_deg_h", &row.b_deg_h}, {"N_deg_h_rtHz", &row.n_deg_h_rthz}}) {
        const auto v = kv.second[field];
        if (!v) {
          problem(kv.second, where + "." + field, "missing (expected a finite number > 0)");
          continue;
        }
        double number = 0.0;
        if (!YAML::convert<double>::decode(v, number) || !(std::isfinite(number) && number > 0.0))
          problem(v, where + "." + field, "expected a finite number > 0");
        else
          *value = number;
      }
      ref.rows.emplace(*name, row);
    }
    p.reference = std::move(ref);
  }

  // Output names of a step, or empty when the step is unknown.
  std::vector<std::string> outputs_of(const std::vector<RawStep>& raw, const std::string& step) const {
    for (const auto& r : raw)
      if (r.step.name == step) {
        if (r.step.plugin.empty()) return {"signal"};
        if (!registry_.contains(r.step.plugin)) return {"*"};
        return ports_of_kind(registry_.info(r.step.plugin).kind()).outputs;
      }
    return {};
  }

  void check_ref(const std::vector<RawStep>& raw, const Pipeline& p, const std::string& ref, int line,
                 const std::string& key) {
    const auto dot = ref.find('.');
    if (dot == std::string::npos) {
      if (!p.inputs.count(ref) && ref != "time") {
        std::string names = "time";
        for (const auto& [n, r] : p.inputs) names += ", " + n;
        problems_.push_back(
            {{file_, line, key},
             "dangling reference '" + ref + "': no pipeline input of that name (inputs: " + names + ")"});
      }
      return;
    }
    const auto step = ref.substr(0, dot), output = ref.substr(dot + 1);
    const auto outs = outputs_of(raw, step);
    if (outs.empty()) {
      problems_.push_back({{file_, line, key}, "dangling reference '" + ref + "': no step named '" + step + "'"});
    } else if (outs.front() != "*" && std::find(outs.begin(), outs.end(), output) == outs.end()) {
      std::string valid;
      for (const auto& o : outs) valid += (valid.empty() ? "" : ", ") + o;
      problems_.push_back(
          {{file_, line, key}, "dangling reference '" + ref + "': step '" + step + "' has outputs " + valid});
    }
  }

  void check_references(const std::vector<RawStep>& raw, const Pipeline& p) {
    for (const auto& r : raw)
      for (const auto& [ref, line] : r.refs) check_ref(raw, p, ref, line, r.step.name + ".inputs");
    for (const auto& [ref, line] : output_refs_) check_ref(raw, p, ref, line, "outputs");
  }

  void order_steps(std::vector<RawStep>& raw, Pipeline& p) {
    std::vector<bool> placed(raw.size(), false);
    std::set<std::string> done;
    while (p.steps.size() < raw.size()) {
      bool progressed = false;
      for (std::size_t i = 0; i < raw.size(); ++i) {
        if (placed[i]) continue;
        const bool ready = std::all_of(raw[i].refs.begin(), raw[i].refs.end(), [&](const auto& ref) {
          const auto dot = ref.first.find('.');
          return dot == std::string::npos || done.count(ref.first.substr(0, dot)) ||
                 outputs_of(raw, ref.first.substr(0, dot)).empty();
        });
        if (!ready) continue;
        placed[i] = true;
        done.insert(raw[i].step.name);
        p.steps.push_back(raw[i].step);
        progressed = true;
      }
      if (!progressed) {
        std::string cycle;
        for (std::size_t i = 0; i < raw.size(); ++i)
          if (!placed[i]) cycle += (cycle.empty() ? "" : ", ") + raw[i].step.name;
        for (std::size_t i = 0; i < raw.size(); ++i)
          if (!placed[i]) {
            problems_.push_back({{file_, raw[i].step.line, raw[i].step.name},
                                 "cyclic reference: steps " + cycle + " depend on each other"});
            break;
          }
        return;
      }
    }
  }

  const Registry& registry_;
  std::string file_;
  std::vector<Diagnostic> problems_;
  std::vector<std::pair<std::string, int>> output_refs_;
};

Signal side_by_side(const std::vector<const Signal*>& parts) {
  if (parts.size() == 1) return *parts.front();
  Signal s;
  Eigen::Index cols = 0;
  for (const Signal* p : parts) cols += p->columns.cols();
  s.columns.resize(parts.front()->columns.rows(), cols);
  Eigen::Index c = 0;
  for (const Signal* p : parts) {
    s.columns.middleCols(c, p->columns.cols()) = p->columns;
    c += p->columns.cols();
    s.labels.insert(s.labels.end(), p->labels.begin(), p->labels.end());
  }
  s.unit = parts.front()->unit;
  return s;
}

}  // namespace

PipelineOverride parse_pipeline_override(const std::string& text, const std::string& option) {
  static const std::regex name_re("[A-Za-z_][A-Za-z0-9_]*");
  const auto fail = [&](const std::string& why) -> PipelineOverride {
    throw ConfigError({"", 0, option + " " + quoted_excerpt(text)},
                      why + " (expected STEP.PARAM=VALUE, STEP.PARAM.NESTED_PARAM=VALUE or STEP.plugin=KIND/NAME)");
  };
  const auto eq = text.find('=');
  if (eq == std::string::npos) return fail("no '='");
  PipelineOverride o;
  o.text = text;
  o.value = text.substr(eq + 1);
  if (o.value.empty()) return fail("no value after '='");
  std::vector<std::string> names;
  for (std::size_t start = 0;;) {
    const auto dot = text.find('.', start);
    const auto end = dot == std::string::npos || dot > eq ? eq : dot;
    names.push_back(text.substr(start, end - start));
    if (!std::regex_match(names.back(), name_re))
      return fail("'" + names.back() + "' is not a step or parameter name (letters, digits, _)");
    if (end == eq) break;
    start = end + 1;
  }
  if (names.size() < 2) return fail("no parameter after the step name");
  o.step = names.front();
  o.key.assign(names.begin() + 1, names.end());
  if (o.key.front() == "plugin" && o.key.size() > 1) return fail("'plugin' has no sub-keys");
  return o;
}

namespace {

// The key path a pipeline problem names for what an override changes: "STEP.plugin", or
// "STEP.params.PARAM[.params.NESTED...]".
std::string override_field(const PipelineOverride& o) {
  if (o.key.front() == "plugin") return o.step + ".plugin";
  std::string field = o.step + ".params";
  for (std::size_t i = 0; i < o.key.size(); ++i) field += (i ? ".params." : ".") + o.key[i];
  return field;
}

// The YAML of the overrides applied to `root` (the parsed pipeline file), and their records.
class OverrideApplier {
 public:
  OverrideApplier(const Registry& registry, const std::string& file, std::vector<Diagnostic>& problems)
      : registry_(registry), file_(file), problems_(problems) {}

  // Applies swaps first, then parameter settings, each in the order given. Returns the records
  // (the text, with the parameters a swap dropped).
  std::vector<std::string> apply(YAML::Node root, const std::vector<PipelineOverride>& overrides) {
    std::vector<std::string> records;
    for (const bool swaps : {true, false})
      for (const auto& o : overrides)
        if ((o.key.front() == "plugin") == swaps) {
          if (auto record = apply_one(root.IsMap() ? root["steps"] : YAML::Node(), o)) records.push_back(*record);
        }
    return records;
  }

 private:
  void problem(const PipelineOverride& o, const std::string& field, const std::string& message) {
    problems_.push_back({{"--set " + o.text, 0, field}, message});
  }

  std::optional<std::string> apply_one(YAML::Node steps, const PipelineOverride& o) {
    std::vector<std::string> names;
    if (steps && steps.IsSequence()) {
      for (std::size_t i = 0; i < steps.size(); ++i) {
        YAML::Node step = steps[i];
        const auto name = step.IsMap() ? scalar_text(step["name"]) : std::nullopt;
        if (!name) continue;
        if (*name == o.step) return apply_to_step(step, o);
        names.push_back(*name);
      }
    }
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    problem(o, o.step, "no step '" + o.step + "' in " + file_ + " (its steps: " + (list.empty() ? "none" : list) + ")");
    return std::nullopt;
  }

  std::optional<YAML::Node> value_of(const PipelineOverride& o) {
    std::vector<Diagnostic> duplicates;
    try {
      YAML::Node value = load_yaml_checked(o.value, "--set " + o.text, &duplicates);
      if (duplicates.empty()) return value;
      problems_.insert(problems_.end(), duplicates.begin(), duplicates.end());
    } catch (const ConfigError& e) {
      problems_.insert(problems_.end(), e.problems().begin(), e.problems().end());
    }
    return std::nullopt;
  }

  std::optional<std::string> apply_to_step(YAML::Node step, const PipelineOverride& o) {
    if (step["sum"]) {
      problem(o, o.step, "step '" + o.step + "' is a sum step: it has no plugin or parameters to set");
      return std::nullopt;
    }
    const auto value = value_of(o);
    if (!value) return std::nullopt;
    const std::string plugin = scalar_text(step["plugin"]).value_or("");
    if (o.key.front() == "plugin") return swap(step, o, plugin, *value);
    if (!step["params"] || !step["params"].IsMap()) step["params"] = YAML::Node(YAML::NodeType::Map);
    if (!set_param(step["params"], plugin, o, 0, *value, o.step + ".params")) return std::nullopt;
    return o.text;
  }

  std::optional<std::string> swap(YAML::Node step, const PipelineOverride& o, const std::string& old,
                                  const YAML::Node& value) {
    const std::string kind = registry_.contains(old) ? registry_.info(old).kind() : "";
    const auto name = scalar_text(value);
    std::string known;
    for (const auto* info : registry_.list(kind)) known += (known.empty() ? "" : ", ") + info->name;
    if (!name || !registry_.contains(*name)) {
      problem(o, o.step + ".plugin",
              "expected a " + (kind.empty() ? std::string("plugin") : kind + " plugin") + " name (known: " + known +
                  "), got " + yaml_shape(value));
      return std::nullopt;
    }
    if (!kind.empty() && registry_.info(*name).kind() != kind) {
      problem(o, o.step + ".plugin",
              "expected a " + kind + " plugin (the step's " + old + " is one; known: " + known + "), got " + *name +
                  ", a " + registry_.info(*name).kind() + " plugin");
      return std::nullopt;
    }
    step["plugin"] = *name;
    std::string dropped;
    if (YAML::Node params = step["params"]; params && params.IsMap()) {
      const auto& table = registry_.info(*name).params;
      std::vector<std::string> keys;
      for (const auto& kv : params)
        if (const auto key = scalar_text(kv.first); key && !table.find(*key)) keys.push_back(*key);
      for (const auto& key : keys) {
        params.remove(key);
        dropped += (dropped.empty() ? "" : ", ") + key;
      }
    }
    return dropped.empty() ? o.text : o.text + " (dropped " + old + "'s " + dropped + ")";
  }

  // Sets o.key[depth...] in `params` (the parameter map of `plugin`); false after a problem.
  bool set_param(YAML::Node params, const std::string& plugin, const PipelineOverride& o, std::size_t depth,
                 const YAML::Node& value, const std::string& field) {
    const std::string& key = o.key[depth];
    if (depth + 1 == o.key.size()) {
      params[key] = value;  // type and range checked by the parser, as a value in the file is
      return true;
    }
    const ParamSpec* spec = registry_.contains(plugin) ? registry_.info(plugin).params.find(key) : nullptr;
    if (!spec || spec->type != ParamType::Plugin) {
      problem(o, field + "." + key,
              spec ? "parameter '" + key + "' of " + plugin + " is not a nested plugin: it has no parameters"
                   : "unknown parameter of " + plugin + " (valid: " + joined_keys(plugin) + ")");
      return false;
    }
    const YAML::Node current = params[key];
    std::string nested = std::get<std::shared_ptr<const PluginSpec>>(spec->default_value)->name;
    if (const auto text = scalar_text(current))
      nested = *text;
    else if (current && current.IsMap() && scalar_text(current["plugin"]))
      nested = *scalar_text(current["plugin"]);
    if (!current || !current.IsMap()) {
      YAML::Node expanded(YAML::NodeType::Map);
      expanded["plugin"] = nested;
      params[key] = expanded;
    }
    YAML::Node node = params[key];
    if (!node["params"] || !node["params"].IsMap()) node["params"] = YAML::Node(YAML::NodeType::Map);
    return set_param(node["params"], nested, o, depth + 1, value, field + "." + key + ".params");
  }

  std::string joined_keys(const std::string& plugin) const {
    std::string list;
    for (const auto& k : registry_.info(plugin).params.keys()) list += (list.empty() ? "" : ", ") + k;
    return list;
  }

  const Registry& registry_;
  const std::string& file_;
  std::vector<Diagnostic>& problems_;
};

// The steps `reference` ("step.port" or an input name) reads, directly or through other steps.
void upstream_steps(const Pipeline& p, const std::string& reference, std::set<std::string>& found) {
  const auto dot = reference.find('.');
  if (dot == std::string::npos) return;
  const std::string name = reference.substr(0, dot);
  if (!found.insert(name).second) return;
  for (const auto& step : p.steps)
    if (step.name == name)
      for (const auto& [port, refs] : step.inputs)
        for (const auto& ref : refs) upstream_steps(p, ref, found);
}

// Appends to each declared stage's label the overrides of the steps its output depends on.
void label_stages_with_overrides(Pipeline& p, const std::vector<PipelineOverride>& overrides) {
  for (auto& stage : p.stages) {
    std::set<std::string> upstream;
    upstream_steps(p, p.outputs.at(stage.output), upstream);
    std::string applied;
    for (const auto& o : overrides)
      if (upstream.count(o.step)) applied += (applied.empty() ? "" : ", ") + o.text;
    if (!applied.empty()) stage.label += " [" + applied + "]";
  }
}

}  // namespace

Pipeline parse_pipeline(const std::string& yaml_text, const std::string& file_label, const Registry& registry,
                        const std::vector<PipelineOverride>& overrides) {
  std::vector<Diagnostic> problems;  // repeated keys and override problems, reported with every other
  YAML::Node root = load_yaml_checked(yaml_text, file_label, &problems);
  std::vector<std::string> records;
  if (!overrides.empty()) {
    records = OverrideApplier(registry, file_label, problems).apply(root, overrides);
    if (!problems.empty() && records.size() < overrides.size()) throw ConfigError(problems);
  }
  try {
    Pipeline p = Parser(registry, file_label, std::move(problems)).parse(root);
    p.overrides = std::move(records);
    label_stages_with_overrides(p, overrides);
    return p;
  } catch (const ConfigError& e) {
    if (overrides.empty()) throw;
    // A problem with what an override set is that override's: named by it, not by the file.
    std::vector<Diagnostic> mapped = e.problems();
    for (auto& d : mapped) {
      if (d.where.file != file_label) continue;
      for (const auto& o : overrides) {
        const std::string field = override_field(o);
        if (d.where.field == field || d.where.field.rfind(field + ".", 0) == 0)
          d.where = {"--set " + o.text, 0, d.where.field};
      }
    }
    throw ConfigError(std::move(mapped));
  }
}

Pipeline load_pipeline(const std::filesystem::path& path, const Registry& registry,
                       const std::vector<PipelineOverride>& overrides) {
  return parse_pipeline(read_config_text(path, "pipeline file"), input_name(path), registry, overrides);
}

std::string effective_pipeline_yaml(const Pipeline& pipeline, const Registry& registry) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << kPipelineFormat;
  out << YAML::Key << "seed" << YAML::Value << pipeline.seed;
  out << YAML::Key << "inputs" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, role] : pipeline.inputs) out << YAML::Key << name << YAML::Value << role;
  out << YAML::EndMap;
  out << YAML::Key << "steps" << YAML::Value << YAML::BeginSeq;
  for (const auto& step : pipeline.steps) {
    out << YAML::BeginMap << YAML::Key << "name" << YAML::Value << step.name;
    if (step.plugin.empty()) {
      out << YAML::Key << "sum" << YAML::Value << YAML::Flow << step.inputs.at("terms");
    } else {
      out << YAML::Key << "plugin" << YAML::Value << step.plugin;
      out << YAML::Key << "inputs" << YAML::Value << YAML::BeginMap;
      for (const auto& [port, refs] : step.inputs) {
        out << YAML::Key << port << YAML::Value;
        if (refs.size() == 1)
          out << refs.front();
        else
          out << YAML::Flow << refs;
      }
      out << YAML::EndMap;
      out << YAML::Key << "params" << YAML::Value << params_to_yaml(registry, step.plugin, step.params);
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "outputs" << YAML::Value << YAML::BeginMap;
  for (const auto& name : pipeline.output_order) out << YAML::Key << name << YAML::Value << pipeline.outputs.at(name);
  out << YAML::EndMap;
  if (!pipeline.stages.empty()) {
    out << YAML::Key << "stages" << YAML::Value << YAML::BeginMap;
    for (const auto& stage : pipeline.stages) out << YAML::Key << stage.output << YAML::Value << stage.label;
    out << YAML::EndMap;
  }
  if (pipeline.reference) {
    out << YAML::Key << "reference" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "source" << YAML::Value << pipeline.reference->source;
    out << YAML::Key << "rows" << YAML::Value << YAML::BeginMap;
    for (const auto& [name, row] : pipeline.reference->rows)
      out << YAML::Key << name << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "B_deg_h" << YAML::Value
          << row.b_deg_h << YAML::Key << "N_deg_h_rtHz" << YAML::Value << row.n_deg_h_rthz << YAML::EndMap;
    out << YAML::EndMap;
    if (const auto& r = pipeline.reference->record) {
      out << YAML::Key << "record" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "sample_rate_hz"
          << YAML::Value << r->sample_rate_hz << YAML::Key << "duration_s" << YAML::Value << r->duration_s << YAML::Key
          << "temperature_range_c" << YAML::Value << YAML::Flow << YAML::BeginSeq << r->temperature_min_c
          << r->temperature_max_c << YAML::EndSeq << YAML::EndMap;
    }
    if (!pipeline.reference->figures.empty()) {
      out << YAML::Key << "figures" << YAML::Value << YAML::BeginMap;
      for (const auto& [figure, text] : pipeline.reference->figures) out << YAML::Key << figure << YAML::Value << text;
      out << YAML::EndMap;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

nlohmann::json StepRecord::to_json() const {
  nlohmann::json j{{"name", name}, {"plugin", plugin}, {"status", ok ? "ok" : "failed"}, {"diagnostics", diagnostics}};
  if (ok)
    j["seconds"] = seconds;
  else
    j["error"] = error;
  return j;
}

nlohmann::json steps_json(const std::vector<StepRecord>& steps) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& step : steps) j.push_back(step.to_json());
  return j;
}

std::map<std::string, Signal> run_pipeline(const Pipeline& pipeline, const Registry& registry, const TimeSeries& record,
                                           const PipelineRunOptions& options, nlohmann::json& report) {
  std::vector<StepRecord> steps;
  try {
    auto outputs = run_pipeline(pipeline, registry, record, options, steps);
    report["steps"] = steps_json(steps);
    return outputs;
  } catch (...) {
    report["steps"] = steps_json(steps);
    throw;
  }
}

std::map<std::string, Signal> run_pipeline(const Pipeline& pipeline, const Registry& registry, const TimeSeries& record,
                                           const PipelineRunOptions& options, std::vector<StepRecord>& steps) {
  std::map<std::string, Signal> inputs;
  inputs["time"] = Signal::single(record.time(), "time", "s");
  for (const auto& [name, role] : pipeline.inputs) {
    if (role == "time") {
      inputs[name] = inputs["time"];
      continue;
    }
    const auto& c = record.channel(role);
    inputs[name] = Signal::single(c.values, name, c.unit);
  }
  const std::size_t count = pipeline.steps.size();
  std::map<std::string, std::size_t> index_of;
  for (std::size_t i = 0; i < count; ++i) index_of[pipeline.steps[i].name] = i;
  std::vector<std::vector<std::size_t>> deps(count);
  for (std::size_t i = 0; i < count; ++i) {
    for (const auto& [port, refs] : pipeline.steps[i].inputs)
      for (const auto& ref : refs)
        if (const auto dot = ref.find('.'); dot != std::string::npos)
          deps[i].push_back(index_of.at(ref.substr(0, dot)));
  }
  std::vector<SignalMap> produced(count);
  const auto resolve = [&](const std::string& ref) -> const Signal& {
    const auto dot = ref.find('.');
    if (dot == std::string::npos) return inputs.at(ref);
    return produced[index_of.at(ref.substr(0, dot))].at(ref.substr(dot + 1));
  };
  const double sample_rate_hz = record.sample_rate_hz();
  std::vector<std::optional<StepRecord>> entries(count);  // empty: the step has not started
  std::mutex progress_mutex;
  const auto run_step = [&](std::size_t i) {
    const auto& step = pipeline.steps[i];
    auto& entry = entries[i].emplace();
    entry.name = step.name;
    entry.plugin = step.plugin.empty() ? "sum" : step.plugin;
    const auto start = std::chrono::steady_clock::now();
    RunContext ctx;
    ctx.threads = options.threads;
    ctx.time_s = record.time();
    ctx.sample_rate_hz = sample_rate_hz;
    ctx.seed = static_cast<std::uint64_t>(derived_seed(pipeline.seed, step.name));
    if (options.progress)
      ctx.progress = [&, i](double f) {
        const std::lock_guard<std::mutex> lock(progress_mutex);
        options.progress(i, count, step.name, f);
      };
    std::map<std::string, Signal> port_values;
    for (const auto& [port, refs] : step.inputs) {
      std::vector<const Signal*> parts;
      for (const auto& ref : refs) parts.push_back(&resolve(ref));
      port_values[port] = side_by_side(parts);
    }
    ctx.progress(0.0);
    try {
      if (step.plugin.empty()) {
        const auto& terms = port_values.at("terms");
        produced[i]["signal"] = Signal::single(terms.sum(), step.name, terms.unit);
      } else {
        auto plugin = registry.create(step.plugin, step.params);
        produced[i] = plugin->run(port_values, ctx);
      }
    } catch (const std::exception& e) {
      entry.error = e.what();
      entry.diagnostics = ctx.diagnostics;
      throw;
    }
    ctx.progress(1.0);
    entry.ok = true;
    entry.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    entry.diagnostics = ctx.diagnostics;
  };
  // The records of the steps a serial run would have reached: all of them, or those up to and
  // including the first failed one.
  const auto fill_report = [&] {
    steps.clear();
    for (const auto& entry : entries) {
      if (!entry) break;
      steps.push_back(*entry);
      if (!entry->ok) break;
    }
  };
  try {
    parallel_graph(deps, options.threads, run_step);
  } catch (...) {
    fill_report();
    throw;
  }
  fill_report();
  std::map<std::string, Signal> outputs;
  for (const auto& [name, ref] : pipeline.outputs) outputs[name] = resolve(ref);
  if (options.step_signals != nullptr)
    for (std::size_t i = 0; i < count; ++i)
      for (auto& [port, signal] : produced[i])
        (*options.step_signals)[pipeline.steps[i].name + "." + port] = std::move(signal);
  return outputs;
}

}  // namespace driftlab
