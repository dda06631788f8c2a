#include "tools/mrpt/rawlog_io.hpp"

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "framework/regular_file.hpp"
#include "framework/resources.hpp"

namespace driftlab::mrpt_bridge {
namespace {

namespace fs = std::filesystem;
using mrpt::obs::CObservationIMU;

constexpr double kTicksPerSecond = 1e7;                         // mrpt::Clock: 100 ns ticks
constexpr std::int64_t kUnixEpochTicks = 116444736000000000LL;  // 1970-01-01 in FILETIME ticks

DataError data_error(const fs::path& file, const std::string& message) {
  return DataError(Location{file.string(), 0, ""}, message);
}

// MRPT's exception texts nest ("==== MRPT exception ====", "Message: ...", a call trace): keep the
// innermost message, which says what went wrong.
std::string innermost_message(const std::string& text) {
  std::istringstream in(text);
  std::string line, best;
  while (std::getline(in, line))
    if (line.rfind("Message:", 0) == 0) best = line.substr(line.find_first_not_of(" ", 8));
  if (best.empty()) best = text.substr(0, text.find('\n'));
  return best.size() > 200 ? best.substr(0, 200) + "..." : best;
}

// A CStream over a rawlog file that can look one byte ahead, so the end of the file between two
// objects (a clean end) is told apart from an end inside an object (a truncated file).
class PeekStream : public mrpt::io::CStream {
 public:
  explicit PeekStream(const fs::path& path) {
    check_data_input(path);
    if (!file_.open(path.string())) throw data_error(path, "cannot open the rawlog file");
  }
  bool at_end() {
    if (pending_) return false;
    std::uint8_t b = 0;
    if (file_.Read(&b, 1) != 1) return true;
    pending_ = b;
    return false;
  }
  size_t Read(void* buffer, size_t count) override {
    if (count == 0) return 0;
    auto* out = static_cast<std::uint8_t*>(buffer);
    size_t done = 0;
    if (pending_) {
      out[0] = *pending_;
      pending_.reset();
      done = 1;
    }
    return done + (count > done ? file_.Read(out + done, count - done) : 0);
  }
  size_t Write(const void*, size_t) override { throw std::logic_error("PeekStream is read-only"); }
  uint64_t Seek(int64_t, CStream::TSeekOrigin) override { throw std::logic_error("PeekStream cannot seek"); }
  uint64_t getTotalBytesCount() const override { return file_.getTotalBytesCount(); }
  uint64_t getPosition() const override { return file_.getPosition() - (pending_ ? 1 : 0); }

 private:
  mrpt::io::CFileGZInputStream file_;
  std::optional<std::uint8_t> pending_;
};

std::string index_text(std::size_t object, int in_frame) {
  return "object " + std::to_string(object) +
         (in_frame >= 0 ? " (observation " + std::to_string(in_frame) + " of its sensory frame)" : "") + ": ";
}

std::int64_t ticks_of(const mrpt::Clock::time_point& t) { return t.time_since_epoch().count(); }

// The byte MRPT's deserializer stored in a bool: reading a bool holding anything but 0 or 1 is
// undefined behaviour, so a flag is looked at as a byte before it is used.
unsigned bool_byte(const bool& flag) {
  unsigned char byte = 0;
  std::memcpy(&byte, &flag, 1);
  return byte;
}

// What the bridge reads of a deserialized object, checked before it is used (issue 28): every
// presence flag of an IMU observation and the flags of an odometry action are 0 or 1, and IMU time
// stamps are not before MRPT's clock epoch (1601; 100-ns ticks >= 0, so the difference of two never
// overflows). DataError naming the file and the object otherwise.
void check_object(const mrpt::serialization::CSerializable::Ptr& object, const fs::path& path, std::size_t k) {
  const auto check_observation = [&](const mrpt::obs::CObservation::Ptr& obs, int j) {
    const auto imu = std::dynamic_pointer_cast<CObservationIMU>(obs);
    if (!imu) return;
    for (std::size_t f = 0; f < imu->dataIsPresent.size(); ++f)
      if (const unsigned b = bool_byte(imu->dataIsPresent[f]); b > 1)
        throw data_error(path, index_text(k, j) + "the presence flag of IMU field " + std::to_string(f) + " is byte " +
                                   std::to_string(b) + "; expected 0 or 1 (malformed rawlog)");
    if (ticks_of(imu->timestamp) < 0)
      throw data_error(path, index_text(k, j) + "IMU time stamp " + std::to_string(ticks_of(imu->timestamp)) +
                                 " is before the MRPT clock's epoch (1601-01-01; expected 100-ns ticks >= 0)");
  };
  if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(object)) {
    int j = 0;
    for (const auto& obs : *sf) check_observation(obs, j++);
  } else if (auto acts = std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(object)) {
    for (std::size_t a = 0; a < acts->size(); ++a)
      if (auto odo = std::dynamic_pointer_cast<mrpt::obs::CActionRobotMovement2D>(acts->get(a)))
        for (const bool* flag : {&odo->hasVelocities, &odo->hasEncodersInfo})
          if (const unsigned b = bool_byte(*flag); b > 1)
            throw data_error(path, index_text(k, -1) + "an odometry flag of action " + std::to_string(a) + " is byte " +
                                       std::to_string(b) + "; expected 0 or 1 (malformed rawlog)");
  } else if (auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(object)) {
    check_observation(obs, -1);
  }
}

// Reads the top-level objects of a rawlog one at a time, each checked (check_object).
class ObjectReader {
 public:
  explicit ObjectReader(const fs::path& path) : path_(path), stream_(path) {}
  // The next object, or nullptr at a clean end of file. Index of the returned object: index().
  mrpt::serialization::CSerializable::Ptr next() {
    if (stream_.at_end()) {
      if (count_ == 0) throw data_error(path_, "empty rawlog (no objects)");
      return nullptr;
    }
    index_ = count_++;
    try {
      auto archive = mrpt::serialization::archiveFrom(stream_);
      auto object = archive.ReadObject();
      if (!object) throw data_error(path_, where() + "a null object");
      check_object(object, path_, index_);
      return object;
    } catch (const DataError&) {
      throw;
    } catch (const mrpt::serialization::CExceptionEOF&) {
      throw data_error(path_, where() + "the file ends inside this object (truncated rawlog)");
    } catch (const std::exception& e) {
      const std::string what = e.what();
      if (what.find("EOF") != std::string::npos || what.find("nexpected end") != std::string::npos)
        throw data_error(path_, where() + "the file ends inside this object (truncated rawlog)");
      throw data_error(path_, where() + "not a valid MRPT object (malformed rawlog): " + innermost_message(what));
    }
  }
  std::size_t index() const { return index_; }
  std::size_t count() const { return count_; }
  std::string where() const { return "object " + std::to_string(index_) + ": "; }

