#include <iomanip>
#include <iostream>
#include <memory>

#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
namespace {

std::string default_text(const ParamSpec& p) {
  const auto text = format_value(p.default_value);
  return text.empty() ? "\"\"" : text;
}

void describe(const PluginInfo& info, std::ostream& out) {
  out << info.name << "  (" << info.origin << ")\n  " << info.summary << "\n";
  if (!info.reference.empty()) out << "  reference: " << info.reference << "\n";
  out << "  inputs:";
  const auto& ports = ports_of_kind(info.kind());
  if (ports.inputs.empty()) out << " none (used nested inside other plugins)";
  for (const auto& port : ports.inputs)
    out << " " << port.name << (port.required ? "" : "?") << (port.many ? "[]" : "");
  out << "\n  outputs:";
  for (const auto& o : ports.outputs) out << " " << o;
  out << "\n  parameters:\n";
  if (info.params.params.empty()) out << "    (none)\n";
  for (const auto& p : info.params.params) {
    out << "    " << p.key << "  " << to_string(p.type) << "  default " << default_text(p);
    if (!p.unit.empty() && p.unit != "1") out << "  [" << p.unit << "]";
    out << "  " << p.constraint_text() << "\n      " << p.doc << "\n";
  }
  for (const auto& r : info.params.rules) out << "    rule: " << r.description << "\n";
}

void markdown_table(const Registry& registry, std::ostream& out) {
  out << "| plugin | parameter | type | default | unit | constraint | meaning |\n"
      << "|---|---|---|---|---|---|---|\n";
  for (const auto* info : registry.list()) {
    out << "| **" << info->name << "** | | | | | | " << info->summary << " |\n";
    for (const auto& p : info->params.params)
      out << "| | `" << p.key << "` | " << to_string(p.type) << " | `" << default_text(p) << "` | " << p.unit << " | "
          << p.constraint_text() << " | " << p.doc << " |\n";
  }
}

}  // namespace

void add_plugins_command(CLI::App& app, CommandEnv& env) {
  auto* plugins = app.add_subcommand("plugins", "list and describe the registered plugins");
  plugins->require_subcommand(1);

  auto* list = plugins->add_subcommand("list", "list plugins by kind");
  list->callback([&env] {
    const auto& registry = env.registry();
    for (const auto& kind : plugin_kinds()) {
      const auto infos = registry.list(kind);
      std::cout << kind << ":\n";
      if (infos.empty()) std::cout << "  (none)\n";
      for (const auto* info : infos)
        std::cout << "  " << std::left << std::setw(32) << info->name << info->summary
                  << (info->origin == "built-in" ? "" : "  [" + info->origin + "]") << "\n";
    }
  });

  auto* describe_cmd =
      plugins->add_subcommand("describe", "describe plugins: parameters with type, default, unit, range, doc");
  struct Options {
    std::vector<std::string> names;
    bool markdown = false;
  };
  auto opts = std::make_shared<Options>();
  describe_cmd->add_option("names", opts->names, "plugin names (kind/name); all plugins when omitted");
  describe_cmd->add_flag("--markdown", opts->markdown,
                         "print one Markdown table of every parameter (for docs/plugins.md)");
  describe_cmd->callback([&env, opts] {
    const auto& registry = env.registry();
    if (opts->markdown) return markdown_table(registry, std::cout);
    std::vector<const PluginInfo*> infos;
    if (opts->names.empty()) infos = registry.list();
    for (const auto& n : opts->names) infos.push_back(&registry.info(n));
    for (std::size_t i = 0; i < infos.size(); ++i) {
      if (i) std::cout << "\n";
      describe(*infos[i], std::cout);
    }
  });
}

}  // namespace driftlab::cli
