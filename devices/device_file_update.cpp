#include "devices/device_file_update.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "devices/device_file.hpp"
#include "framework/effect_catalogue.hpp"
#include "framework/error.hpp"
#include "framework/yaml_io.hpp"

namespace driftlab::devices {
namespace {

constexpr int kSignificantDigits = 8;  // well below any fitted parameter's uncertainty

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

bool top_level_key(const std::string& line) {
  return !line.empty() && line[0] != ' ' && line[0] != '\t' && line[0] != '#' && line[0] != '-';
}

std::string number(double v) {
  std::ostringstream out;
  out << std::setprecision(kSignificantDigits) << v;
  return out.str();
}

// "name: {key: value, list: [a, b]}" in the catalogue's key order.
std::string effect_line(const NamedEffect& e, const std::string& file) {
  const EffectInfo* info = find_effect_info(e.name);
  if (!info)
    throw ConfigError({file, 0, "effects." + e.name},
                      "effect '" + e.name + "' cannot be written to a device file (not in the effect catalogue)");
  std::string line = e.name + ": {";
  for (std::size_t i = 0; i < info->keys.size(); ++i) {
    const auto& key = info->keys[i];
    const auto value =
        std::find_if(e.values.begin(), e.values.end(), [&](const EffectValue& v) { return v.key == key.key; });
    if (value == e.values.end() || value->values.empty())
      throw ConfigError({file, 0, "effects." + e.name + "." + key.key}, "no value for this key");
    std::string text;
    for (double v : value->values) text += (text.empty() ? "" : ", ") + number(v);
    line += (i ? ", " : "") + key.key + ": " + (key.list ? "[" + text + "]" : text);
  }
  return line + "}";
}

std::string indent_of(const std::string& line) { return line.substr(0, line.find_first_not_of(' ')); }

}  // namespace

std::string add_effects_to_device_text(const std::string& text, const std::string& file,
                                       const std::vector<NamedEffect>& effects, const std::string& note) {
  std::vector<std::string> lines = split_lines(text);
  std::vector<std::string> new_lines;
  for (const auto& e : effects) new_lines.push_back(effect_line(e, file));

  const auto section =
      std::find_if(lines.begin(), lines.end(), [](const std::string& l) { return l.rfind("effects:", 0) == 0; });
  if (section == lines.end()) {
    if (!lines.empty() && !lines.back().empty()) lines.push_back("");
    if (!note.empty()) lines.push_back("# " + note);
    lines.push_back("effects:");
    for (const auto& l : new_lines) lines.push_back("  " + l);
  } else {
    const auto at = static_cast<std::size_t>(section - lines.begin());
    std::string rest = lines[at].substr(8);
    const auto comment = rest.find(" #");
    const std::string trailing_comment = comment == std::string::npos ? "" : rest.substr(comment);
    if (comment != std::string::npos) rest = rest.substr(0, comment);
    if (rest.find_first_not_of(' ') != std::string::npos) {
      // Flow style on one line: rewrite as a block with the existing entries kept in order.
      // The shared checked loader (framework/yaml_io.hpp); the leading newlines put an error on
      // the file's line.
      const YAML::Node existing = load_yaml_checked(std::string(at, '\n') + rest, file);
      std::vector<std::string> block{"effects:" + trailing_comment};
      for (const auto& entry : existing) {
        const std::string name = entry.first.as<std::string>();
        if (std::any_of(effects.begin(), effects.end(), [&](const NamedEffect& e) { return e.name == name; })) continue;
        YAML::Emitter out;
        out << YAML::Flow << entry.second;
        block.push_back("  " + name + ": " + out.c_str());
      }
      for (const auto& l : new_lines) block.push_back("  " + l);
      lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(at));
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(at), block.begin(), block.end());
    } else {
      // Block style: the section runs to the next top-level key; entries are its least-indented keys.
      std::size_t end = at + 1;
      while (end < lines.size() && !top_level_key(lines[end])) ++end;
      std::size_t last_content = at;
      std::string indent = "  ";
      for (std::size_t k = at + 1; k < end; ++k) {
        const auto first = lines[k].find_first_not_of(' ');
        if (first == std::string::npos || lines[k][first] == '#') continue;
        if (last_content == at) indent = indent_of(lines[k]);
        last_content = k;
      }
      for (std::size_t i = 0; i < effects.size(); ++i) {
        const std::string prefix = indent + effects[i].name + ":";
        std::size_t k = at + 1;
        while (k < end && lines[k].rfind(prefix, 0) != 0) ++k;
        if (k < end) {  // replace the entry and its more-indented continuation lines
          std::size_t stop = k + 1;
          while (stop < end && (lines[stop].find_first_not_of(' ') == std::string::npos ||
                                indent_of(lines[stop]).size() > indent.size()))
            ++stop;
          lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(k + 1),
                      lines.begin() + static_cast<std::ptrdiff_t>(stop));
          lines[k] = indent + new_lines[i];
          const std::size_t removed = stop - k - 1;
          end -= removed;
          if (last_content >= stop)
            last_content -= removed;
          else if (last_content > k)
            last_content = k;
        } else {
          lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(last_content + 1), indent + new_lines[i]);
          ++last_content;
          ++end;
        }
      }
    }
  }
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  parse_device(out, file);  // the written file must load
  return out;
}

}  // namespace driftlab::devices