 private:
  fs::path path_;
  PeekStream stream_;
  std::size_t index_ = 0, count_ = 0;
};

// MRPT's deserializer trusts the file: a malformed object can crash it (a null dereference) and a
// length field can make it allocate gigabytes before anything fails. So a rawlog is first read
// whole in a child process, with its address space limited to what it holds now plus
// kDeserializeBytes and the fatal signals at their default action (whatever handlers this process
// installed), reporting the index of each object it starts, then either the message of a failed
// read or that it read every object. A crash there, a failed read (running out of that memory:
// std::bad_alloc), or any other end of the child becomes a DataError naming the object; only a file
// that the child read to its end is read here.
constexpr double kDeserializeBytes = 1024.0 * 1024.0 * 1024.0;  // for one object at a time

void read_in_child_first(const fs::path& path) {
  int pipe_fds[2];
  if (::pipe(pipe_fds) != 0) return;  // no guard available: read as before
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    return;
  }
  constexpr std::uint64_t kMessage = ~std::uint64_t{0};  // then the text of the child's DataError
  constexpr std::uint64_t kReadAll = kMessage - 1;       // the child read every object
  if (pid == 0) {  // the child: no destructors, no atexit handlers, no stdio flush (_exit)
    ::close(pipe_fds[0]);
    for (const int fatal : {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT}) std::signal(fatal, SIG_DFL);
    long pages = 0;
    if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(f, "%ld", &pages) != 1) pages = 0;
      std::fclose(f);
    }
    const double now = static_cast<double>(pages) * static_cast<double>(::sysconf(_SC_PAGESIZE));
    const auto limit = static_cast<rlim_t>(now + std::min(kDeserializeBytes, memory_limit_bytes()));
    const rlimit as{limit, limit};
    ::setrlimit(RLIMIT_AS, &as);
    try {
      ObjectReader reader(path);
      for (;;) {
        const std::uint64_t index = reader.count();
        if (::write(pipe_fds[1], &index, sizeof index) != sizeof index) ::_exit(0);
        if (!reader.next()) break;
      }
      const std::uint64_t done = kReadAll;
      if (::write(pipe_fds[1], &done, sizeof done) != sizeof done) ::_exit(0);
    } catch (const DataError& e) {  // ObjectReader's, for every failure (std::bad_alloc included): sent after kMessage
      const std::uint64_t marker = kMessage;
      const std::string text = e.what();
      if (::write(pipe_fds[1], &marker, sizeof marker) == sizeof marker)
        for (std::size_t done = 0; done < text.size();) {
          const auto n = ::write(pipe_fds[1], text.data() + done, text.size() - done);
          if (n <= 0) break;
          done += static_cast<std::size_t>(n);
        }
    } catch (...) {  // anything else: without kReadAll the parent reports an unfinished read
    }
    ::_exit(0);
  }
  ::close(pipe_fds[1]);
  std::uint64_t index = 0, last = 0;
  std::string message;
  bool read_all = false;
  while (::read(pipe_fds[0], &index, sizeof index) == sizeof index) {
    if (index == kReadAll) read_all = true;
    if (index != kMessage) {
      if (!read_all) last = index;
      continue;
    }
    char buffer[4096];
    for (ssize_t n; (n = ::read(pipe_fds[0], buffer, sizeof buffer)) > 0;)
      message.append(buffer, static_cast<std::size_t>(n));
    break;
  }
  ::close(pipe_fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const std::string object = "object " + std::to_string(last) + ": ";
  if (WIFSIGNALED(status))
    throw data_error(path, object + "MRPT's deserializer crashed on this object (signal " +
                               std::to_string(WTERMSIG(status)) + "): not a valid MRPT object (malformed rawlog)");
  if (!message.empty()) {  // the child's DataError (ObjectReader names the object), without "file: "
    const std::string prefix = path.string() + ": ";
    throw data_error(path, message.rfind(prefix, 0) == 0 ? message.substr(prefix.size()) : message);
  }
  if (!read_all || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw data_error(path, object + "the guarded read of the rawlog in a child process ended without reading it (" +
                               (WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                                  : std::string("no exit status")) +
                               "): not a valid MRPT object (malformed rawlog)");
}

// Writes a gzip'ed rawlog into the staged temporary file of an output planned in an OutputSet
// (framework/output_set.hpp: the checks of every output, its hidden temporary file, nothing left
// behind unless the set is committed). close() before the set commits.
class RawlogWriter {
 public:
  RawlogWriter(OutputSet& outputs, const fs::path& path) {
    const fs::path temp = outputs.stage_path(path);
    if (!out_.open(temp.string()))
      throw data_error(path, "cannot write the rawlog (temporary file " + temp.string() + ")");
  }
  void write(const mrpt::serialization::CSerializable& object) {
    auto archive = mrpt::serialization::archiveFrom(out_);
    archive << object;
  }
  void close() { out_.close(); }

 private:
  mrpt::io::CFileGZOutputStream out_;
};

mrpt::Clock::time_point time_point_of(double start_unix_s, double t_s) {
  const auto start = static_cast<std::int64_t>(std::llround(start_unix_s * kTicksPerSecond)) + kUnixEpochTicks;
  return mrpt::Clock::time_point(mrpt::Clock::duration(start + std::llround(t_s * kTicksPerSecond)));
}

// IMU observations of one sensor label, collected while reading.
struct Collected {
  std::vector<std::int64_t> ticks;
  std::vector<int> fields;  // present in the first observation, imu_columns() order
  std::vector<std::vector<double>> values;
  bool odometry = false, speed = false;
  std::vector<double> dx, dy, dphi, v;
  std::optional<mrpt::poses::CPose2D> pending;  // odometry since the previous IMU observation
  double pending_speed = 0.0;
};

std::string field_name(int field) {
  for (const auto& c : imu_columns())
    if (c.field == field) return c.column;
  return std::to_string(field);
}

// A present IMU field's value; DataError naming the object and the field when it is NaN or infinite
// (a CSV or a correction could not use it).
double finite_field(const CObservationIMU& imu, int field, const fs::path& path, std::size_t k, int j) {
  const double v = imu.get(static_cast<mrpt::obs::TIMUDataIndex>(field));
  if (!std::isfinite(v))
    throw data_error(path, index_text(k, j) + "IMU observation '" + imu.sensorLabel + "': " + field_name(field) +
                               " is " + (std::isnan(v) ? "NaN" : "infinite") + "; expected a finite number");
  return v;
}

// Walks a rawlog: on_observation(obs, object index, index in frame or -1), on_action(action, index).
struct Walker {
  RawlogStats stats;
  std::set<std::string> labels;
  bool saw_frames = false, saw_observations = false;

  template <class OnObs, class OnAct, class OnObject>
  void walk(const fs::path& path, OnObs&& on_observation, OnAct&& on_action, OnObject&& on_object) {
    check_data_input(path);
    read_in_child_first(path);
    ObjectReader reader(path);
    while (auto object = reader.next()) {
      const std::size_t k = reader.index();
      if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(object)) {
        saw_frames = true;
        ++stats.sensory_frames;
        int j = 0;
        for (const auto& obs : *sf) count(obs), on_observation(obs, k, j++);
      } else if (auto acts = std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(object)) {
        saw_frames = true;
        for (std::size_t a = 0; a < acts->size(); ++a) {
          auto action = acts->get(a);
          if (auto odo = std::dynamic_pointer_cast<mrpt::obs::CActionRobotMovement2D>(action)) {
            ++stats.odometry_actions;
            on_action(*odo, k);
          }
        }
      } else if (auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(object)) {
        saw_observations = true;
        count(obs);
        on_observation(obs, k, -1);
      }
      on_object(object, k);
    }
    stats.objects = reader.count();
    stats.format = saw_frames && saw_observations ? "mixed"
                   : saw_frames                   ? "actions/sensory-frame"
                                                  : "observations-only";
    stats.imu_labels.assign(labels.begin(), labels.end());
  }
  void count(const mrpt::obs::CObservation::Ptr& obs) {
    if (auto imu = std::dynamic_pointer_cast<CObservationIMU>(obs)) {
      ++stats.imu_observations;
      labels.insert(imu->sensorLabel);
    }
  }
};

