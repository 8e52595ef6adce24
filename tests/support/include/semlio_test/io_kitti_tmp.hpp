#pragma once
// Scratch directories and small file helpers for the io/kitti tests.
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace semlio_test {

/// A fresh directory under the system temp dir, removed with its contents on
/// destruction. Unique per process and instance (ctest may run tests in parallel).
class KittiTempDir {
 public:
  explicit KittiTempDir(const std::string& tag = "io") {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("semlio_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~KittiTempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  KittiTempDir(const KittiTempDir&) = delete;
  KittiTempDir& operator=(const KittiTempDir&) = delete;

  /// Absolute path of `relative` inside the directory (parent dirs created).
  [[nodiscard]] std::string file(const std::string& relative) const {
    const std::filesystem::path p = path_ / relative;
    std::filesystem::create_directories(p.parent_path());
    return p.string();
  }
  /// The directory itself.
  [[nodiscard]] std::string str() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

/// Writes `content` to `path` (binary, replacing it).
inline void write_text(const std::string& path, std::string_view content) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return;
  std::fwrite(content.data(), 1, content.size(), f);
  std::fclose(f);
}

}  // namespace semlio_test
