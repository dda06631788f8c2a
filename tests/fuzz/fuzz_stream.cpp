// libFuzzer harness: the CSV stream parser (framework/csv.hpp CsvLineStream + CsvRowParser, what
// `driftlab compensate --stream` reads standard input with), differential against the batch reader
// (parse_csv on the whole text).
// Byte 0 picks the read options (as fuzz_csv: default columns, an explicit mapping, --fs); byte 1
// how the text arrives: the sizes of the successive reads (1 to 64 bytes, cycling) and, with bit 7,
// a line cap of 64 bytes; the rest is the text. Gaps are allowed in both (the gap test needs the
// whole record and is batch's alone).
// Properties: both accept or both refuse; when both accept, the same rows with bit-equal times and
// values; when both refuse, the same exception type and the same message. The one allowed
// difference is the stream's line cap: then the stream refuses with "is longer than 64 bytes" and
// the text really holds a line of more than 64 bytes.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"

namespace {

using namespace driftlab;

struct Outcome {
  bool accepted = false;
  std::string error;  // "config: ..." or "data: ..."
  std::vector<double> time;
  std::vector<std::vector<double>> values;  // per channel (batch) / per planned column (stream)
  std::vector<std::string> roles;
};

template <class F>
Outcome run(F&& f) {
  Outcome o;
  try {
    f(o);
    o.accepted = true;
  } catch (const ConfigError& e) {
    o.error = std::string("config: ") + e.what();
  } catch (const DataError& e) {
    o.error = std::string("data: ") + e.what();
  }
  return o;
}

bool has_line_longer_than(const std::string& text, std::size_t cap) {
  std::size_t run = 0;
  for (const char c : text) {
    run = (c == '\n' || c == '\r') ? 0 : run + 1;
    if (run > cap) return true;
  }
  return false;
}

// "data: <stdin>:LINE: the line is longer than 64 bytes ...", the cap's own message (a quoted cell
// may hold the same words, but never right after the line number).
bool is_cap_error(const std::string& error) {
  const std::string head = "data: <stdin>:";
  if (error.rfind(head, 0) != 0) return false;
  std::size_t i = head.size();
  while (i < error.size() && error[i] >= '0' && error[i] <= '9') ++i;
  return i > head.size() && error.compare(i, 35, ": the line is longer than 64 bytes ") == 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  using fuzz::require;
  const std::uint8_t mode = data[0], arrival = data[1];
  const std::string text(reinterpret_cast<const char*>(data + 2), size - 2);
  CsvReadOptions options;
  options.required_roles = (mode & 1) ? std::vector<std::string>{} : std::vector<std::string>{"rate"};
  if (mode & 2) options.columns = {{"rate", "g", "rad/s"}, {"temperature", "T", "K"}};
  if (mode & 4) options.sample_rate_hz = 100.0;
  if ((mode & 6) == 2) options.columns.push_back({"time", "ts", "ms"});
  options.max_gap_factor = 0.0;
  const std::size_t cap = (arrival & 0x80) ? 64 : text.size() + 1;

  const Outcome batch = run([&](Outcome& o) {
    const TimeSeries series = parse_csv(text, "<stdin>", options);
    o.time.assign(series.time().data(), series.time().data() + series.time().size());
    for (const auto& c : series.channels()) {
      o.roles.push_back(c.role);
      o.values.emplace_back(c.values.data(), c.values.data() + c.values.size());
    }
  });
  const Outcome stream = run([&](Outcome& o) {
    std::size_t offset = 0, call = 0;
    CsvLineStream lines(
        [&](char* buffer, std::size_t want) {
          const std::size_t piece = 1 + (static_cast<std::size_t>(arrival & 0x3f) * (++call)) % 64;
          const std::size_t n = std::min({want, piece, text.size() - offset});
          std::memcpy(buffer, text.data() + offset, n);
          offset += n;
          return n;
        },
        "<stdin>", cap, 64);
    CsvRowParser parser("<stdin>", options);
    std::vector<std::vector<double>> columns;
    std::string_view line;
    while (lines.next(line)) {
      if (!parser.has_header()) {
        parser.header(line, lines.line_number());
        columns.resize(parser.columns().size());
        continue;
      }
      parser.row(line, lines.line_number());
      o.time.push_back(parser.time_s());
      for (std::size_t k = 0; k < columns.size(); ++k) columns[k].push_back(parser.values()[k]);
    }
    parser.finish();
    // The channels as parse_csv makes them: every planned column but time and device ids.
    for (std::size_t k = 0; k < columns.size(); ++k) {
      const auto& role = parser.columns()[k].mapping.role;
      if (role == "time" || device_id_instance(role)) continue;
      o.roles.push_back(role);
      o.values.push_back(std::move(columns[k]));
    }
  });

  if (!stream.accepted && is_cap_error(stream.error)) {
    require(cap == 64 && has_line_longer_than(text, 64), "the line cap refuses only a line above it", stream.error);
    return 0;
  }
  const std::string detail = "batch: " + (batch.accepted ? std::string("accepted") : batch.error) +
                             "\nstream: " + (stream.accepted ? std::string("accepted") : stream.error);
  require(batch.accepted == stream.accepted, "stream and batch accept the same input", detail);
  if (!batch.accepted) {
    require(batch.error == stream.error, "stream and batch refuse with the same message", detail);
    return 0;
  }
  require(batch.time == stream.time, "stream and batch read the same time stamps", detail);
  std::vector<std::pair<std::string, std::vector<double>>> b, s;
  for (std::size_t i = 0; i < batch.roles.size(); ++i) b.emplace_back(batch.roles[i], batch.values[i]);
  for (std::size_t i = 0; i < stream.roles.size(); ++i) s.emplace_back(stream.roles[i], stream.values[i]);
  std::sort(b.begin(), b.end());
  std::sort(s.begin(), s.end());
  require(b == s, "stream and batch read the same channels and values", detail);
  return 0;
}
