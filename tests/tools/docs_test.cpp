// The documentation against the product: README.md is an entry point of at most 200 lines; every
// relative link in README.md and docs/ resolves to a file (and heading) inside the repository; the
// generated references (docs/cli.md, the plugin table of docs/plugins.md) equal what the program
// prints; and every fenced ```sh and ```python block says on the line before its fence whether it
// runs: `<!-- docs-test: runs -->` (it is run here as written) or `<!-- docs-test: not run: REASON -->`
// (REASON, not empty, says why it cannot run in a test: it builds the whole tree, needs a Slurm
// cluster, a record that is not bundled, ...). A block with neither marker fails. The blocks that
// run, run page by page in one scratch directory each, which is also $HOME (so `~/.local` stays
// inside it), with `driftlab` on the PATH, `python3` the interpreter the Python module was built
// for, the build tree's Python package importable, and the repository's devices/, models/, tests/,
// tools/ and python/ and the build tree (as build/) beside them.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <iostream>
#include <regex>
#include <set>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using namespace testing_cli;
namespace fs = std::filesystem;

const fs::path kSource = DRIFTLAB_SOURCE_DIR;
constexpr std::size_t kReadmeMaxLines = 200;
const std::string kRunsMarker = "<!-- docs-test: runs -->";
const std::string kNotRunMarkerBegin = "<!-- docs-test: not run:", kMarkerEnd = "-->";

// README.md, then every Markdown file under docs/, sorted.
std::vector<fs::path> markdown_pages() {
  std::vector<fs::path> pages{kSource / "README.md"};
  for (const auto& entry : fs::recursive_directory_iterator(kSource / "docs")) {
    if (entry.is_regular_file() && entry.path().extension() == ".md") pages.push_back(entry.path());
  }
  std::sort(pages.begin() + 1, pages.end());
  return pages;
}

std::string relative_name(const fs::path& page) { return fs::relative(page, kSource).string(); }

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// GitHub's anchor of a heading: lower case; letters, digits, '-' and '_' kept, spaces become '-',
// everything else (punctuation, backquotes, non-ASCII) dropped.
std::string heading_anchor(const std::string& heading) {
  std::string anchor;
  for (const unsigned char c : heading) {
    if (std::isalnum(c) && c < 0x80) {
      anchor += static_cast<char>(std::tolower(c));
    } else if (c == ' ' || c == '-') {
      anchor += '-';
    } else if (c == '_') {
      anchor += '_';
    }
  }
  return anchor;
}

// The anchors of a page's headings (outside fenced blocks).
std::set<std::string> anchors_of(const fs::path& page) {
  std::set<std::string> anchors;
  bool fenced = false;
  for (const auto& line : lines_of(read_text(page))) {
    if (line.rfind("```", 0) == 0) fenced = !fenced;
    if (fenced || line.empty() || line[0] != '#') continue;
    const auto text = line.find_first_not_of('#');
    if (text != std::string::npos) anchors.insert(heading_anchor(line.substr(text + 1)));
  }
  return anchors;
}

// Markdown link targets `](target)` of a page, outside fenced blocks.
std::vector<std::string> link_targets(const fs::path& page) {
  static const std::regex link(R"(\]\(([^)\s]+)\))");
  std::vector<std::string> targets;
  bool fenced = false;
  for (const auto& line : lines_of(read_text(page))) {
    if (line.rfind("```", 0) == 0) fenced = !fenced;
    if (fenced) continue;
    for (std::sregex_iterator m(line.begin(), line.end(), link), end; m != end; ++m) targets.push_back((*m)[1]);
  }
  return targets;
}

bool is_external(const std::string& target) {
  return target.rfind("http://", 0) == 0 || target.rfind("https://", 0) == 0 || target.rfind("mailto:", 0) == 0;
}

bool inside_source(const fs::path& p) {
  const auto normal = p.lexically_normal().string(), root = kSource.lexically_normal().string();
  return normal == root || normal.rfind(root + "/", 0) == 0;
}

struct CodeBlock {
  std::size_t line = 0;  // 1-based line of the opening fence
  bool python = false;   // a ```python block; otherwise ```sh
  std::string text;
  bool marked_runs = false;
  bool marked_not_run = false;
  std::string not_run_reason;  // the REASON of `<!-- docs-test: not run: REASON -->`, trimmed
};

std::string trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

// The ```sh and ```python blocks of a page, each with the marker on the line before its fence.
std::vector<CodeBlock> code_blocks(const fs::path& page) {
  const auto lines = lines_of(read_text(page));
  std::vector<CodeBlock> blocks;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (lines[i] != "```sh" && lines[i] != "```python") continue;
    CodeBlock block{i + 1, lines[i] == "```python", "", i > 0 && lines[i - 1] == kRunsMarker};
    const std::string before = i > 0 ? lines[i - 1] : "";
    if (before.rfind(kNotRunMarkerBegin, 0) == 0 && before.size() >= kNotRunMarkerBegin.size() + kMarkerEnd.size() &&
        before.compare(before.size() - kMarkerEnd.size(), kMarkerEnd.size(), kMarkerEnd) == 0) {
      block.marked_not_run = true;
      block.not_run_reason = trimmed(
          before.substr(kNotRunMarkerBegin.size(), before.size() - kNotRunMarkerBegin.size() - kMarkerEnd.size()));
    }
    for (++i; i < lines.size() && lines[i].rfind("```", 0) != 0; ++i) block.text += lines[i] + "\n";
    blocks.push_back(block);
  }
  return blocks;
}

