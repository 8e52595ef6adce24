// libFuzzer entry point for every harness (scripts/fuzz.sh). One executable,
// semlio_fuzz, holds all harness bodies -- they share one heavy translation
// unit, compiled once -- and the environment variable SEMLIO_FUZZ_HARNESS
// (kitti_bin, pcd, ..., settings_yaml) selects the one a run fuzzes.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "harness_settings_yaml.hpp"
#include "harnesses.hpp"

namespace {

using Body = int (*)(const std::uint8_t*, std::size_t);

Body selected = nullptr;

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* name = std::getenv("SEMLIO_FUZZ_HARNESS");
  if (name != nullptr && std::strcmp(name, "settings_yaml") == 0) selected = semlio_fuzz::fuzz_settings_yaml;
  for (const semlio_fuzz::Harness& h : semlio_fuzz::kHarnesses) {
    if (name != nullptr && std::strcmp(name, h.name) == 0) selected = h.body;
  }
  if (selected == nullptr) {
    std::fprintf(stderr, "semlio_fuzz: set SEMLIO_FUZZ_HARNESS to one of:");
    for (const semlio_fuzz::Harness& h : semlio_fuzz::kHarnesses) std::fprintf(stderr, " %s", h.name);
    std::fprintf(stderr, " settings_yaml\n");
    std::exit(2);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) { return selected(data, size); }
