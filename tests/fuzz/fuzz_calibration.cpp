// libFuzzer harness: the calibration model reader (models/calibration, driftlab-calibration/1
// JSON). read_calibration takes a path, so each input is written to one scratch file.
// Property oracle: an accepted model writes JSON that reads back to the same JSON, and its
// compensator gives a finite rate (or a DataError) for an ordinary sample.
// Rejections must be ConfigError; anything else is a finding.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <string>

#include "framework/error.hpp"
#include "models/calibration/calibration_model.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"

namespace {

void write(const std::string& path, const char* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(data, static_cast<std::streamsize>(size));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  static const std::string path = "/tmp/driftlab_fuzz_calibration_" + std::to_string(::getpid()) + ".json";
  write(path, reinterpret_cast<const char*>(data), size);
  try {
    const auto model = calibration::read_calibration(path);
    const std::string text = calibration::to_json_text(model);
    write(path, text.data(), text.size());
    fuzz::require(calibration::to_json_text(calibration::read_calibration(path)) == text,
                  "the model's JSON reads back to itself", text);
    try {
      for (const auto& channel : model.channels) {
        calibration::CausalCompensator comp(channel.model);
        fuzz::require(std::isfinite(comp.step(0.0, 0.01, 25.0)), "a finite compensated rate", text);
      }
    } catch (const DataError&) {
    }
  } catch (const ConfigError&) {
  }
  return 0;
}
