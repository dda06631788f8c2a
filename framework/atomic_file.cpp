#include "framework/atomic_file.hpp"

#include <string>

#include "framework/error.hpp"
#include "framework/output_set.hpp"

namespace driftlab {

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  OutputSet output;
  output.plan(path, "");
  output.write(path, content);
  output.commit();
}

void ensure_not_an_input(const std::filesystem::path& output, const std::vector<std::filesystem::path>& inputs) {
  std::error_code ec;
  for (const auto& in : inputs) {
    const bool same = std::filesystem::exists(output, ec) && std::filesystem::exists(in, ec)
                          ? std::filesystem::equivalent(output, in, ec)
                          : std::filesystem::weakly_canonical(output, ec) == std::filesystem::weakly_canonical(in, ec);
    if (same)
      throw ConfigError({output.string(), 0, ""}, "output would overwrite the input " + in.string() +
                                                      "; inputs are never overwritten, choose another path");
  }
}

}  // namespace driftlab