std::string choose_label(const fs::path& path, const std::vector<std::string>& labels, const std::string& wanted) {
  if (!wanted.empty()) {
    if (std::find(labels.begin(), labels.end(), wanted) == labels.end()) {
      std::string all;
      for (const auto& l : labels) all += (all.empty() ? "" : ", ") + ("'" + l + "'");
      throw ConfigError(
          Location{path.string(), 0, "--sensor-label"},
          "no IMU observation labelled '" + wanted + "'; IMU labels in the file: " + (all.empty() ? "none" : all));
    }
    return wanted;
  }
  if (labels.empty()) throw data_error(path, "the rawlog has no CObservationIMU objects");
  if (labels.size() > 1) {
    std::string all;
    for (const auto& l : labels) all += (all.empty() ? "" : ", ") + ("'" + l + "'");
    throw ConfigError(
        Location{path.string(), 0, "--sensor-label"},
        "the rawlog has IMU observations of several sensors (" + all + "); choose one with --sensor-label");
  }
  return labels.front();
}

}  // namespace

const std::vector<ImuColumn>& imu_columns() {
  using namespace mrpt::obs;
  static const std::vector<ImuColumn> columns{
      {IMU_WZ, "IMU_WZ", "rate_rps", "rad/s", "yaw rate about the sensor z axis (IMU_WZ), rad/s"},
      {IMU_TEMPERATURE, "IMU_TEMPERATURE", "temp_c", "degC", "sensor temperature (IMU_TEMPERATURE), degC"},
      {IMU_WX, "IMU_WX", "wx_rps", "rad/s", "roll rate (IMU_WX), rad/s"},
      {IMU_WY, "IMU_WY", "wy_rps", "rad/s", "pitch rate (IMU_WY), rad/s"},
      {IMU_X_ACC, "IMU_X_ACC", "acc_x_mps2", "1", "acceleration x (IMU_X_ACC), m/s^2"},
      {IMU_Y_ACC, "IMU_Y_ACC", "acc_y_mps2", "1", "acceleration y (IMU_Y_ACC), m/s^2"},
      {IMU_Z_ACC, "IMU_Z_ACC", "acc_z_mps2", "1", "acceleration z (IMU_Z_ACC), m/s^2"},
      {IMU_X_VEL, "IMU_X_VEL", "vel_x_mps", "1", "velocity x (IMU_X_VEL), m/s"},
      {IMU_Y_VEL, "IMU_Y_VEL", "vel_y_mps", "1", "velocity y (IMU_Y_VEL), m/s"},
      {IMU_Z_VEL, "IMU_Z_VEL", "vel_z_mps", "1", "velocity z (IMU_Z_VEL), m/s"},
      {IMU_YAW, "IMU_YAW", "yaw_rad", "1", "yaw (IMU_YAW), rad"},
      {IMU_PITCH, "IMU_PITCH", "pitch_rad", "1", "pitch (IMU_PITCH), rad"},
      {IMU_ROLL, "IMU_ROLL", "roll_rad", "1", "roll (IMU_ROLL), rad"},
      {IMU_X, "IMU_X", "pos_x_m", "1", "position x (IMU_X), m"},
      {IMU_Y, "IMU_Y", "pos_y_m", "1", "position y (IMU_Y), m"},
      {IMU_Z, "IMU_Z", "pos_z_m", "1", "position z (IMU_Z), m"},
      {IMU_MAG_X, "IMU_MAG_X", "mag_x_gauss", "1", "magnetic field x (IMU_MAG_X), gauss"},
      {IMU_MAG_Y, "IMU_MAG_Y", "mag_y_gauss", "1", "magnetic field y (IMU_MAG_Y), gauss"},
      {IMU_MAG_Z, "IMU_MAG_Z", "mag_z_gauss", "1", "magnetic field z (IMU_MAG_Z), gauss"},
      {IMU_PRESSURE, "IMU_PRESSURE", "pressure_pa", "1", "air pressure (IMU_PRESSURE), Pa"},
      {IMU_ALTITUDE, "IMU_ALTITUDE", "altitude_m", "1", "altitude (IMU_ALTITUDE), m"},
      {IMU_ORI_QUAT_X, "IMU_ORI_QUAT_X", "quat_x", "1", "orientation quaternion x (IMU_ORI_QUAT_X)"},
      {IMU_ORI_QUAT_Y, "IMU_ORI_QUAT_Y", "quat_y", "1", "orientation quaternion y (IMU_ORI_QUAT_Y)"},
      {IMU_ORI_QUAT_Z, "IMU_ORI_QUAT_Z", "quat_z", "1", "orientation quaternion z (IMU_ORI_QUAT_Z)"},
      {IMU_ORI_QUAT_W, "IMU_ORI_QUAT_W", "quat_w", "1", "orientation quaternion w (IMU_ORI_QUAT_W)"},
      {IMU_YAW_VEL_GLOBAL, "IMU_YAW_VEL_GLOBAL", "wz_global_rps", "rad/s",
       "global yaw rate (IMU_YAW_VEL_GLOBAL), rad/s"},
      {IMU_PITCH_VEL_GLOBAL, "IMU_PITCH_VEL_GLOBAL", "wy_global_rps", "rad/s",
       "global pitch rate (IMU_PITCH_VEL_GLOBAL), rad/s"},
      {IMU_ROLL_VEL_GLOBAL, "IMU_ROLL_VEL_GLOBAL", "wx_global_rps", "rad/s",
       "global roll rate (IMU_ROLL_VEL_GLOBAL), rad/s"},
      {IMU_X_ACC_GLOBAL, "IMU_X_ACC_GLOBAL", "acc_x_global_mps2", "1",
       "global acceleration x (IMU_X_ACC_GLOBAL), m/s^2"},
      {IMU_Y_ACC_GLOBAL, "IMU_Y_ACC_GLOBAL", "acc_y_global_mps2", "1",
       "global acceleration y (IMU_Y_ACC_GLOBAL), m/s^2"},
      {IMU_Z_ACC_GLOBAL, "IMU_Z_ACC_GLOBAL", "acc_z_global_mps2", "1",
       "global acceleration z (IMU_Z_ACC_GLOBAL), m/s^2"},
  };
  return columns;
}

