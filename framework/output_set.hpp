// All outputs of one command, planned and checked before any computation and committed together
// (DESIGN.md §5: outputs atomic, inputs never overwritten; issue 17: all or nothing).
//
//   OutputSet outputs({data_path, device_path});       // the command's inputs
//   outputs.plan(o.out, "--out");                      // every output, before reading data:
//   outputs.plan(o.json, "--json");                    //   empty paths are skipped
//   ... compute ...
//   outputs.write_csv(o.out, columns);                 // staged in a temporary file next to it
//   outputs.write(o.json, text);
//   outputs.commit();                                  // renames every staged file into place
//
// plan() refuses (ConfigError, exit 2) a path that is an input, that another option of the same
// command already names, that exists and is not a regular file (a directory, FIFO, socket or
// device node, also through a symbolic link: outputs are regular files, always, and a rename
// would replace the node), or whose directory is missing or not writable; it creates the
// temporary file right away, so a path that cannot be written fails before any work. Temporary
// files are hidden, next to their output: ".NAME.tmp-XXXXXX" (mkstemp), the one naming scheme of
// every writer (a killed run leaves only such hidden files, never a partial file under NAME).
// commit() checks the paths again, requires every planned output to have been written, then
// renames them all; if one rename fails, the ones already renamed are put back (an earlier file of
// that name is restored). An OutputSet destroyed without commit() (an exception on the way)
// removes its temporary files and the directories make_directory() created: a failed command
// leaves nothing new behind.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "framework/csv.hpp"
#include "framework/error.hpp"

namespace driftlab {

class OutputSet {
 public:
  explicit OutputSet(std::vector<std::filesystem::path> inputs = {});
  ~OutputSet();
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  // Checks and reserves one output; `option` names it in messages ("--json"). Empty path: no-op.
  void plan(const std::filesystem::path& path, const std::string& option);
  bool planned(const std::filesystem::path& path) const;
  // Creates the directory `dir` (and missing parents) for outputs of this command; `option` names
  // it in messages. ConfigError when it cannot be created or exists as something else. The levels
  // it creates are removed again (when empty) unless the set is committed.
  void make_directory(const std::filesystem::path& dir, const std::string& option);

  // Stage the content of a planned output (throws std::logic_error when the path was not planned).
  // Different planned outputs may be written from different threads at once, as long as nothing is
  // planned, dropped, retired or committed meanwhile (`simulate --fleet` writes its units so).
  void write(const std::filesystem::path& path, std::string_view content);
  // Streams the CSV (stream_csv) to the temporary file: the text is never held whole.
  void write_csv(const std::filesystem::path& path, const std::vector<CsvColumn>& columns);
  // For a writer that needs a file name (a library writing the file itself, e.g. an MRPT rawlog):
  // the staged temporary file to write into, in the output's directory; the output counts as
  // written. The writer may replace the file (its own temp + rename) but must not rename it away.
  std::filesystem::path stage_path(const std::filesystem::path& path);

  // Gives up a planned output that will not be written after all (an optional figure that could
  // not be drawn); its temporary file is removed.
  void drop(const std::filesystem::path& path);

  // An output of an earlier run that this run replaces with nothing (a file a failed run does not
  // write): removed by commit(), after every rename, so a committed set leaves exactly its files.
  // Checked like plan() (never an input, never a node that is not a regular file).
  void retire(const std::filesystem::path& path, const std::string& option);

  // Removes the hidden temporary files of `path` (".NAME.tmp-XXXXXX" and commit()'s ".old" links)
  // that a killed run left next to it. Only for outputs one command owns exclusively (a fleet
  // unit's directory): another run's live temporaries look the same.
  static void remove_stale_temporaries(const std::filesystem::path& path);

  // Renames every staged file into place, all or nothing.
  void commit();

 private:
  // Opens the entry's temporary file, hands `produce` a function that appends to it, then syncs
  // and closes it.
  void write_with(const std::filesystem::path& path,
                  const std::function<void(const std::function<void(std::string_view)>&)>& produce);
  struct Entry {
    std::filesystem::path path;
    std::string option;
    std::string temp;  // temporary file next to `path`
    bool written = false;
  };
  Entry& entry(const std::filesystem::path& path);
  // ConfigError when `path` is already an output of this set, an input, or exists as something other
  // than a regular file.
  void check_output(const std::filesystem::path& path, const Location& where) const;
  void discard() noexcept;

  std::vector<std::filesystem::path> inputs_;
  std::vector<Entry> entries_;
  std::vector<std::filesystem::path> retired_;
  std::vector<std::filesystem::path> created_dirs_;  // by make_directory(), outermost first
  bool committed_ = false;
};

}  // namespace driftlab
