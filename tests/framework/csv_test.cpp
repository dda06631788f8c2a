#include "framework/csv.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "framework/units.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;

const std::filesystem::path kCsvDir = std::filesystem::path(DRIFTLAB_TEST_DATA) / "csv";
constexpr double kUnitConversionTolerance = 1e-12;  // a couple of double roundings

TEST(CsvReader, ReadsDefaultColumnsAndConvertsToInternalUnits) {
  constexpr double kSixDecimals = 1e-6 * kRadPerDeg;  // good.csv prints the rate in deg/s with 6 decimals
  constexpr double kRateFromTimes = 1e-9;             // Hz: 10 Hz from decimal time stamps, to rounding
  const auto record = read_csv(kCsvDir / "good.csv");
  ASSERT_EQ(record.size(), 50);
  EXPECT_DOUBLE_EQ(record.time()[1], 0.1);
  EXPECT_EQ(record.channel("rate").unit, "rad/s");
  EXPECT_NEAR(record.channel("rate").values[7], 0.01 * std::sin(1.0) * kRadPerDeg, kSixDecimals);
  EXPECT_EQ(record.channel("temperature").unit, "degC");
  EXPECT_NEAR(record.channel("temperature").values[10], 25.01, kUnitConversionTolerance);
  EXPECT_NEAR(record.sample_rate_hz(), 10.0, kRateFromTimes);
}

TEST(CsvReader, ReadsOtherFilesThroughExplicitMappings) {
  CsvReadOptions options;
  options.columns = {parse_column_mapping("time=timestamp_ms:ms"), parse_column_mapping("rate=gyro_z:rad/s"),
                     parse_column_mapping("temperature=board_temp_k:K")};
  const auto record = read_csv(kCsvDir / "gyro_z_rad_s.csv", options);
  EXPECT_NEAR(record.time()[3], 0.03, kUnitConversionTolerance);
  EXPECT_NEAR(record.channel("rate").values[4], 0.004, kUnitConversionTolerance);
  EXPECT_NEAR(record.channel("temperature").values[0], 25.0, kUnitConversionTolerance);
}

TEST(CsvReader, SynthesizesTimeFromTheSampleRateWhenThereIsNoTimeColumn) {
  CsvReadOptions options;
  options.columns = {parse_column_mapping("rate=gyro_z:deg/h")};
  options.sample_rate_hz = 50.0;
  const auto record = read_csv(kCsvDir / "gyro_z_rad_s.csv", options);
  EXPECT_DOUBLE_EQ(record.time()[5], 0.1);
  EXPECT_NEAR(record.channel("rate").values[3], 0.003 * kRadPerDeg / kSecondsPerHour, kUnitConversionTolerance);
}

TEST(ColumnMapping, AcceptsTheThreeSpellingsAndRejectsUnknownUnits) {
  EXPECT_EQ(parse_column_mapping("rate=gyro_z:rad/s").role, "rate");
  EXPECT_EQ(parse_column_mapping("gyro_x:deg/s").role, "gyro_x");
  const auto suffixed = parse_column_mapping("true_rate_dps");
  EXPECT_EQ(suffixed.role, "true_rate");
  EXPECT_EQ(suffixed.unit, "deg/s");
  try {
    parse_column_mapping("rate=gyro_z:furlongs/fortnight");
    FAIL() << "an unknown unit must be rejected";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown unit 'furlongs/fortnight'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rad/s"), std::string::npos) << "lists the known units";
  }
}

struct BadCsv {
  const char* file;
  int line;
  const char* column;
  const char* message;
};

class CsvReaderRejects : public testing::TestWithParam<BadCsv> {};