const std::vector<ImuColumn>& odometry_columns() {
  static const std::vector<ImuColumn> columns{
      {-1, "", "odom_dx_m", "1", "odometry increment since the previous IMU sample, robot frame x, m"},
      {-1, "", "odom_dy_m", "1", "odometry increment, robot frame y, m"},
      {-1, "", "odom_dphi_rad", "1", "odometry heading increment, rad"},
      {-1, "", "odom_speed_mps", "1", "odometry forward speed (velocityLocal.vx), m/s"},
  };
  return columns;
}

bool ImuTable::has(const std::string& column) const {
  return std::any_of(columns.begin(), columns.end(), [&](const CsvColumn& c) { return c.name == column; });
}

const Eigen::VectorXd& ImuTable::values(const std::string& column) const {
  for (const auto& c : columns)
    if (c.name == column) return c.values;
  throw DataError(Location{"", 0, column}, "the IMU record has no column '" + column + "'");
}

ImuTable read_imu_csv(const fs::path& path) {
  // The header decides the mapping: every column must be one the bridge knows. One read of the
  // text (read_text_file: a regular file, its memory estimated first), the CSV reader's line rule.
  const std::string text = read_text_file(path);
  CsvLineCursor cursor(text);
  std::string_view header;
  if (!cursor.next(header)) throw DataError(Location{path.string(), 0, ""}, "empty file: no header row");
  const int line = cursor.line_number();
  std::vector<std::string> names;
  for (const auto cell : split_csv_row(header)) names.emplace_back(cell);
  CsvReadOptions options;
  options.max_gap_factor = 0.0;
  options.required_roles = {"rate"};
  bool have_time = false, have_rate = false;
  std::vector<std::pair<std::string, std::string>> wanted;  // role -> output column
  std::vector<std::string> ignored;
  for (const auto& name : names) {
    if (name == "t_s") {
      options.columns.push_back({"time", name, "s"});
      have_time = true;
      continue;
    }
    if (name == "rate_dps" || name == "rate_rps") {
      if (have_rate)
        throw DataError(Location{path.string(), line, name}, "two yaw-rate columns (rate_dps and rate_rps)");
      options.columns.push_back({"rate", name, name == "rate_dps" ? "deg/s" : "rad/s"});
      wanted.emplace_back("rate", "rate_rps");
      have_rate = true;
      continue;
    }
    const ImuColumn* known = nullptr;
    for (const auto* table : {&imu_columns(), &odometry_columns()})
      for (const auto& c : *table)
        if (c.column == name) known = &c;
    if (!known) {
      ignored.push_back(name);
      continue;
    }
    const std::string role = known->column == "temp_c" ? "temperature" : known->column;
    options.columns.push_back({role, name, known->unit});
    wanted.emplace_back(role, known->column);
  }
  if (!have_time) throw DataError(Location{path.string(), line, "t_s"}, "missing time column t_s");
  if (!have_rate)
    throw DataError(Location{path.string(), line, "rate_rps"}, "missing yaw-rate column rate_rps or rate_dps");
  const TimeSeries series = parse_csv(text, path.string(), options);

  ImuTable table;
  table.ignored_columns = ignored;
  table.time_s = series.time();
  // CSV order: imu_columns() order, then odometry
  for (const auto* list : {&imu_columns(), &odometry_columns()})
    for (const auto& c : *list)
      for (const auto& [role, column] : wanted)
        if (column == c.column) table.columns.push_back({column, series.channel(role).values, "1"});
  if (table.has("odom_dx_m") != table.has("odom_dy_m") || table.has("odom_dx_m") != table.has("odom_dphi_rad"))
    throw DataError(Location{path.string(), line, "odom_dx_m"},
                    "odometry needs all of odom_dx_m, odom_dy_m and odom_dphi_rad");
  if (table.has("odom_speed_mps") && !table.has("odom_dx_m"))
    throw DataError(Location{path.string(), line, "odom_speed_mps"},
                    "odom_speed_mps needs the odometry increments odom_dx_m, odom_dy_m, odom_dphi_rad");
  return table;
}

