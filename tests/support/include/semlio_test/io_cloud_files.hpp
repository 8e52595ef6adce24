#pragma once
// Scratch files for the PCD/PLY reader tests: a private temporary directory
// (removed on destruction) and whole-file byte helpers.
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

namespace semlio_test {

/// A fresh directory under the system temp dir, removed with its content on
/// destruction. The name carries a random suffix so parallel test runs do not
/// collide.
class CloudTempDir {
 public:
  explicit CloudTempDir(const std::string& tag) {
    std::random_device rd;
    const auto suffix = std::to_string(rd()) + "_" + std::to_string(rd());
    path_ = std::filesystem::temp_directory_path() / ("semlio_" + tag + "_" + suffix);
    std::filesystem::create_directories(path_);
  }
  CloudTempDir(const CloudTempDir&) = delete;
  CloudTempDir& operator=(const CloudTempDir&) = delete;
  ~CloudTempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }

  /// Absolute path of a file inside the directory.
  [[nodiscard]] std::string file(const std::string& name) const { return (path_ / name).string(); }

  /// Writes `bytes` to a file inside the directory and returns its path.
  std::string write(const std::string& name, const std::string& bytes) const {
    const std::string p = file(name);
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return p;
  }

 private:
  std::filesystem::path path_;
};

/// Whole file as bytes (empty string when it cannot be read).
inline std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace semlio_test
