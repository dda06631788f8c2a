// `driftlab entropy`: sample entropy SampEn(m, r) of one channel, r relative to its population
// standard deviation (PhysioNet convention), with the match counts A and B and the sample count.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>
#include <span>

#include "framework/error.hpp"
#include "framework/units.hpp"
#include "plugins/sample_entropy/sample_entropy.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
namespace {

struct EntropyOptions {
  DataOptions data;
  int m = 2;
  double r = 0.2;
};

std::string number(double value, const char* format) {
  char text[64];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

void entropy_command(const EntropyOptions& o) {
  const auto record = load_evenly_sampled_record(o.data, {role::kRate}, "Sample entropy");
  const std::string role = primary_role(o.data);
  const auto& values = record.channel(role).values;
  const std::span<const double> x(values.data(), static_cast<std::size_t>(values.size()));
  const double sd = sampen::population_sd(x);
  if (std::all_of(x.begin(), x.end(), [&](double v) { return v == x.front(); }))
    throw DataError({o.data.path, 0, record.channel(role).source},
                    "the channel is constant (all " + std::to_string(x.size()) +
                        " samples equal): its standard deviation is 0, so the tolerance r x SD is 0 and SampEn is "
                        "undefined (a constant record has no irregularity to measure)");
  const auto result = sampen::sample_entropy(x, o.m, o.r * sd);

  const std::string unit = display_unit(record, role, o.data);
  const auto display = find_unit(unit);
  const double sd_shown = display ? sd / display->scale : sd;

  std::cout << "SampEn(m=" << o.m << ", r=" << o.r << ") = ";
  switch (result.status) {
    case sampen::Status::Finite:
      std::cout << number(std::max(0.0, result.value), "%.6f") << "\n";
      break;  // A <= B: never -0
    case sampen::Status::NoMatches:
      std::cout << "Inf  (no template pairs match over m+1 = " << o.m + 1 << " samples: A = 0)\n";
      break;
    case sampen::Status::Undefined:
      std::cout << "Inf  (undefined: no template pairs match over m = " << o.m << " samples: B = 0)\n";
      break;
  }
  std::cout << "A = " << result.a << "  (template pairs matching over m+1 = " << o.m + 1 << " samples)\n"
            << "B = " << result.b << "  (template pairs matching over m = " << o.m << " samples)\n"
            << "N = " << result.n << " samples of " << role << "; r = " << o.r << " x population SD "
            << number(sd_shown, "%.6g") << " " << unit << " = " << number(o.r * sd_shown, "%.6g") << " " << unit
            << "\n";
}

}  // namespace

void add_entropy_command(CLI::App& app, CommandEnv&) {
  auto options = std::make_shared<EntropyOptions>();
  auto* cmd = app.add_subcommand(
      "entropy", "sample entropy SampEn(m, r) of one channel (Richman & Moorman 2000; PhysioNet counts)");
  add_data_options(cmd, options->data, "column to analyse, role=column:unit (default rate_dps)");
  cmd->add_option("--m", options->m, "template length")->check(CLI::Range(0, 10))->capture_default_str();
  cmd->add_option("--r", options->r, "tolerance as a multiple of the population standard deviation")
      ->check(finite_number(0.0, 1e6, true))
      ->capture_default_str();
  cmd->callback([options] { entropy_command(*options); });
}

}  // namespace driftlab::cli
