// semlio_convert: converts point clouds between KITTI .bin, PCD and PLY
// (by file extension). Labels travel where the formats carry them (PCD/PLY
// label field; a KITTI .label beside the .bin with --labels FILE).
//
//   semlio_convert IN OUT [--labels IN.label] [--ascii]
//
// Dataset mode (the first argument is an option): every frame of any input
// semlio_run reads into a KITTI-layout folder or a folder of PCDs
// (convert_dataset.hpp):
//
//   semlio_convert --input PATH --out DIR [--format F] [--lidar-topic T]
//                  [--imu-topic T] [--gt FILE] [--calib FILE] [--to kitti|pcd]
//                  [--first N] [--last N] [--overwrite]
//
// Exit 1 with a message naming the file for unreadable or invalid input, and
// for a scan with no valid point (all NaN/Inf or (0,0,0)) written as .bin:
// a KITTI .bin cannot hold an empty scan, so nothing is written. To .pcd and
// .ply such a scan is written with 0 points. Exit 2 for a bad command line.

#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>

#include <semlio/io/kitti.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/io/ply.hpp>

#include "convert_dataset.hpp"

namespace {

std::string extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (auto& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

int usage() {
  std::cerr << "usage: semlio_convert IN OUT [--labels IN.label] [--ascii]\n"
               "  formats by extension: .bin (KITTI), .pcd, .ply\n"
               "   or: semlio_convert --input PATH --out DIR [--to kitti|pcd] ... (a whole dataset; --help)\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::strncmp(argv[1], "--", 2) == 0) return semlio_examples::convert_dataset_main(argc, argv);
  if (argc < 3) return usage();
  const std::string in = argv[1];
  const std::string out = argv[2];
  std::optional<std::string> labels;
  bool ascii = false;
  for (int i = 3; i < argc; ++i) {
    if (std::strcmp(argv[i], "--labels") == 0 && i + 1 < argc) {
      labels = argv[++i];
    } else if (std::strcmp(argv[i], "--ascii") == 0) {
      ascii = true;
    } else {
      return usage();
    }
  }
  try {
    semlio::io::ReadStats stats;
    semlio::Scan scan;
    const std::string ein = extension(in);
    if (ein == ".bin") {
      scan = semlio::io::read_kitti_scan(in, labels, &stats);
    } else if (ein == ".pcd") {
      scan = semlio::io::read_pcd(in, &stats);
    } else if (ein == ".ply") {
      scan = semlio::io::read_ply(in, &stats);
    } else {
      return usage();
    }
    const std::string eout = extension(out);
    // A KITTI .bin cannot hold an empty scan (the reader rejects a 0-byte
    // file), so a scan whose every point was dropped is an error here, before
    // anything is written. PCD and PLY carry empty scans (0 points) and
    // read back as such.
    if (eout == ".bin" && scan.empty()) {
      std::cerr << "semlio_convert: " << in << ": no valid point to write to " << out << " ("
                << stats.dropped_nonfinite << " non-finite and " << stats.dropped_zero
                << " (0,0,0) points dropped); a KITTI .bin cannot hold an empty scan\n";
      return 1;
    }
    if (eout == ".bin") {
      semlio::io::write_kitti_bin(out, scan);
    } else if (eout == ".pcd") {
      semlio::io::write_pcd(out, scan, ascii ? semlio::io::PcdEncoding::kAscii : semlio::io::PcdEncoding::kBinary);
    } else if (eout == ".ply") {
      semlio::io::write_ply(out, scan, ascii ? semlio::io::PlyEncoding::kAscii
                                            : semlio::io::PlyEncoding::kBinaryLittleEndian);
    } else {
      return usage();
    }
    std::cout << "semlio_convert: " << in << " -> " << out << ": " << scan.size() << " points ("
              << stats.dropped_nonfinite << " non-finite and " << stats.dropped_zero
              << " (0,0,0) points dropped)\n";
    return 0;
  } catch (const semlio::Error& e) {
    std::cerr << "semlio_convert: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    // Last resort (e.g. std::bad_alloc): a message and exit 1, never an abort.
    std::cerr << "semlio_convert: unexpected error converting " << in << " to " << out << ": " << e.what() << "\n";
    return 1;
  }
}
