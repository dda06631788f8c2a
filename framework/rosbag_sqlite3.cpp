#include <sqlite3.h>

#include <memory>
#include <unordered_map>

#include "framework/error.hpp"
#include "framework/rosbag_containers.hpp"

namespace driftlab::rosbag::detail {
namespace {

struct CloseDb {
  void operator()(sqlite3* db) const { sqlite3_close(db); }
};
struct Finalize {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};
using Statement = std::unique_ptr<sqlite3_stmt, Finalize>;

std::string column_text(sqlite3_stmt* s, int column) {
  const auto* p = sqlite3_column_text(s, column);
  return p ? std::string(reinterpret_cast<const char*>(p), static_cast<std::size_t>(sqlite3_column_bytes(s, column)))
           : "";
}

// A path as the path part of an sqlite URI: '?', '#' and '%' (and non-ASCII bytes) percent-encoded.
std::string percent_encoded(const std::string& path) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (const char ch : path) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '?' || c == '#' || c == '%' || c < 0x20 || c >= 0x7f) {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    } else {
      out += ch;
    }
  }
  return out;
}

class Database {
 public:
  // Opened as immutable (no locks, no -shm / -wal files created next to the bag) unless a -wal
  // file is there: then the bag was not closed cleanly and its last messages are in that file,
  // which sqlite reads only in the normal read-only mode (it may create the -shm file for it).
  explicit Database(const std::filesystem::path& path) : file_(path.string()) {
    std::error_code ec;
    const bool wal = std::filesystem::exists(file_ + "-wal", ec);
    const std::string uri =
        "file:" + percent_encoded(std::filesystem::absolute(path, ec).string()) + (wal ? "?mode=ro" : "?immutable=1");
    sqlite3* db = nullptr;
    const int rc =
        sqlite3_open_v2(uri.c_str(), &db, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX | SQLITE_OPEN_URI, nullptr);
    db_.reset(db);
    if (rc != SQLITE_OK) fail("cannot open it as an sqlite3 database");
  }

  Statement prepare(const std::string& sql, const std::string& purpose) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db_.get(), sql.c_str(), -1, &s, nullptr) != SQLITE_OK)
      fail("not a rosbag2 sqlite3 bag, or a corrupt one: cannot read " + purpose);
    return Statement(s);
  }

  // Steps `s`: true for a row, false at the end; DataError for a database error (corrupt pages).
  bool step(sqlite3_stmt* s, const std::string& purpose) {
    const int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail("while reading " + purpose);
  }

  [[noreturn]] void fail(const std::string& message) const {
    throw DataError({file_, 0, ""},
                    message + " (sqlite3: " + (db_ ? sqlite3_errmsg(db_.get()) : "out of memory") + ")");
  }

  const std::string& file() const { return file_; }

 private:
  std::string file_;
  std::unique_ptr<sqlite3, CloseDb> db_;
};

}  // namespace

void read_sqlite3(const std::filesystem::path& path, const Wanted& wanted, const Visitor& visit, Bag& bag) {
  Database db(path);
  std::error_code ec;
  bag.container = "ROS 2 bag, sqlite3 storage";
  bag.bytes = std::filesystem::file_size(path, ec);
  bag.files = {db.file()};

  std::unordered_map<std::int64_t, Topic> by_id;
  std::string wanted_ids;
  {
    const std::string purpose = "its topics table";
    auto s = db.prepare("SELECT id, name, type, serialization_format FROM topics", purpose);
    while (db.step(s.get(), purpose)) {
      const std::int64_t id = sqlite3_column_int64(s.get(), 0);
      Topic t{column_text(s.get(), 1), column_text(s.get(), 2), column_text(s.get(), 3), "", 0, 0, 0};
      if (wanted(t)) wanted_ids += (wanted_ids.empty() ? "" : ",") + std::to_string(id);
      if (!by_id.try_emplace(id, std::move(t)).second)
        db.fail("topic id " + std::to_string(id) + " appears twice in its topics table");
    }
  }
  {
    const std::string purpose = "the counts of its messages table";
    auto s = db.prepare("SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY topic_id",
                        purpose);
    while (db.step(s.get(), purpose)) {
      const std::int64_t id = sqlite3_column_int64(s.get(), 0);
      const auto it = by_id.find(id);
      if (it == by_id.end())
        db.fail("messages of topic id " + std::to_string(id) + ", which its topics table does not list");
      it->second.count = static_cast<std::uint64_t>(sqlite3_column_int64(s.get(), 1));
      it->second.first_ns = sqlite3_column_int64(s.get(), 2);
      it->second.last_ns = sqlite3_column_int64(s.get(), 3);
    }
  }
  if (!wanted_ids.empty()) {
    const std::string purpose = "its messages table";
    auto s = db.prepare(
        "SELECT topic_id, timestamp, data, id FROM messages WHERE topic_id IN (" + wanted_ids + ") ORDER BY id",
        purpose);
    while (db.step(s.get(), purpose)) {
      const Topic& t = by_id.at(sqlite3_column_int64(s.get(), 0));
      const auto* data = static_cast<const char*>(sqlite3_column_blob(s.get(), 2));
      const auto size = static_cast<std::size_t>(sqlite3_column_bytes(s.get(), 2));
      const std::int64_t row = sqlite3_column_int64(s.get(), 3);
      visit({&t, sqlite3_column_int64(s.get(), 1), std::string_view(data ? data : "", size),
             [row] { return "row " + std::to_string(row); }});
    }
  }
  for (auto& [id, t] : by_id) bag.topics.push_back(std::move(t));
}

}  // namespace driftlab::rosbag::detail