TEST(Docs, ReadmeIsAnEntryPointOfAtMost200Lines) {
  const auto lines = lines_of(read_text(kSource / "README.md"));
  EXPECT_LE(lines.size(), kReadmeMaxLines) << "README.md is an entry point; move detail into docs/";
}

TEST(Docs, NoPageReferencesAFileOutsideTheRepository) {
  for (const auto& page : markdown_pages()) {
    const auto text = read_text(page);
    EXPECT_THAT(text, ::testing::Not(HasSubstr("../shared"))) << relative_name(page);
    for (const auto& target : link_targets(page)) {
      if (is_external(target) || target[0] == '#') continue;
      const auto file = target.substr(0, target.find('#'));
      EXPECT_TRUE(inside_source(page.parent_path() / file))
          << relative_name(page) << ": link " << target << " leaves the repository";
    }
  }
}

TEST(Docs, EveryRelativeLinkResolvesToAFileAndHeading) {
  for (const auto& page : markdown_pages()) {
    for (const auto& target : link_targets(page)) {
      if (is_external(target)) continue;
      const auto hash = target.find('#');
      const auto file = target.substr(0, hash);
      const auto path = file.empty() ? page : (page.parent_path() / file).lexically_normal();
      ASSERT_TRUE(fs::exists(path)) << relative_name(page) << ": link " << target << ": no such file";
      if (hash == std::string::npos || path.extension() != ".md") continue;
      EXPECT_TRUE(anchors_of(path).count(target.substr(hash + 1)))
          << relative_name(page) << ": link " << target << ": no such heading in " << relative_name(path);
    }
  }
}

TEST(Docs, CliReferenceIsWhatTheCommandsPrint) {
  if (!DRIFTLAB_HAVE_MRPT) GTEST_SKIP() << "built without MRPT: `driftlab mrpt` and `nav` print a stub";
  const auto dir = scratch_dir("docs_cli");
  const auto out = dir / "cli.md";
  const std::string command = "bash " + (kSource / "tools/cli-reference.sh").string() + " " + DRIFTLAB_EXE + " >" +
                              out.string() + " 2>" + (dir / "stderr").string();
  ASSERT_EQ(std::system(command.c_str()), 0) << read_text(dir / "stderr");
  EXPECT_EQ(read_text(kSource / "docs/cli.md"), read_text(out))
      << "docs/cli.md is out of date; regenerate it: bash tools/cli-reference.sh build/tools/driftlab/driftlab > "
         "docs/cli.md";
}

TEST(Docs, PluginReferenceIsWhatPluginsDescribePrints) {
  const auto generated = run_driftlab("plugins describe --markdown");
  ASSERT_EQ(generated.exit_code, 0) << generated.err;
  const auto page = read_text(kSource / "docs/plugins.md");
  const std::string begin = "<!-- plugin-table:begin -->\n", end = "<!-- plugin-table:end -->";
  const auto b = page.find(begin), e = page.find(end);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(e, std::string::npos);
  EXPECT_EQ(page.substr(b + begin.size(), e - b - begin.size()), generated.out)
      << "regenerate the part of docs/plugins.md between the plugin-table markers: driftlab plugins describe "
         "--markdown";
}

// Every `driftlab WORD` at the start of a line of a shell block names a command of `driftlab --help`
// (a check of the blocks that are not run, too).
TEST(Docs, EveryShownCommandIsACommandOfTheProgram) {
  const auto help = run_driftlab("--help");
  ASSERT_EQ(help.exit_code, 0);
  std::set<std::string> commands;
  bool listing = false;
  for (const auto& line : lines_of(help.out)) {
    if (line == "Subcommands:") listing = true;
    static const std::regex entry(R"(^  ([a-z]+) )");
    std::smatch m;
    if (listing && std::regex_search(line, m, entry)) commands.insert(m[1]);
  }
  ASSERT_THAT(commands, ::testing::Contains("calibrate"));
  std::size_t shown = 0;
  static const std::regex command(R"(^driftlab ((--?[a-z-]+( [^-][^ ]*)? )*)([a-z]+))");
  for (const auto& page : markdown_pages()) {
    for (const auto& block : code_blocks(page)) {
      if (block.python) continue;
      for (const auto& line : lines_of(block.text)) {
        std::smatch m;
        if (!std::regex_search(line, m, command)) continue;
        ++shown;
        EXPECT_TRUE(commands.count(m[4])) << relative_name(page) << ":" << block.line << ": " << line;
      }
    }
  }
  EXPECT_GT(shown, 20U);
}