TEST_P(CsvReaderRejects, NamingFileLineAndColumn) {
  const auto& bad = GetParam();
  const auto path = kCsvDir / bad.file;
  try {
    read_csv(path);
    FAIL() << bad.file << " must be rejected";
  } catch (const DataError& e) {
    EXPECT_EQ(e.where().file, path.string());
    EXPECT_EQ(e.where().line, bad.line) << e.what();
    EXPECT_EQ(e.where().field, bad.column) << e.what();
    EXPECT_NE(std::string(e.what()).find(bad.message), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Fixtures, CsvReaderRejects,
    testing::Values(BadCsv{"empty.csv", 0, "", "file is empty"}, BadCsv{"no_header.csv", 1, "", "missing header row"},
                    BadCsv{"missing_rate_column.csv", 1, "rate", "no column for the 'rate' channel"},
                    BadCsv{"non_numeric.csv", 8, "rate_dps", "expected a number, got 'abc'"},
                    BadCsv{"nan_line_1234.csv", 1234, "rate_dps", "NaN/Inf not allowed"},
                    BadCsv{"inf_temperature.csv", 11, "temp_c", "NaN/Inf not allowed"},
                    BadCsv{"decreasing_time.csv", 7, "t_s", "time stamps must increase"},
                    BadCsv{"duplicated_time.csv", 10, "t_s", "duplicated time stamp (same as line 9)"},
                    BadCsv{"gap.csv", 12, "t_s", "gap of"},
                    BadCsv{"ragged_row.csv", 5, "", "row has 4 cells, the header has 3"},
                    BadCsv{"empty_cell.csv", 13, "rate_dps", "empty cell"},
                    BadCsv{"does_not_exist.csv", 0, "", "does not exist"}),
    [](const auto& test_info) {
      std::string name = test_info.param.file;
      return name.substr(0, name.find('.'));
    });

TEST(CsvReader, AcceptsGapsWhenTheToleranceIsDisabled) {
  CsvReadOptions options;
  options.max_gap_factor = 0.0;
  EXPECT_EQ(read_csv(kCsvDir / "gap.csv", options).size(), 20);
}

TEST(CsvReader, RejectsAMappedColumnThatIsMissing) {
  CsvReadOptions options;
  options.columns = {parse_column_mapping("rate=gyro_q:rad/s")};
  try {
    read_csv(kCsvDir / "gyro_z_rad_s.csv", options);
    FAIL();
  } catch (const DataError& e) {
    EXPECT_EQ(e.where().line, 1);
    EXPECT_NE(std::string(e.what()).find("timestamp_ms"), std::string::npos) << "lists the header: " << e.what();
  }
}

// A CSV output the way commands write one: an OutputSet of one file.
void write_csv_atomically(const std::filesystem::path& path, const std::vector<CsvColumn>& columns) {
  OutputSet outputs;
  outputs.plan(path, "--out");
  outputs.write_csv(path, columns);
  outputs.commit();
}

TEST(CsvWriter, WritesAtomicallyAndRoundTripsExactly) {
  const auto dir = std::filesystem::temp_directory_path() / "driftlab_csv_writer_test";
  std::filesystem::create_directories(dir);
  const auto path = dir / "out.csv";
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(100, 0.0, 9.9);
  Eigen::VectorXd rate = (t.array() * 1.2345678901234567).sin() * 0.01;
  write_csv_atomically(path, {{"t_s", t, "s"}, {"rate_rps", rate, "rad/s"}});
  const auto back = read_csv(path);
  EXPECT_EQ(back.channel("rate").values, rate) << "shortest round-trip formatting is exact";
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename(), "out.csv") << "no temporary file left behind";
  std::filesystem::remove_all(dir);
}

TEST(CsvWriter, FailsClearlyWhenTheDirectoryIsMissing) {
  // A usage error (exit 2), not bad input data: the user named a directory that is not there.
  EXPECT_THROW(write_csv_atomically("/nonexistent-dir/out.csv", {{"t_s", Eigen::VectorXd::Zero(2), "s"}}), ConfigError);
}

TEST(CsvWriter, RefusesColumnNamesThatCannotBeReadBack) {
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(2);
  EXPECT_THROW(format_csv({{"t_s", v, "s"}, {"a,b", v, "1"}}, "out.csv"), ConfigError);
  EXPECT_THROW(format_csv({{"t_s", v, "s"}, {"t_s", v, "s"}}, "out.csv"), ConfigError);
  EXPECT_THROW(format_csv({{"", v, "s"}}, "out.csv"), ConfigError);
  EXPECT_THROW(format_csv({{"x", Eigen::VectorXd::Constant(2, 1e308), "deg/h"}}, "out.csv"), Error)
      << "a value that overflows in its output unit is not written as inf";
}

TEST(CsvWriter, AnOffsetUnitConvertsOnlyAbsoluteColumns) {
  const Eigen::VectorXd celsius = Eigen::VectorXd::Constant(1, 1.0);
  EXPECT_EQ(format_csv({{"abs_k", celsius, "K"}, {"dev_k", celsius, "K", false}}, "o.csv"), "abs_k,dev_k\n274.15,1\n");
}

TEST(CsvReader, AcceptsAByteOrderMarkAndCrOrCrLfLineEnds) {
  for (const std::string text : {"\xEF\xBB\xBFt_s,rate_dps\n0,1\n1,2\n", "t_s,rate_dps\r0,1\r1,2\r",
                                 "t_s,rate_dps\r\n0,1\r\n1,2\r\n", "t_s,rate_dps\r\n0,1\r1,2"}) {
    const auto series = parse_csv(text, "x.csv");
    EXPECT_EQ(series.size(), 2) << text;
  }
}

TEST(CsvReader, QuotesAtMostEightyBytesOfABadCellWithControlBytesEscaped) {
  const std::string cell = "\x1b[2J" + std::string(100000, 'z');
  try {
    parse_csv("t_s,rate_dps\n0," + cell + "\n", "x.csv");
    FAIL();
  } catch (const DataError& e) {
    EXPECT_THAT(e.what(), HasSubstr("'\\x1b[2Jzzz"));
    EXPECT_THAT(e.what(), HasSubstr("(100004 bytes in all)"));
    EXPECT_LT(std::string(e.what()).size(), 300u);
  }
}

TEST(CsvReader, FindsADuplicateAmongManyColumnsInOnePass) {
  std::string header = "t_s";
  for (int i = 0; i < 200000; ++i) header += ",c" + std::to_string(i);
  header += ",c123456";
  try {
    parse_csv(header + "\n", "wide.csv");
    FAIL();
  } catch (const DataError& e) {
    EXPECT_THAT(e.what(), HasSubstr("wide.csv:1: duplicated column name 'c123456' (columns 123458 and 200002)"));
  }
}

TEST(CsvReader, RefusesValuesWhoseArithmeticWouldOverflowAndSubNanosecondSteps) {
  EXPECT_THROW(parse_csv("t_s,rate_dps\n0,1\n1,-1e308\n", "x.csv"), DataError);
  EXPECT_THROW(parse_csv("t_s,rate_dps\n0,1\n1e-300,1\n", "x.csv"), DataError);
}

TEST(CsvMapping, EachRoleAcceptsOnlyUnitsOfItsDimension) {
  EXPECT_THROW(parse_column_mapping("rate=rate_dps:K"), ConfigError);
  EXPECT_THROW(parse_column_mapping("temperature=t:deg/s"), ConfigError);
  EXPECT_THROW(parse_column_mapping("time=t:Hz"), ConfigError);
  EXPECT_NO_THROW(parse_column_mapping("temperature=t:K"));
  EXPECT_NO_THROW(parse_column_mapping("accel=a:1")) << "other roles take any unit";
}

// A CsvLineStream source handing out `text` in reads of at most `piece` bytes; `offset` counts the
// bytes handed out.
CsvLineStream::Read reads_of(const std::string& text, std::size_t piece, std::size_t& offset) {
  return [&text, piece, &offset](char* buffer, std::size_t size) {
    const std::size_t n = std::min({size, piece, text.size() - offset});
    std::copy_n(text.data() + offset, n, buffer);
    offset += n;
    return n;
  };
}

// The stream reader (compensate --stream) gives exactly CsvLineCursor's lines and line numbers on
// the whole text, however the text is cut into reads: a CR LF split between two reads stays one
// line end, and a byte-order mark is skipped only at the very start.
TEST(CsvReader, AFileIsReadInPiecesToTheSameRecordAndErrorsAsItsText) {
  // Several of read_csv's 1-MiB reads, with a byte-order mark, CR LF and CR line ends, comments and
  // blank lines, so that line numbers differ from row numbers.
  const auto dir = std::filesystem::temp_directory_path() / ("driftlab_csv_pieces_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto record_text = [](double gap_s) {
    std::string text = "\xEF\xBB\xBF# oven run\r\nt_s,rate_dps,temp_c\r\n";
    for (int i = 0; i < 80000; ++i) {
      text += std::to_string(i * 0.01 + (i >= 40000 ? gap_s : 0.0)) + "," + std::to_string(std::sin(i * 1e-3)) + "," +
              std::to_string(20 + i * 1e-4);
      text += i % 7 == 0 ? "\r" : "\r\n";
      if (i % 5000 == 0) text += "# a comment\n\n";
    }
    return text;
  };
  const std::string text = record_text(0.0);
  ASSERT_GT(text.size(), std::size_t{2} << 20);
  std::ofstream(dir / "pieces.csv", std::ios::binary) << text;
  const auto from_file = read_csv(dir / "pieces.csv");
  const auto from_text = parse_csv(text, (dir / "pieces.csv").string());
  EXPECT_EQ(from_file.time(), from_text.time());
  EXPECT_EQ(from_file.channel("rate").values, from_text.channel("rate").values);
  EXPECT_EQ(from_file.channel("temperature").values, from_text.channel("temperature").values);

  // A gap after row 40000: the same message, naming the same line, either way.
  const std::string gapped = record_text(100.0);
  std::ofstream(dir / "gapped.csv", std::ios::binary) << gapped;
  std::string file_error, text_error;
  try {
    read_csv(dir / "gapped.csv");
  } catch (const DataError& e) {
    file_error = e.what();
  }
  try {
    parse_csv(gapped, (dir / "gapped.csv").string());
  } catch (const DataError& e) {
    text_error = e.what();
  }
  EXPECT_THAT(file_error, HasSubstr("gap of"));
  EXPECT_EQ(file_error, text_error);
  std::filesystem::remove_all(dir);
}

TEST(CsvLineStream, GivesTheCursorsLinesHoweverTheReadsAreCut) {
  const std::string text =
      "\xEF\xBB\xBFt_s,rate_dps\r\n# note\r\n\r\n0,1\r1,2\n\n2,3\r\n\xEF\xBB\xBF"
      "3,4\r";
  std::vector<std::pair<int, std::string>> expected;
  CsvLineCursor cursor(text);
  for (std::string_view line; cursor.next(line);) expected.emplace_back(cursor.line_number(), std::string(line));
  ASSERT_EQ(expected.size(), 5u);
  EXPECT_EQ(expected.back().second,
            "\xEF\xBB\xBF"
            "3,4");  // a mark inside the text is data
  for (std::size_t piece = 1; piece <= text.size(); ++piece) {
    std::size_t offset = 0;
    CsvLineStream lines(reads_of(text, piece, offset), "<stdin>", 64, piece);
    std::vector<std::pair<int, std::string>> got;
    for (std::string_view line; lines.next(line);) got.emplace_back(lines.line_number(), std::string(line));
    EXPECT_EQ(got, expected) << "reads of " << piece << " bytes";
  }
}

// fuzz_stream's finding (tests/fuzz/corpus/stream/cr_after_a_line_at_the_cap.bin): a line of exactly
// the cap whose CR has arrived, but not yet what follows it, is no longer than the cap.
TEST(CsvLineStream, ALineOfExactlyTheCapEndedByACrPasses) {
  const std::string text = std::string(8, 'x') + "\r";
  for (std::size_t piece = 1; piece <= text.size(); ++piece) {
    std::size_t offset = 0;
    CsvLineStream lines(reads_of(text, piece, offset), "<stdin>", 8, piece);
    std::string_view line;
    ASSERT_TRUE(lines.next(line)) << "reads of " << piece << " bytes";
    EXPECT_EQ(line, std::string(8, 'x'));
    EXPECT_FALSE(lines.next(line));
  }
}

TEST(CsvLineStream, RefusesALineLongerThanItsCapNamingTheLine) {
  const std::string text = "t_s,rate_dps\n0,1\n1," + std::string(100, '2') + "\n2,3\n";
  std::size_t offset = 0;
  CsvLineStream lines(reads_of(text, text.size(), offset), "<stdin>", 32, 8);
  std::string_view line;
  ASSERT_TRUE(lines.next(line));
  ASSERT_TRUE(lines.next(line));
  EXPECT_EQ(line, "0,1");
  try {
    lines.next(line);
    FAIL() << "a 102-byte line passed a 32-byte cap";
  } catch (const DataError& e) {
    EXPECT_THAT(e.what(), HasSubstr("<stdin>:3: the line is longer than 32 bytes (--max-line-bytes)"));
  }
  EXPECT_LT(offset, 64u) << "reading stopped once the line passed the cap";
}

// The one row parser: parse_csv's acceptance and messages row by row, with the raw cells kept.
TEST(CsvRowParser, ChecksEveryPlannedCellAndTheTimeOrderRowByRow) {
  CsvReadOptions options;
  CsvRowParser parser("f.csv", options);
  parser.header("t_s,rate_dps,note,temp_c", 1);
  parser.row("0, +0.5 ,a b,20", 2);
  EXPECT_EQ(parser.time_s(), 0.0);
  ASSERT_EQ(parser.cells().size(), 4u);
  EXPECT_EQ(parser.cells()[1], " +0.5 ");
  EXPECT_EQ(parser.cells()[2], "a b");
  const PlannedColumn* rate = parser.find("rate");
  ASSERT_NE(rate, nullptr);
  EXPECT_DOUBLE_EQ(parser.values()[static_cast<std::size_t>(rate - parser.columns().data())], 0.5 * kRadPerDeg);
  const auto message = [&](const std::string& line) {
    try {
      parser.row(line, 3);
    } catch (const DataError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message("1,x,a,20"), "f.csv:3: rate_dps: expected a number, got 'x'");
  EXPECT_EQ(message("1,0.1,a"), "f.csv:3: row has 3 cells, the header has 4");
  EXPECT_EQ(message("1,0.1,a,inf"), "f.csv:3: temp_c: value is 'inf' (NaN/Inf not allowed)");
  EXPECT_EQ(message("0,0.1,a,20"), "f.csv:3: t_s: duplicated time stamp (same as line 2)");
  EXPECT_EQ(message("1,0.1,,20"), "accepted") << "a column that is not read may be empty";
  EXPECT_EQ(message("0.5,0.1,a,20"), "f.csv:3: t_s: time stamps must increase (this one is earlier than line 3)");
  EXPECT_EQ(parser.rows(), 2u);
  CsvRowParser empty("g.csv", options);
  EXPECT_THROW(empty.finish(), DataError);
  EXPECT_THROW(empty.header("1,2,3", 1), DataError);
}

}  // namespace
}  // namespace driftlab