void write_imu_csv(const ImuTable& table, OutputSet& outputs, const fs::path& path) {
  std::vector<CsvColumn> columns{{"t_s", table.time_s, "s"}};
  for (const auto& c : table.columns) columns.push_back(c);
  outputs.write_csv(path, columns);
}

namespace {

// One walk of the rawlog: the table of every IMU label (of `sensor_label` only, when given).
std::map<std::string, ImuTable> import_tables(const fs::path& path, const std::string& sensor_label,
                                              RawlogStats* stats_out) {
  std::map<std::string, Collected> by_label;
  bool any_odometry = false, any_speed = false;
  std::optional<mrpt::poses::CPose2D> unseen_pending;  // odometry before a label's first observation
  double unseen_speed = 0.0;
  Walker walker;
  walker.walk(
      path,
      [&](const mrpt::obs::CObservation::Ptr& obs, std::size_t k, int j) {
        auto imu = std::dynamic_pointer_cast<CObservationIMU>(obs);
        if (!imu || (!sensor_label.empty() && imu->sensorLabel != sensor_label)) return;
        auto& c = by_label[imu->sensorLabel];
        if (!imu->has(mrpt::obs::IMU_WZ))
          throw data_error(path,
                           index_text(k, j) + "IMU observation '" + imu->sensorLabel + "' has no yaw rate (IMU_WZ)");
        const auto ticks = ticks_of(imu->timestamp);
        if (!c.ticks.empty() && ticks <= c.ticks.back())
          throw data_error(path, index_text(k, j) + "IMU observation '" + imu->sensorLabel +
                                     "' is not later than the previous one (time stamps must increase)");
        if (c.ticks.empty()) {
          c.pending = unseen_pending;
          c.pending_speed = unseen_speed;
          for (const auto& col : imu_columns())
            if (imu->has(static_cast<mrpt::obs::TIMUDataIndex>(col.field))) c.fields.push_back(col.field);
          c.values.resize(c.fields.size());
        }
        for (const auto& col : imu_columns()) {
          const auto f = static_cast<mrpt::obs::TIMUDataIndex>(col.field);
          const bool expected = std::find(c.fields.begin(), c.fields.end(), col.field) != c.fields.end();
          if (expected && !imu->has(f))
            throw data_error(path, index_text(k, j) + "IMU observation '" + imu->sensorLabel + "' lacks " +
                                       field_name(col.field) + ", which the first one has");
        }
        for (std::size_t i = 0; i < c.fields.size(); ++i)
          c.values[i].push_back(finite_field(*imu, c.fields[i], path, k, j));
        c.ticks.push_back(ticks);
        const mrpt::poses::CPose2D inc = c.pending.value_or(mrpt::poses::CPose2D());
        c.dx.push_back(inc.x());
        c.dy.push_back(inc.y());
        c.dphi.push_back(inc.phi());
        c.v.push_back(c.pending_speed);
        c.pending.reset();
      },
      [&](const mrpt::obs::CActionRobotMovement2D& odo, std::size_t k) {
        any_odometry = true;
        const auto& inc = odo.rawOdometryIncrementReading;
        if (!std::isfinite(inc.x()) || !std::isfinite(inc.y()) || !std::isfinite(inc.phi()) ||
            (odo.hasVelocities && !std::isfinite(odo.velocityLocal.vx)))
          throw data_error(path, index_text(k, -1) +
                                     "an odometry increment or speed is not finite (NaN or infinite); "
                                     "expected finite numbers");
        for (auto& [label, c] : by_label) c.pending = c.pending ? *c.pending + inc : inc;
        unseen_pending = unseen_pending ? *unseen_pending + inc : inc;
        if (odo.hasVelocities) {
          any_speed = true;
          for (auto& [label, c] : by_label) c.pending_speed = odo.velocityLocal.vx;
          unseen_speed = odo.velocityLocal.vx;
        }
      },
      [](const auto&, std::size_t) {});
  if (stats_out) *stats_out = walker.stats;
  std::map<std::string, ImuTable> tables;
  for (auto& [label, c] : by_label) {
    ImuTable& table = tables[label];
    table.sensor_label = label;
    const auto n = static_cast<Eigen::Index>(c.ticks.size());
    table.time_s.resize(n);
    const std::int64_t t0 = c.ticks.front();
    for (Eigen::Index i = 0; i < n; ++i) table.time_s[i] = static_cast<double>(c.ticks[i] - t0) / kTicksPerSecond;
    table.start_unix_s = static_cast<double>(t0 - kUnixEpochTicks) / kTicksPerSecond;
    auto vec = [](const std::vector<double>& v) {
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(v.data(), v.size()));
    };
    for (std::size_t i = 0; i < c.fields.size(); ++i)
      table.columns.push_back({field_name(c.fields[i]), vec(c.values[i]), "1"});
    if (any_odometry) {
      table.columns.push_back({"odom_dx_m", vec(c.dx), "1"});
      table.columns.push_back({"odom_dy_m", vec(c.dy), "1"});
      table.columns.push_back({"odom_dphi_rad", vec(c.dphi), "1"});
      if (any_speed) table.columns.push_back({"odom_speed_mps", vec(c.v), "1"});
    }
    c = Collected{};
  }
  return tables;
}

}  // namespace