// Every ```sh and ```python block either runs (below) or says why it cannot: a block without a marker
// would be a command nobody checks.
TEST(Docs, EveryCodeBlockRunsOrSaysWhyNot) {
  std::size_t runs = 0, not_run = 0;
  for (const auto& page : markdown_pages()) {
    for (const auto& block : code_blocks(page)) {
      const auto where = relative_name(page) + ":" + std::to_string(block.line);
      if (block.marked_runs) {
        ++runs;
      } else if (block.marked_not_run) {
        ++not_run;
        EXPECT_FALSE(block.not_run_reason.empty())
            << where << ": `" << kNotRunMarkerBegin << " REASON " << kMarkerEnd << "` needs a REASON";
      } else {
        ADD_FAILURE() << where << ": a block without a marker; put `" << kRunsMarker << "` or `" << kNotRunMarkerBegin
                      << " REASON " << kMarkerEnd << "` on the line before its fence:\n"
                      << block.text;
      }
    }
  }
  EXPECT_GT(runs, not_run) << "most shown commands should run";
}

// The pages (relative to the repository) that hold at least one block marked to run.
std::vector<std::string> pages_with_marked_blocks() {
  std::vector<std::string> pages;
  for (const auto& page : markdown_pages()) {
    const auto blocks = code_blocks(page);
    if (std::any_of(blocks.begin(), blocks.end(), [](const CodeBlock& b) { return b.marked_runs; })) {
      pages.push_back(relative_name(page));
    }
  }
  return pages;
}

class DocsPage : public ::testing::TestWithParam<std::string> {};

// Runs the page's marked blocks in order in one scratch directory; a block that fails (any command
// with a nonzero exit, a Python exception) fails the test with its output.
TEST_P(DocsPage, MarkedCodeBlocksRunAsWritten) {
  const auto page = kSource / GetParam();
  std::vector<CodeBlock> blocks;
  for (const auto& block : code_blocks(page)) {
    if (block.marked_runs) blocks.push_back(block);
  }
  const auto dir = scratch_dir("docs_run_" + page.stem().string());
  for (const auto* tree : {"devices", "models", "python", "tests", "tools"})
    fs::create_directory_symlink(kSource / tree, dir / tree);
  fs::create_directory_symlink(DRIFTLAB_BUILD_DIR, dir / "build");
  const auto bin = fs::path(DRIFTLAB_EXE).parent_path();
  const std::string python = DRIFTLAB_PYTHON;
  // `python3` in a shell block is the interpreter the module was built for (the PATH's may be another).
  const auto python_bin = dir / ".python3";
  fs::create_directory(python_bin);
  if (!python.empty()) fs::create_symlink(python, python_bin / "python3");
  for (const auto& block : blocks) {
    const bool needs_mrpt =
        block.text.find("driftlab nav") != std::string::npos || block.text.find("driftlab mrpt") != std::string::npos;
    if (needs_mrpt && !DRIFTLAB_HAVE_MRPT) continue;
    const bool needs_python = block.python || block.text.find("python3") != std::string::npos;
    if (needs_python && python.empty()) continue;  // built without the Python module
    const auto script = dir / ("block_" + std::to_string(block.line) + (block.python ? ".py" : ".sh"));
    std::ofstream(script) << block.text;
    const auto log = dir / "output";
    const std::string interpreter =
        block.python ? std::string("PYTHONPATH=") + DRIFTLAB_PYTHONPATH + " " + python : "bash -e -o pipefail";
    const std::string command = "cd " + dir.string() + " && HOME=" + dir.string() + " PATH=" + bin.string() + ":" +
                                python_bin.string() + ":$PATH " + interpreter + " " + script.string() + " >" +
                                log.string() + " 2>&1";
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(std::system(command.c_str()), 0) << relative_name(page) << ":" << block.line << ": the block failed:\n"
                                               << block.text << "--- output:\n"
                                               << read_text(log);
    const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
    std::cout << relative_name(page) << ":" << block.line << ": " << took.count() << " s\n";
  }
}

std::string page_test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = info.param;
  for (auto& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Pages, DocsPage, ::testing::ValuesIn(pages_with_marked_blocks()), page_test_name);

// The marker is in use where the tour and the tutorials show commands: a renamed marker would
// otherwise leave every block unrun without a failure.
TEST(Docs, TheReadmeAndEveryTutorialWithCommandsHaveBlocksThatRun) {
  const auto pages = pages_with_marked_blocks();
  for (const auto* page : {"README.md", "docs/usage.md", "docs/tutorials/paper.md", "docs/tutorials/calibrate-imu.md",
                           "docs/tutorials/fleet.md", "docs/tutorials/discrepancy.md", "docs/tutorials/compare.md",
                           "docs/tutorials/mrpt-navigation.md", "docs/tutorials/python.md"}) {
    EXPECT_THAT(pages, ::testing::Contains(page));
  }
}

}  // namespace
}  // namespace driftlab
