// `driftlab fleet`: calibrates every unit of a manifest (read_manifest below) with the calibrate
// code path (models/calibration/imu_channels.hpp), one unit per work item of a worker pool, each unit's results
// written atomically into OUT/units/<id>/, then the fleet report (fleet_report.hpp).
// `--shard i/N` runs every N-th unit and no report (one task of a scheduler job array);
// `driftlab fleet merge` writes the report from the unit folders once every shard has run.
// Started by mpirun as several ranks, the units are dealt over the ranks instead (fleet_mpi.hpp).
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "devices/yaml_fields.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "framework/parallel.hpp"
#include "framework/regular_file.hpp"
#include "models/calibration/exports.hpp"
#include "framework/time_series.hpp"
#include "framework/units.hpp"
#include "models/discrepancy/discrepancy.hpp"
#include "tools/driftlab/calibration_cli.hpp"
#include "models/discrepancy/report.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/fleet_mpi.hpp"
#include "tools/driftlab/fleet_report.hpp"
#include "tools/driftlab/version.hpp"

namespace driftlab::cli {
namespace {

namespace fs = std::filesystem;

struct FleetOptions {
  std::string manifest, out;
  unsigned workers = 1;
  std::string model = "physical";
  std::string extrapolation = "clamp";
  CalibrationDataOptions data;  // --column, --channels, --axis, --fs, --max-gap, log selection
  bool strict = false, force = false;
  std::string shard;                   // "i/N": only the manifest's units i, i + N, ... (1-based i); no report
  bool discrepancy = false;            // --discrepancy: the discrepancy check of every gyro channel
  bool timings = false;                // --timings: each unit's stage times on its console line
  const Registry* registry = nullptr;  // its candidate effects (every effect/* plugin)
};

// One manifest row: the unit, its records (relative paths are relative to the manifest's folder)
// and its spec limits.
struct ManifestUnit {
  std::string id;
  std::vector<std::string> data;
  std::vector<std::string> columns;  // the unit's own --column mappings, used after the fleet's
  std::vector<SpecLimit> limits;
};

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(text);
  while (std::getline(in, cell, sep)) out.push_back(cell);
  if (!text.empty() && text.back() == sep) out.emplace_back();
  return out;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  const auto e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

bool valid_unit_id(const std::string& id) {
  if (id.empty() || id == "." || id == ".." || id.size() > 128) return false;
  for (char c : id)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') return false;
  return true;
}

// A manifest's unit id: a valid folder name, not seen before (ConfigError at `where` otherwise).
void check_unit_id(const std::string& id, std::set<std::string>& seen, const Location& where) {
  if (!valid_unit_id(id))
    throw ConfigError(where, "unit id '" + id + "' must be 1-128 characters of A-Z a-z 0-9 _ - . (it names a folder)");
  if (!seen.insert(id).second) throw ConfigError(where, "unit '" + id + "' appears twice");
}

// A unit's column mapping, checked as --column is (ConfigError at `where`, naming the mapping).
void add_column(ManifestUnit& u, const std::string& mapping, const Location& where) {
  try {
    parse_column_mapping(mapping);
  } catch (const Error& e) {
    throw ConfigError(where, "unit '" + u.id + "': column mapping '" + mapping + "': " + e.what());
  }
  u.columns.push_back(mapping);
}

// A record path of a unit, relative to the manifest's folder unless absolute; blank ones skipped.
void add_record(ManifestUnit& u, const std::string& path, const fs::path& base) {
  if (path.empty()) return;
  u.data.push_back(fs::path(path).is_absolute() ? path : (base / path).string());
}

// Manifest CSV: a header with `unit` and `data`, optionally `columns`, and any spec-limit columns
// ("<channels>.<figure key>_max", fleet_report.hpp); one row per unit; `data` holds one or more
// record paths separated by ';', `columns` the unit's column mappings (as --column, e.g.
// `gyro_x=gx:deg/s;temperature=T:degC`) separated by ';'. Blank lines and lines starting with '#'
// are skipped. No quoting.
std::vector<ManifestUnit> read_manifest_csv(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError({path.string(), 0, ""}, "cannot open the manifest");
  const fs::path base = path.parent_path();
  std::string line;
  int number = 0;
  std::vector<std::string> header;
  int unit_col = -1, data_col = -1, columns_col = -1;
  std::vector<std::pair<int, SpecLimit>> limit_cols;
  std::vector<ManifestUnit> units;
  std::set<std::string> seen;
  while (std::getline(in, line)) {
    ++number;
    if (trim(line).empty() || trim(line)[0] == '#') continue;
    auto cells = split(line, ',');
    for (auto& c : cells) c = trim(c);
    if (header.empty()) {
      header = cells;
      for (int c = 0; c < static_cast<int>(header.size()); ++c) {
        if (header[c] == "unit")
          unit_col = c;
        else if (header[c] == "data")
          data_col = c;
        else if (header[c] == "columns")
          columns_col = c;
        else
          limit_cols.emplace_back(c, parse_spec_column(header[c], {path.string(), number, header[c]}));
      }
      if (unit_col < 0 || data_col < 0)
        throw ConfigError({path.string(), number, unit_col < 0 ? "unit" : "data"},
                          "the manifest header needs the columns unit and data");
      continue;
    }
    if (cells.size() != header.size())
      throw ConfigError({path.string(), number, ""}, "row has " + std::to_string(cells.size()) + " cells, the header " +
                                                         std::to_string(header.size()));
    ManifestUnit u;
    u.id = cells[unit_col];
    check_unit_id(u.id, seen, {path.string(), number, "unit"});
    for (const auto& p : split(cells[data_col], ';')) add_record(u, trim(p), base);
    if (u.data.empty()) throw ConfigError({path.string(), number, "data"}, "unit '" + u.id + "' has no record");
    if (columns_col >= 0)
      for (const auto& m : split(cells[columns_col], ';'))
        if (!trim(m).empty()) add_column(u, trim(m), {path.string(), number, "columns"});
    for (const auto& [c, limit] : limit_cols) {
      if (cells[c].empty()) continue;
      SpecLimit l = limit;
      char* end = nullptr;
      l.max = std::strtod(cells[c].c_str(), &end);
      if (end == cells[c].c_str() || *end != '\0' || !std::isfinite(l.max) || l.max < 0)
        throw ConfigError({path.string(), number, header[c]}, "'" + cells[c] + "' is no finite limit >= 0");
      u.limits.push_back(std::move(l));
    }
    units.push_back(std::move(u));
  }
  if (units.empty()) throw ConfigError({path.string(), number, ""}, "the manifest lists no unit");
  return units;
}

// Manifest YAML, the CSV's content:
//   units:
//     - unit: unit001
//       data: unit001.csv            # or a list: [run1.csv, run2.csv]
//       columns: [gyro_x=gx:deg/s]   # optional, the unit's column mappings (as --column)
//       limits: {gyro.holdout_dph_max: 30, accel.a1_mg_per_k_max: 0.5}   # optional, as the CSV's columns
// Every problem is collected and reported with file, line and key path (units[3].limits.gyro.x_max).
std::vector<ManifestUnit> read_manifest_yaml(const fs::path& path) {
  const YAML::Node root = load_yaml_file(path, "fleet manifest");
  std::vector<Diagnostic> problems;
  devices::YamlFields f(path.string(), problems);
  const fs::path base = path.parent_path();
  std::vector<ManifestUnit> units;
  std::set<std::string> seen;
  if (f.map(root, "", {"units"})) {
    const YAML::Node list = f.child(root, "", "units", true);
    if (list && !list.IsSequence()) f.problem(list, "units", "expected a list of units (- unit: ID, data: FILE)");
    for (std::size_t i = 0; list && list.IsSequence() && i < list.size(); ++i) {
      const YAML::Node node = list[i];
      const std::string at = "units[" + std::to_string(i) + "]";
      if (!f.map(node, at, {"unit", "data", "columns", "limits"})) continue;
      ManifestUnit u;
      if (const auto id = f.text(node, at, "unit", true)) {
        u.id = *id;
        try {
          check_unit_id(u.id, seen, {path.string(), devices::YamlFields::line_of(node["unit"]), at + ".unit"});
        } catch (const ConfigError& e) {
          for (const auto& p : e.problems()) problems.push_back(p);
        }
      }
      const YAML::Node data = f.child(node, at, "data", true);
      if (data && data.IsScalar()) {
        add_record(u, data.as<std::string>(), base);
      } else if (data && data.IsSequence()) {
        for (const auto& d : data) {
          if (d.IsScalar())
            add_record(u, d.as<std::string>(), base);
          else
            f.problem(d, at + ".data", "expected a record path");
        }
      }
      if (data && u.data.empty()) f.problem(data, at + ".data", "expected a record path or a list of them");
      const YAML::Node columns = f.child(node, at, "columns", false);
      const auto add = [&](const YAML::Node& c) {
        try {
          add_column(u, c.as<std::string>(), {path.string(), devices::YamlFields::line_of(c), at + ".columns"});
        } catch (const ConfigError& e) {
          for (const auto& p : e.problems()) problems.push_back(p);
        }
      };
      if (columns && columns.IsScalar()) {
        add(columns);
      } else if (columns && columns.IsSequence()) {
        for (const auto& c : columns) {
          if (c.IsScalar())
            add(c);
          else
            f.problem(c, at + ".columns", "expected a column mapping ROLE=COLUMN:UNIT");
        }
      } else if (columns) {
        f.problem(columns, at + ".columns", "expected a column mapping or a list of them");
      }
      const YAML::Node limits = f.child(node, at, "limits", false);
      if (limits && !limits.IsMap()) f.problem(limits, at + ".limits", "expected a map <channels>.<figure>_max: limit");
      for (auto it = limits && limits.IsMap() ? limits.begin() : YAML::const_iterator();
           limits && limits.IsMap() && it != limits.end(); ++it) {
        const std::string key = it->first.as<std::string>();
        const std::string where = at + ".limits." + key;
        try {
          SpecLimit l = parse_spec_column(key, {path.string(), devices::YamlFields::line_of(it->first), where});
          if (const auto max = f.number(limits, at + ".limits", key, true, devices::Bounds::non_negative())) {
            l.max = *max;
            u.limits.push_back(std::move(l));
          }
        } catch (const ConfigError& e) {
          for (const auto& p : e.problems()) problems.push_back(p);
        }
      }
      units.push_back(std::move(u));
    }
  }
  if (problems.empty() && units.empty())
    problems.push_back({{path.string(), 1, "units"}, "the manifest lists no unit"});
  if (!problems.empty()) throw ConfigError(std::move(problems));
  return units;
}

// A manifest by its extension: .yaml / .yml as YAML, anything else as CSV.
std::vector<ManifestUnit> read_manifest(const fs::path& path) {
  const auto ext = path.extension().string();
  return ext == ".yaml" || ext == ".yml" ? read_manifest_yaml(path) : read_manifest_csv(path);
}

// FNV-1a, 64 bit: the fingerprint of a unit's inputs and options (not a security hash).
struct Fnv1a {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  void add(std::string_view bytes) {
    for (unsigned char c : bytes) h = (h ^ c) * 0x100000001b3ULL;
  }
  std::string hex() const {
    char text[20];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
    return text;
  }
};

// What a unit's results depend on: the driftlab version, every option that reaches the fit, and
// each record's path and bytes (a missing record hashes as missing).
std::string input_hash(const ManifestUnit& u, const FleetOptions& o) {
  Fnv1a f;
  std::ostringstream opts;
  opts.precision(17);
  opts << "driftlab-fleet-unit/2 " << kVersion << "\nmodel " << o.model << "\nextrapolation " << o.extrapolation
       << "\nstrict " << o.strict << "\nforce " << o.force << "\ndiscrepancy " << o.discrepancy << "\nchannels "
       << o.data.channels << "\naxis " << o.data.axis << "\nfs " << o.data.sample_rate_hz << "\nmax_gap "
       << o.data.max_gap_factor << "\ntopic " << o.data.log.topic << "\ninstance " << o.data.log.instance << "\nsensor "
       << o.data.log.sensor << "\n";
  for (const auto& c : o.data.columns) opts << "column " << c << "\n";
  for (const auto& c : u.columns) opts << "unit column " << c << "\n";
  f.add(opts.str());
  std::vector<char> buffer(1 << 20);
  for (const auto& p : u.data) {
    f.add("record " + p + "\n");
    std::ifstream in(p, std::ios::binary);
    if (!in) {
      f.add("missing\n");
      continue;
    }
    while (in.read(buffer.data(), static_cast<std::streamsize>(buffer.size())) || in.gcount() > 0)
      f.add(std::string_view(buffer.data(), static_cast<std::size_t>(in.gcount())));
  }
  return f.hex();
}

// The input hash of the unit's last finished run; empty when it has none (or no readable status).
std::string recorded_hash(const fs::path& status_json) {
  std::ifstream in(status_json);
  if (!in) return "";
  try {
    nlohmann::json j;
    in >> j;
    return unit_status_from_json(j).input_hash;
  } catch (const nlohmann::json::exception&) {
    return "";
  }
}

// The discrepancy check of one gyro channel (`driftlab discrepancy` without a device file, every
// effect/* plugin a candidate, default options) on the unit's first record: what it names, in
// status.json's words.
DiscrepancyCheck discrepancy_check(const ChannelRecords& ch, const Registry& registry) {
  const calibration::Record& r = ch.records.front();
  TimeSeries record(r.time_s);
  record.set_channel({role::kRate, "rad/s", ch.column, r.rate_rad_s});
  record.set_channel({role::kTemperature, "degC", ch.temperature_column, r.temp_c});
  if (r.true_rate_rad_s.size() == r.time_s.size())
    record.set_channel({role::kTrueRate, "rad/s", "", r.true_rate_rad_s});
  const auto candidates = discrepancy::make_candidates(registry, {}, {}, false);
  const auto result = discrepancy::find_missing_effects(record, candidates.candidates, {});
  DiscrepancyCheck check;
  std::string text;
  for (const auto& step : result.steps) {
    check.named.push_back({step.effect, step.delta_bic});
    char bic[32];
    std::snprintf(bic, sizeof bic, "%.4g", step.delta_bic);
    text += (text.empty() ? "" : ", ") + step.effect + " named, delta BIC " + bic;
  }
  if (result.unexplained.found) text += (text.empty() ? "" : "; ") + std::string("unexplained structure remains");
  check.unexplained = result.unexplained.found;
  check.gap_initial_dph = result.gap_initial_rad_s * kDphPerRadPerSec;
  check.gap_final_dph = result.gap_final_rad_s * kDphPerRadPerSec;
  check.text = ch.id.role() + ": " + (text.empty() ? std::string("nothing significant missing") : text);
  return check;
}

// Runs one unit: the calibrate path (records, quality gate, fit of every channel, held-out check),
// the exports, and its status; a failure is recorded, never thrown. Returns the console line.
std::string run_unit(const ManifestUnit& u, const FleetOptions& o, const fs::path& dir) {
  const std::string hash = input_hash(u, o);
  if (recorded_hash(dir / "status.json") == hash) return u.id + ": skipped (finished with the same inputs and options)";
  // The unit is unfinished while it runs: an earlier status (other inputs or options) goes now, so
  // neither a rerun nor the report can take it for this run's.
  std::error_code stale;
  if (non_regular_kind(dir / "status.json").empty()) fs::remove(dir / "status.json", stale);
  UnitStatus status;
  status.unit = u.id;
  status.input_hash = hash;
  status.data = u.data;
  calibration::ImuCalibration model;
  std::vector<calibration::ExportResult> exports;
  // Wall time per stage (--timings), on the console only: the unit's files do not depend on it.
  std::vector<std::pair<const char*, double>> stages;
  auto clock = std::chrono::steady_clock::now();
  const auto lap = [&](const char* stage) {
    const auto now = std::chrono::steady_clock::now();
    stages.emplace_back(stage, std::chrono::duration<double>(now - clock).count());
    clock = now;
  };
  auto fail = [&](int exit_class, const std::string& reason) {
    status.status = "failed";
    status.exit_class = exit_class;
    status.reason = reason;
  };
  try {
    CalibrationDataOptions data = o.data;
    data.columns.insert(data.columns.end(), u.columns.begin(), u.columns.end());
    const auto channels = load_channel_records(u.data, data);
    lap("read");
    for (const auto& f : run_quality_gate(channels, calibration::FitOptions{}.bin_s, o.strict, nullptr))
      status.quality_gate.push_back({calibration::to_string(f.severity), f.code, f.message});
    lap("gate");
    calibration::FitOptions fit;
    fit.kind = model_kind_option(o.model);
    fit.extrapolation = extrapolation_option(o.extrapolation);
    model.device = u.id;
    for (const auto& ch : channels) model.channels.push_back(fit_channel(ch, ch.records, fit));
    model.validate();
    if (!o.force) check_holdout_error(model);
    lap("fit");
    exports = {calibration::export_px4_params(model), calibration::export_ardupilot_params(model)};
    for (const auto& ch : model.channels) {
      status.figures[ch.id.role()] = channel_figures(ch);
      status.bias_curves[ch.id.role()] = bias_curve(ch);
    }
    for (const auto& ch : channels) {
      Eigen::Index n = 0;
      for (const auto& r : ch.records) n += r.rate_rad_s.size();
      Eigen::VectorXd raw(n);
      n = 0;
      for (const auto& r : ch.records) raw.segment(n, r.rate_rad_s.size()) = r.rate_rad_s, n += r.rate_rad_s.size();
      const Quantisation q = quantisation_check(raw);
      const double display = imu::display_unit(ch.id.sensor).per_internal;
      status.quantisation[ch.id.role()] = {q.lsb * display, q.share, q.sample_sigma * display, q.quantised};
    }
    lap("figures");
    if (o.discrepancy)
      for (const auto& ch : channels)
        if (ch.id.sensor == imu::Sensor::Gyro) status.discrepancy[ch.id.role()] = discrepancy_check(ch, *o.registry);
    lap("discrepancy");
    status.status = "passed";
    status.exit_class = 0;
    status.reason = "";
  } catch (const ConfigError& e) {
    fail(kExitUsage, e.what());
  } catch (const DataError& e) {
    fail(kExitData, e.what());
  } catch (const std::exception& e) {
    fail(kExitFailure, e.what());
  }
  for (const auto& e : exports)
    for (const auto& n : e.notes) status.export_notes.push_back(n);

  // The unit's folder holds exactly these files of its last run (a failed run retires an earlier
  // model and exports); a killed run's hidden temporaries are cleared first (the folder is the
  // unit's alone).
  OutputSet files({u.data.begin(), u.data.end()});
  files.make_directory(dir, "--out");
  const bool passed = status.status == "passed";
  const std::pair<const char*, std::string> products[] = {
      {"model.json", passed ? calibration::to_json_text(model) : ""},
      {"px4.params", passed ? exports[0].text : ""},
      {"ardupilot.params", passed ? exports[1].text : ""}};
  for (const auto& [name, text] : products) {
    OutputSet::remove_stale_temporaries(dir / name);
    if (!passed) {
      files.retire(dir / name, name);
      continue;
    }
    files.plan(dir / name, name);
    files.write(dir / name, text);
  }
  OutputSet::remove_stale_temporaries(dir / "status.json");
  files.plan(dir / "status.json", "status.json");  // last: a unit is finished once it is in place
  files.write(dir / "status.json", to_json(status).dump(2) + "\n");
  files.commit();
  lap("exports");
  std::string times;
  if (o.timings) {
    for (const auto& [stage, seconds] : stages) {
      char t[48];
      std::snprintf(t, sizeof t, "%s%s %.3f s", times.empty() ? " [" : ", ", stage, seconds);
      times += t;
    }
    times += "]";
  }
  return (passed ? u.id + ": passed (" + std::to_string(model.channels.size()) + " channels)"
                 : u.id + ": failed (exit class " + std::to_string(status.exit_class) + "): " + status.reason) +
         times;
}

// The fleet report from the units' status files (fleet_report.hpp), its summary on stdout; throws
// Error (exit 1) when a unit failed or is outside spec.
void report_command(const std::vector<ManifestUnit>& units, const FleetOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path out(o.out);
  OutputSet report_files({o.manifest});
  for (const char* name : {"report.json", "units.csv", "report.html"}) report_files.plan(out / name, "--out");
  std::vector<UnitSummary> summaries;
  for (const auto& u : units) {
    const fs::path status = out / "units" / u.id / "status.json";
    if (!fs::exists(status))
      throw DataError({status.string(), 0, u.id}, "unit " + u.id + " has not run (no status): run its shard first");
    summaries.push_back(read_unit_summary(status));
    summaries.back().limits = u.limits;
  }
  const auto outliers = find_outliers(summaries);
  const auto families = find_families(summaries);
  write_fleet_report(summaries, outliers, families, out,
                     "driftlab fleet --manifest " + o.manifest + " --model " + o.model, report_files);
  report_files.commit();

  std::size_t failed = 0, outside = 0;
  for (const auto& s : summaries) {
    failed += s.status != "passed";
    outside += s.status == "passed" && !spec_violations(s).empty();
  }
  for (const auto& x : outliers) std::cout << "outlier " << x.unit << ": " << x.text << "\n";
  std::cout << "families: " << families.k << (families.k == 1 ? " (no split supported)" : "") << "\n";
  if (o.timings)
    std::cout << "report: " << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
              << " s\n";
  std::cout << units.size() << " units: " << units.size() - failed << " calibrated, " << failed << " failed, "
            << outside << " outside spec; wrote " << (out / "report.json").string() << ", units.csv, report.html\n";
  if (failed + outside > 0)
    throw Error(std::to_string(failed) + " of " + std::to_string(units.size()) + " units failed and " +
                std::to_string(outside) + " are outside spec (see " + (out / "report.json").string() + ")");
}

// "i/N" (1 <= i <= N) -> {i - 1, N}; ConfigError naming --shard otherwise.
std::pair<std::size_t, std::size_t> parse_shard(const std::string& text) {
  unsigned long i = 0, n = 0;
  char extra = 0;
  if (std::sscanf(text.c_str(), "%lu/%lu%c", &i, &n, &extra) != 2 || i < 1 || n < 1 || i > n)
    throw ConfigError({"", 0, "--shard"}, "expected i/N with 1 <= i <= N (e.g. 2/8), got '" + text + "'");
  return {i - 1, n};
}

// Progress (CommandEnv::progress) is reported per finished unit, on threads or MPI rank 0 alike.
void fleet_command(const FleetOptions& o, CommandEnv& env) {
  if (o.manifest.empty() || o.out.empty())
    throw ConfigError({"", 0, o.manifest.empty() ? "--manifest" : "--out"},
                      "driftlab fleet needs --manifest and --out");
  const auto units = read_manifest(o.manifest);
  const fs::path out(o.out);
  // The directory stays when a unit fails: units are written (and resumed) one by one.
  {
    OutputSet directory;
    directory.make_directory(out / "units", "--out");
    directory.commit();
  }
  // A shard runs the units i, i + N, i + 2N, ... of the manifest (0-based i), and no report.
  const auto [first, step] = o.shard.empty() ? std::pair<std::size_t, std::size_t>{0, 1} : parse_shard(o.shard);
  std::vector<std::size_t> mine;
  for (std::size_t i = first; i < units.size(); i += step) mine.push_back(i);

  const auto run = [&](std::size_t k) { return run_unit(units[mine[k]], o, out / "units" / units[mine[k]].id); };
  // The units' lines and the progress, from the threads or from MPI rank 0 as results arrive.
  std::mutex console;
  const std::string label = "fleet: " + std::to_string(mine.size()) + " units";
  std::size_t done = 0;
  const auto started = [&] {
    if (!mine.empty()) env.progress(label, 0.0);
  };
  const auto finished = [&](const std::string& line) {
    const std::lock_guard<std::mutex> lock(console);
    std::cout << line << "\n" << std::flush;
    env.progress(label, static_cast<double>(++done) / static_cast<double>(mine.size()));
  };
  if (const auto master = run_over_mpi(mine.size(), run, started, finished)) {
    if (!*master) return;  // an MPI worker rank: rank 0 writes the report
  } else {
    started();
    parallel_for(mine.size(), o.workers, [&](std::size_t k) { finished(run(k)); });
  }
  if (o.shard.empty()) return report_command(units, o);
  std::size_t failed = 0;
  for (const std::size_t i : mine)
    failed += read_unit_summary(out / "units" / units[i].id / "status.json").status != "passed";
  std::cout << "shard " << o.shard << ": " << mine.size() << " units, " << failed
            << " failed; `driftlab fleet merge` writes the report once every shard has run\n";
  if (failed > 0)
    throw Error(std::to_string(failed) + " of the shard's " + std::to_string(mine.size()) + " units failed");
}

}  // namespace

void add_fleet_command(CLI::App& app, CommandEnv& env) {
  auto o = std::make_shared<FleetOptions>();
  auto* cmd = app.add_subcommand(
      "fleet",
      "calibrate every unit of a manifest (as calibrate does), each into OUT/units/<id>/, resumable, then a "
      "fleet report with outliers and spec yield; exit 1 when a unit failed or is outside spec");
  cmd->add_option("--manifest", o->manifest,
                  "CSV: unit,data[,columns][,<channels>.<figure>_max ...]; data = record paths separated by ';' "
                  "(relative to the manifest), columns = the unit's --column mappings separated by ';'; or YAML "
                  "(.yaml/.yml): units: [{unit, data: path or list, columns: [mapping, ...], limits: {<channels>."
                  "<figure>_max: value}}]");
  cmd->add_option("--out", o->out, "output directory (units/<id>/, report.json, units.csv, report.html)");
  cmd->add_option("--workers", o->workers, "units calibrated at once (results do not depend on it)")
      ->check(CLI::Range(1u, 256u))
      ->capture_default_str();
  cmd->add_option("--model", o->model, "as calibrate --model")
      ->check(CLI::IsMember({"poly", "physical", "rbf"}))
      ->capture_default_str();
  cmd->add_option("--extrapolation", o->extrapolation, "as calibrate --extrapolation")
      ->check(CLI::IsMember({"clamp", "linear", "evaluate"}))
      ->capture_default_str();
  cmd->add_flag("--strict", o->strict, "as calibrate --strict: quality-gate warnings fail the unit");
  cmd->add_flag("--force", o->force, "as calibrate --force: keep a model whose held-out error exceeds the raw one");
  cmd->add_option("--shard", o->shard,
                  "i/N: calibrate only the manifest's units i, i + N, ... (a scheduler job array's task), without "
                  "the report; `driftlab fleet merge` writes it");
  cmd->add_flag("--timings", o->timings,
                "print each unit's wall time per stage (read, gate, fit, figures, discrepancy, exports) on its line, "
                "and the report's");
  cmd->add_flag("--discrepancy", o->discrepancy,
                "also run the discrepancy check (as `driftlab discrepancy` without a device file) on every gyro "
                "channel and record the effects it names");
  add_calibration_channel_options(cmd, o->data);
  auto m = std::make_shared<FleetOptions>();
  auto* merge = cmd->add_subcommand(
      "merge", "write the fleet report (report.json, units.csv, report.html) from the unit folders the shards wrote");
  merge->add_option("--manifest", m->manifest, "the manifest the shards ran")->required();
  merge->add_option("--out", m->out, "the shards' output directory")->required();
  merge->add_option("--model", m->model, "as the shards' --model (named in the report)")
      ->check(CLI::IsMember({"poly", "physical", "rbf"}))
      ->capture_default_str();
  merge->callback([m] { report_command(read_manifest(m->manifest), *m); });
  cmd->require_subcommand(0, 1);
  cmd->callback([o, merge, &env] {
    o->registry = &env.registry();
    if (!merge->parsed()) fleet_command(*o, env);
  });
}

}  // namespace driftlab::cli
