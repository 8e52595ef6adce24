// libFuzzer entry point for every harness (scripts/fuzz.sh). One executable,
// semlio_fuzz, holds all harness bodies -- they share one heavy translation
// unit, compiled once -- and the environment variable SEMLIO_FUZZ_HARNESS
// (kitti_bin, pcd, ..., settings_yaml, and rosbag1 / mcap / sqlite_bag when
// built with the bag libraries: SEMLIO_FUZZ_BAGS) selects the one a run
// fuzzes; SEMLIO_FUZZ_HARNESS=list prints the names this build holds.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "harness_settings_yaml.hpp"
#include "harnesses.hpp"
#if defined(SEMLIO_FUZZ_BAGS)
#include "harnesses_bags.hpp"
#endif

namespace {

using Body = int (*)(const std::uint8_t*, std::size_t);

Body selected = nullptr;

/// Every harness of this build.
std::vector<semlio_fuzz::Harness> all_harnesses() {
  std::vector<semlio_fuzz::Harness> all(std::begin(semlio_fuzz::kHarnesses), std::end(semlio_fuzz::kHarnesses));
  all.push_back({"settings_yaml", semlio_fuzz::fuzz_settings_yaml});
#if defined(SEMLIO_FUZZ_BAGS)
  all.insert(all.end(), std::begin(semlio_fuzz::kBagHarnesses), std::end(semlio_fuzz::kBagHarnesses));
#endif
  return all;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* name = std::getenv("SEMLIO_FUZZ_HARNESS");
  const std::vector<semlio_fuzz::Harness> all = all_harnesses();
  if (name != nullptr && std::strcmp(name, "list") == 0) {
    for (const semlio_fuzz::Harness& h : all) std::printf("%s\n", h.name);
    std::exit(0);
  }
  for (const semlio_fuzz::Harness& h : all) {
    if (name != nullptr && std::strcmp(name, h.name) == 0) selected = h.body;
  }
  if (selected == nullptr) {
    std::fprintf(stderr, "semlio_fuzz: set SEMLIO_FUZZ_HARNESS to list or one of:");
    for (const semlio_fuzz::Harness& h : all) std::fprintf(stderr, " %s", h.name);
    std::fprintf(stderr, "\n");
    std::exit(2);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) { return selected(data, size); }