ImuTable import_rawlog(const fs::path& path, const std::string& sensor_label, RawlogStats* stats_out) {
  RawlogStats stats;
  auto tables = import_tables(path, sensor_label, &stats);
  if (stats_out) *stats_out = stats;
  return std::move(tables.at(choose_label(path, stats.imu_labels, sensor_label)));
}

std::vector<ImuTable> import_rawlog_sensors(const fs::path& path, RawlogStats* stats) {
  auto tables = import_tables(path, "", stats);
  std::vector<ImuTable> out;
  for (auto& [label, table] : tables) out.push_back(std::move(table));
  return out;
}

void export_rawlog(const ImuTable& table, const fs::path& path) {
  OutputSet outputs;
  outputs.plan(path, "");
  export_rawlog(table, outputs, path);
  outputs.commit();
}

void export_rawlog(const ImuTable& table, OutputSet& outputs, const fs::path& path) {
  const Eigen::Index n = table.time_s.size();
  if (n == 0) throw data_error(path, "nothing to export: the IMU record is empty");
  constexpr double kMaxTicks = 4e18;  // 100-ns ticks since 1601: about year 14 000, well inside int64
  for (const double t : {table.start_unix_s + table.time_s[0], table.start_unix_s + table.time_s[n - 1]})
    if (!(t * kTicksPerSecond + static_cast<double>(kUnixEpochTicks) >= 0.0 &&
          t * kTicksPerSecond + static_cast<double>(kUnixEpochTicks) <= kMaxTicks))
      throw ConfigError(Location{path.string(), 0, "--start-unix"},
                        "the time stamps (start Unix time plus t_s) fall outside MRPT's clock; expected finite "
                        "times from 1601 to about year 14000");
  std::vector<std::pair<mrpt::obs::TIMUDataIndex, const Eigen::VectorXd*>> fields;
  for (const auto& col : imu_columns())
    if (table.has(col.column))
      fields.emplace_back(static_cast<mrpt::obs::TIMUDataIndex>(col.field), &table.values(col.column));
  const bool odometry = table.has_odometry();
  const bool speed = table.has("odom_speed_mps");

  RawlogWriter writer(outputs, path);
  mrpt::obs::CActionRobotMovement2D::TMotionModelOptions motion;  // MRPT's default Gaussian model
  for (Eigen::Index i = 0; i < n; ++i) {
    auto obs = CObservationIMU::Create();
    obs->sensorLabel = table.sensor_label;
    obs->timestamp = time_point_of(table.start_unix_s, table.time_s[i]);
    for (const auto& [field, values] : fields) obs->set(field, (*values)[i]);
    if (odometry) {
      mrpt::obs::CActionRobotMovement2D move;
      move.timestamp = obs->timestamp;
      move.computeFromOdometry(mrpt::poses::CPose2D(table.values("odom_dx_m")[i], table.values("odom_dy_m")[i],
                                                    table.values("odom_dphi_rad")[i]),
                               motion);
      if (speed) {
        move.hasVelocities = true;
        move.velocityLocal = mrpt::math::TTwist2D(table.values("odom_speed_mps")[i], 0.0, 0.0);
      }
      mrpt::obs::CActionCollection actions;
      actions.insert(move);
      writer.write(actions);
      mrpt::obs::CSensoryFrame frame;
      frame.insert(obs);
      writer.write(frame);
    } else {
      writer.write(*obs);
    }
  }
  writer.close();
}

