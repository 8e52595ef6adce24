#pragma once
/// \file
/// rosbag2 sqlite3 storage reader (ROS 2's default storage up to Humble)
/// with the shape of every bag reader (io/bag/message.hpp).
///
/// A bag is a folder with `metadata.yaml` and one or more `.db3` files (one
/// per split), or a single `.db3` path. Each file holds the tables
///     topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT,
///            serialization_format TEXT, offered_qos_profiles TEXT, ...)
///     messages(id INTEGER PRIMARY KEY, topic_id INTEGER, timestamp INTEGER,
///              data BLOB)
/// with `timestamp` the recorder's receive time [ns] and `data` the
/// serialised message (CDR with its encapsulation header for
/// serialization_format "cdr"). Which files: the `relative_file_paths` list
/// of metadata.yaml, read with a small line parser (the core does not need
/// yaml-cpp); without metadata.yaml every `*.db3` in the folder, sorted by
/// name. Files are opened read-only (SQLITE_OPEN_READONLY).
///
/// next() steps one `SELECT ... ORDER BY timestamp, id` statement per file
/// (SQLite streams the rows; blobs are never all loaded) and merges the files
/// by timestamp, ties in file order. Topics with the same name in several
/// files are one topic; topics of a serialization format other than "cdr"
/// are not listed. Errors name the file: IoError when a file cannot be
/// opened, FormatError when it is not a rosbag2 sqlite3 database (or, from
/// next(), when a corrupt timestamp index returns rows out of time order).
/// Thread safety: none (one reader per thread).

#include <sqlite3.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/bag/message.hpp>

namespace semlio::io {
namespace detail::sqlite_bag {

struct CloseDb {
  void operator()(sqlite3* db) const noexcept { sqlite3_close_v2(db); }
};
struct FinalizeStmt {
  void operator()(sqlite3_stmt* s) const noexcept { sqlite3_finalize(s); }
};
using Db = std::unique_ptr<sqlite3, CloseDb>;
using Stmt = std::unique_ptr<sqlite3_stmt, FinalizeStmt>;

/// Strips spaces and one pair of matching quotes.
inline std::string trim_yaml_scalar(std::string s) {
  const auto not_space = [](char c) { return c != ' ' && c != '\t' && c != '\r'; };
  s.erase(s.begin(), std::find_if(s.begin(), s.end(), not_space));
  s.erase(std::find_if(s.rbegin(), s.rend(), not_space).base(), s.end());
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front()) s = s.substr(1, s.size() - 2);
  return s;
}

/// The `relative_file_paths:` block list of a rosbag2 metadata.yaml
/// (`- name.db3` items, one per line, more indented than the key).
inline std::vector<std::string> relative_file_paths(const std::filesystem::path& yaml) {
  std::ifstream in(yaml);
  if (!in) throw IoError(yaml.string() + ": cannot open");
  std::vector<std::string> files;
  std::string line;
  std::size_t key_indent = std::string::npos;
  long line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::size_t indent = line.find_first_not_of(' ');
    if (indent == std::string::npos) continue;
    if (key_indent == std::string::npos) {
      if (line.compare(indent, 19, "relative_file_paths") == 0) {
        key_indent = indent;
        const std::size_t colon = line.find(':', indent);
        const std::string rest = colon == std::string::npos ? "" : trim_yaml_scalar(line.substr(colon + 1));
        if (!rest.empty()) {
          throw FormatError(semlio::detail::where(yaml.string(), line_no,
                                                  "relative_file_paths is '" + rest + "', expected a block list"));
        }
      }
      continue;
    }
    // The list ends at the first line that is not a "- item" at or below the key's indent.
    if (line[indent] != '-' || indent < key_indent) break;
    files.push_back(trim_yaml_scalar(line.substr(indent + 1)));
  }
  if (files.empty()) {
    throw FormatError(yaml.string() + ": no relative_file_paths list (is this a rosbag2 metadata.yaml?)");
  }
  return files;
}

