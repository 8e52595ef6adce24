#pragma once
// Shared pieces of the fuzz harnesses (tests/fuzz/harnesses.hpp): the
// invariant check that traps, and a per-process scratch directory for the
// one harness whose reader takes only a path (the YAML settings loader; every
// reader of include/semlio/io has an in-memory entry point the harnesses use).
//
// The harness bodies run both under libFuzzer (scripts/fuzz.sh, clang with
// -fsanitize=fuzzer,address,undefined) and in the regular GCC test build
// (tests/fuzz/replay.cmake replays the committed corpus and crash inputs).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>

namespace semlio_fuzz {

/// Stops the process when a documented invariant does not hold after a
/// successful read: libFuzzer saves the input as a crash, the replay test
/// fails (a trap is not an exception anyone could swallow).
inline void check(bool invariant_holds) {
  if (!invariant_holds) __builtin_trap();
}

/// Where scratch directories go: /dev/shm when it exists (tmpfs: a file
/// written per execution costs no disk I/O), else the system temp directory.
inline std::filesystem::path scratch_root() {
  std::error_code ec;
  if (std::filesystem::is_directory("/dev/shm", ec)) return "/dev/shm";
  return std::filesystem::temp_directory_path();
}

/// A scratch directory private to this process (<scratch_root>/semlio_fuzz_<pid>),
/// created on first use and removed at exit.
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d = scratch_root() / ("semlio_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(scratch_root() / ("semlio_fuzz_" + std::to_string(::getpid())), ec);
    });
    return d;
  }();
  return dir;
}

/// Path of `name` inside the scratch directory (parent folders created).
inline std::string scratch(const std::string& name) {
  const std::filesystem::path p = scratch_dir() / name;
  std::filesystem::create_directories(p.parent_path());
  return p.string();
}

/// Writes `bytes` to scratch file `name` (replacing it) and returns its path.
inline std::string write_scratch(const std::string& name, std::string_view bytes) {
  const std::string path = scratch(name);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  check(f != nullptr);
  if (!bytes.empty()) check(std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size());
  check(std::fclose(f) == 0);
  return path;
}

/// The fuzz input as a string view.
inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

}  // namespace semlio_fuzz