RawlogStats rawlog_stats(const fs::path& path) {
  Walker walker;
  walker.walk(
      path, [](const auto&, std::size_t, int) {}, [](const auto&, std::size_t) {}, [](const auto&, std::size_t) {});
  return walker.stats;
}

int imu_field(imu::Sensor sensor, char axis) {
  using namespace mrpt::obs;
  const bool gyro = sensor == imu::Sensor::Gyro;
  switch (axis) {
    case 'x':
      return gyro ? IMU_WX : IMU_X_ACC;
    case 'y':
      return gyro ? IMU_WY : IMU_Y_ACC;
    case 'z':
      return gyro ? IMU_WZ : IMU_Z_ACC;
    default:
      throw ConfigError(Location{"", 0, "axis"}, std::string("no CObservationIMU field for axis '") + axis + "'");
  }
}

std::string imu_field_name(int field) {
  for (const auto& c : imu_columns())
    if (c.field == field) return c.field_name;
  return std::to_string(field);
}

CompensateStats compensate_rawlog(const fs::path& in, const fs::path& out,
                                  const std::vector<FieldCorrection>& corrections, const std::string& sensor_label) {
  OutputSet outputs({in});
  outputs.plan(out, "");  // checked (and its temporary file made) before the input is read
  const CompensateStats stats = compensate_rawlog(in, outputs, out, corrections, sensor_label);
  outputs.commit();
  return stats;
}