/// One open .db3 file and its cursor.
struct File {
  std::string path;
  Db db;
  std::map<std::int64_t, std::size_t> topic_of_id;  ///< topics.id -> reader topic index (readable topics)
  Stmt stmt;                                        ///< the running SELECT (null: nothing selected here)
  bool has_row = false;                             ///< stmt is on a row not yet handed out
  /// Timestamp of the row of stmt handed out last: rows must not go back in
  /// time (a corrupt timestamp index can return them out of order).
  std::int64_t last_time_ns = std::numeric_limits<std::int64_t>::min();
};

}  // namespace detail::sqlite_bag

/// Reads a rosbag2 sqlite3 bag's messages in timestamp order (see the file comment).
class SqliteBagReader {
 public:
  /// Opens a bag folder or a single .db3 file. Throws IoError when a file
  /// cannot be opened, FormatError when it is not a rosbag2 sqlite3 bag.
  explicit SqliteBagReader(const std::string& path) : path_(path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    std::vector<fs::path> files;
    if (fs::is_directory(path, ec)) {
      const fs::path yaml = fs::path(path) / "metadata.yaml";
      if (fs::exists(yaml, ec)) {
        for (const std::string& rel : detail::sqlite_bag::relative_file_paths(yaml)) {
          if (rel.size() < 4 || rel.compare(rel.size() - 4, 4, ".db3") != 0) {
            throw FormatError(yaml.string() + ": lists '" + rel +
                              "', not an sqlite3 .db3 file (an MCAP bag opens with McapReader; compressed "
                              "files are not supported)");
          }
          files.push_back(fs::path(path) / rel);
        }
      } else {
        for (const fs::directory_entry& e : fs::directory_iterator(path, ec)) {
          if (e.path().extension() == ".db3") files.push_back(e.path());
        }
        std::sort(files.begin(), files.end());
        if (files.empty()) throw IoError(path + ": no metadata.yaml and no .db3 file in the folder");
      }
    } else if (fs::exists(path, ec)) {
      files.emplace_back(path);
    } else {
      throw IoError(path + ": no such bag folder or .db3 file");
    }
    for (const fs::path& f : files) open_file(f.string());
    select({});
  }

  /// Opens one .db3 database held in memory (copied into SQLite's own buffer
  /// with sqlite3_deserialize, read-only; `name` stands for the path in error
  /// messages). Throws IoError when SQLite cannot take the bytes, FormatError
  /// when they are not a rosbag2 sqlite3 database.
  static SqliteBagReader from_bytes(std::string_view db3_bytes, const std::string& name) {
    SqliteBagReader r;
    r.path_ = name;
    r.open_memory(db3_bytes, name);
    r.select({});
    return r;
  }

  /// Topics of the bag (one per name, in the order of the files' topic ids).
  [[nodiscard]] const std::vector<BagTopic>& topics() const noexcept { return topics_; }

  /// Restarts reading with only these topics (empty: all). Throws ValueError
  /// for a name the bag does not have.
  void select(const std::vector<std::string>& topic_names) {
    std::vector<bool> want(topics_.size(), topic_names.empty());
    for (const std::string& name : topic_names) {
      const auto it = std::find_if(topics_.begin(), topics_.end(), [&](const BagTopic& t) { return t.name == name; });
      if (it == topics_.end()) {
        std::string have;
        for (const BagTopic& t : topics_) have += (have.empty() ? "" : ", ") + t.name;
        throw ValueError(path_ + ": no topic '" + name + "' in the bag (it has: " + have + ")");
      }
      want[static_cast<std::size_t>(it - topics_.begin())] = true;
    }
    for (detail::sqlite_bag::File& f : files_) {
      f.stmt.reset();
      f.has_row = false;
      f.last_time_ns = std::numeric_limits<std::int64_t>::min();
      std::string ids;
      for (const auto& [id, topic] : f.topic_of_id) {
        if (!want[topic]) continue;
        // Appends only: GCC 12 reports a false -Wrestrict on `"," + std::to_string(id)`.
        if (!ids.empty()) ids += ',';
        ids += std::to_string(id);
      }
      if (ids.empty()) continue;
      // rosbag2's timestamp_idx is on (timestamp) with the rowid (= id)
      // appended, so this order needs no sort.
      f.stmt = prepare(f, "SELECT topic_id, timestamp, data FROM messages WHERE topic_id IN (" + ids +
                              ") ORDER BY timestamp, id");
      step(f);
    }
  }

