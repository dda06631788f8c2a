#include "framework/atomic_file.hpp"

#include "framework/output_set.hpp"

namespace driftlab {

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  OutputSet output;
  output.plan(path, "");
  output.write(path, content);
  output.commit();
}

}  // namespace driftlab