CompensateStats compensate_rawlog(const fs::path& in, OutputSet& outputs, const fs::path& out,
                                  const std::vector<FieldCorrection>& corrections, const std::string& sensor_label) {
  RawlogWriter writer(outputs, out);
  if (corrections.empty())
    throw ConfigError(Location{in.string(), 0, ""}, "nothing to compensate: no field correction given");
  std::set<int> corrected;
  for (const auto& c : corrections)
    if (!corrected.insert(c.field).second)
      throw ConfigError(Location{in.string(), 0, ""}, imu_field_name(c.field) + " is corrected twice");
  const RawlogStats stats = rawlog_stats(in);
  const std::string label = choose_label(in, stats.imu_labels, sensor_label);

  CompensateStats result;
  result.sensor_label = label;
  for (const auto& c : corrections) result.fields.push_back({c.field, c.source, 0.0});
  std::set<int> passed;
  std::optional<std::int64_t> t0;
  auto fix = [&](const mrpt::obs::CObservation::Ptr& obs, std::size_t k, int j) {
    auto imu = std::dynamic_pointer_cast<CObservationIMU>(obs);
    if (!imu) return;
    ++result.imu_observations;
    if (imu->sensorLabel != label) return;
    for (const auto& c : corrections)
      if (!imu->has(static_cast<mrpt::obs::TIMUDataIndex>(c.field)))
        throw data_error(in, index_text(k, j) + "IMU observation '" + label + "' has no " + imu_field_name(c.field) +
                                 ", which " + c.source + " corrects");
    if (!imu->has(mrpt::obs::IMU_TEMPERATURE))
      throw data_error(in, index_text(k, j) + "IMU observation '" + label +
                               "' has no temperature (IMU_TEMPERATURE), which the calibration model needs");
    const auto ticks = ticks_of(imu->timestamp);
    if (!t0) t0 = ticks;
    const double t = static_cast<double>(ticks - *t0) / kTicksPerSecond;
    const double temp = finite_field(*imu, mrpt::obs::IMU_TEMPERATURE, in, k, j);
    for (std::size_t i = 0; i < corrections.size(); ++i) {
      const auto field = static_cast<mrpt::obs::TIMUDataIndex>(corrections[i].field);
      const double measured = finite_field(*imu, field, in, k, j);
      const double value = corrections[i].correct(t, measured, temp);
      imu->set(field, value);
      auto& worst = result.fields[i].max_abs_correction;
      worst = std::max(worst, std::abs(measured - value));
    }
    for (const auto& col : imu_columns())
      if (!corrected.count(col.field) && imu->has(static_cast<mrpt::obs::TIMUDataIndex>(col.field)))
        passed.insert(col.field);
    ++result.compensated;
  };

  ObjectReader reader(in);
  while (auto object = reader.next()) {
    const std::size_t k = reader.index();
    if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(object)) {
      int j = 0;
      for (const auto& obs : *sf) fix(obs, k, j++);
    } else if (auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(object)) {
      fix(obs, k, -1);
    }
    writer.write(*object);
  }
  result.objects = reader.count();
  for (const auto& col : imu_columns())
    if (passed.count(col.field)) result.passed_through.push_back(col.field);
  writer.close();
  return result;
}

}  // namespace driftlab::mrpt_bridge