  /// The next selected message in timestamp order (ties in file order); false
  /// at the end. Throws FormatError when a file's rows go back in time.
  bool next(BagMessage& out) {
    detail::sqlite_bag::File* best = nullptr;
    std::int64_t best_time = 0;
    for (detail::sqlite_bag::File& f : files_) {
      if (!f.has_row) continue;
      const std::int64_t t = sqlite3_column_int64(f.stmt.get(), 1);
      if (best == nullptr || t < best_time) {
        best = &f;
        best_time = t;
      }
    }
    if (best == nullptr) return false;
    // ORDER BY timestamp walks rosbag2's timestamp index: a corrupt index (or
    // a non-integer timestamp, which SQLite sorts after every integer) yields
    // rows out of order, which would break the time order promised above.
    if (best_time < best->last_time_ns) {
      throw FormatError(best->path + ": message timestamp " + std::to_string(best_time) + " ns comes after " +
                        std::to_string(best->last_time_ns) +
                        " ns in timestamp order (a corrupt timestamp index or a non-integer timestamp)");
    }
    best->last_time_ns = best_time;
    sqlite3_stmt* s = best->stmt.get();
    const auto topic = best->topic_of_id.find(sqlite3_column_int64(s, 0));
    if (topic == best->topic_of_id.end()) {
      throw FormatError(best->path + ": message with an unselected topic id");  // the SQL filter makes this unreachable
    }
    out.topic = topic->second;
    out.log_time_ns = best_time;
    const void* blob = sqlite3_column_blob(s, 2);
    const int n = sqlite3_column_bytes(s, 2);
    const auto* p = static_cast<const std::uint8_t*>(blob);
    out.data.assign(p, p + (p == nullptr ? 0 : n));
    step(*best);
    return true;
  }

 private:
  [[noreturn]] static void fail_sql(const detail::sqlite_bag::File& f, const std::string& what) {
    throw FormatError(f.path + ": " + what + ": " + sqlite3_errmsg(f.db.get()) +
                      " (not a rosbag2 sqlite3 database?)");
  }

  static detail::sqlite_bag::Stmt prepare(const detail::sqlite_bag::File& f, const std::string& sql) {
    sqlite3_stmt* raw = nullptr;
    if (sqlite3_prepare_v2(f.db.get(), sql.c_str(), -1, &raw, nullptr) != SQLITE_OK) {
      sqlite3_finalize(raw);
      fail_sql(f, "cannot run '" + sql + "'");
    }
    return detail::sqlite_bag::Stmt(raw);
  }

  /// Advances f's statement; has_row says whether it is on a row.
  static void step(detail::sqlite_bag::File& f) {
    const int rc = sqlite3_step(f.stmt.get());
    if (rc == SQLITE_ROW) {
      f.has_row = true;
    } else if (rc == SQLITE_DONE) {
      f.has_row = false;
    } else {
      fail_sql(f, "reading messages");
    }
  }

  SqliteBagReader() = default;

  void open_file(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw IoError(path + ": no such .db3 file");
    detail::sqlite_bag::File f;
    f.path = path;
    sqlite3* raw = nullptr;
    const int rc = sqlite3_open_v2(path.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr);
    f.db.reset(raw);  // sqlite returns a handle (to close) even on failure
    if (rc != SQLITE_OK) {
      throw IoError(path + ": cannot open as sqlite3 database: " + (raw != nullptr ? sqlite3_errmsg(raw) : "out of memory"));
    }
    read_topics(std::move(f));
  }

