// The layering of DESIGN.md section 2: plugins/ depends on the framework only. Checked twice: the
// libraries the plugins target links (read from CMake at configure time, DRIFTLAB_PLUGINS_LINKS)
// and the project headers the plugin sources include (every #include "..." under plugins/).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, separator);)
    if (!item.empty()) out.push_back(item);
  return out;
}

TEST(BuildGraph, PluginsLinkNoProjectLibraryButTheFramework) {
  const std::set<std::string> allowed{"driftlab::framework", "driftlab_framework", "driftlab_warnings"};
  const auto links = split(DRIFTLAB_PLUGINS_LINKS, ',');
  EXPECT_THAT(links, ::testing::Contains("driftlab::framework"));
  for (const auto& library : links) {
    if (library.rfind("driftlab", 0) == 0) {
      EXPECT_TRUE(allowed.count(library)) << "plugins link " << library;
    }
  }
}

TEST(BuildGraph, PluginSourcesIncludeNoProjectHeaderOutsideFrameworkAndPlugins) {
  const std::filesystem::path root = DRIFTLAB_SOURCE_DIR;
  const std::regex include(R"re(^\s*#\s*include\s*"([^"]+)")re");
  int files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root / "plugins")) {
    const auto ext = entry.path().extension();
    if (!entry.is_regular_file() || (ext != ".cpp" && ext != ".hpp")) continue;
    ++files;
    std::ifstream in(entry.path());
    int line_number = 0;
    for (std::string line; std::getline(in, line);) {
      ++line_number;
      std::smatch m;
      if (!std::regex_search(line, m, include)) continue;
      const std::string header = m[1];
      const bool below = header.rfind("framework/", 0) == 0 || header.rfind("plugins/", 0) == 0;
      EXPECT_TRUE(below) << std::filesystem::relative(entry.path(), root).string() << ":" << line_number << " includes "
                         << header;
    }
  }
  EXPECT_GT(files, 0);
}

}  // namespace