  /// An in-memory database: an empty one, replaced by a read-only copy of `bytes`.
  void open_memory(std::string_view bytes, const std::string& name) {
    detail::sqlite_bag::File f;
    f.path = name;
    sqlite3* raw = nullptr;
    const int rc = sqlite3_open_v2(":memory:", &raw, SQLITE_OPEN_READWRITE, nullptr);
    f.db.reset(raw);
    if (rc != SQLITE_OK) {
      throw IoError(name + ": cannot open an in-memory sqlite3 database: " +
                    (raw != nullptr ? sqlite3_errmsg(raw) : "out of memory"));
    }
    // SQLite frees the copy when the connection closes (FREEONCLOSE); at
    // least one byte so that an empty input is a FormatError, not a failed malloc.
    const auto size = static_cast<sqlite3_int64>(bytes.size());
    auto* copy = static_cast<unsigned char*>(sqlite3_malloc64(bytes.empty() ? 1U : bytes.size()));
    if (copy == nullptr) throw IoError(name + ": out of memory copying " + std::to_string(bytes.size()) + " bytes");
    if (!bytes.empty()) std::memcpy(copy, bytes.data(), bytes.size());
    if (sqlite3_deserialize(raw, "main", copy, size, size,
                            SQLITE_DESERIALIZE_FREEONCLOSE | SQLITE_DESERIALIZE_READONLY) != SQLITE_OK) {
      throw IoError(name + ": sqlite3 cannot load the bytes as a database: " + sqlite3_errmsg(raw));
    }
    read_topics(std::move(f));
  }

  /// Reads the topics (and message counts) of an opened file and adds it.
  void read_topics(detail::sqlite_bag::File f) {
    // Topics and their message counts (topic_id precedes the blob in each
    // row, so the count does not read the message data).
    std::map<std::int64_t, std::size_t> counts;
    {
      const detail::sqlite_bag::Stmt s = prepare(f, "SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id");
      int r = 0;
      while ((r = sqlite3_step(s.get())) == SQLITE_ROW) {
        counts[sqlite3_column_int64(s.get(), 0)] = static_cast<std::size_t>(sqlite3_column_int64(s.get(), 1));
      }
      if (r != SQLITE_DONE) fail_sql(f, "counting messages");
    }
    const detail::sqlite_bag::Stmt s = prepare(f, "SELECT id, name, type, serialization_format FROM topics ORDER BY id");
    int r = 0;
    while ((r = sqlite3_step(s.get())) == SQLITE_ROW) {
      const std::int64_t id = sqlite3_column_int64(s.get(), 0);
      const auto text = [&](int col) {
        const unsigned char* t = sqlite3_column_text(s.get(), col);
        return t == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(t));
      };
      const std::string name = text(1);
      if (text(3) != "cdr") continue;  // MessageEncoding has no other ROS 2 format
      auto it = std::find_if(topics_.begin(), topics_.end(), [&](const BagTopic& t) { return t.name == name; });
      if (it == topics_.end()) {
        BagTopic t;
        t.name = name;
        t.type = text(2);
        t.encoding = MessageEncoding::kCdr;
        topics_.push_back(std::move(t));
        it = topics_.end() - 1;
      }
      const auto n = counts.find(id);
      if (n != counts.end()) it->message_count += n->second;
      f.topic_of_id[id] = static_cast<std::size_t>(it - topics_.begin());
    }
    if (r != SQLITE_DONE) fail_sql(f, "reading topics");
    files_.push_back(std::move(f));
  }

  std::string path_;
  std::vector<detail::sqlite_bag::File> files_;
  std::vector<BagTopic> topics_;
};

}  // namespace semlio::io
