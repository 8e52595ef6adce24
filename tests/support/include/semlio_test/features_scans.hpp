#pragma once
// Real scans prepared the way the front end sees them (rings inferred,
// preprocessed), for feature tests and benchmarks.
#include <string>

#include <semlio/core/scan.hpp>
#include <semlio/features/preprocess.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio_test/data.hpp>

namespace semlio_test {

/// Real KITTI odometry scan 00/<name> (e.g. "000000.bin"): rings from point
/// order (HDL-64E), default preprocessing.
inline semlio::Scan kitti_scan_with_rings(const std::string& name) {
  semlio::Scan scan = semlio::io::read_kitti_bin(data_path("kitti/sequences/00/velodyne/" + name));
  semlio::infer_rings(scan, semlio::SensorModel::hdl64e());
  semlio::preprocess(scan);
  return scan;
}

}  // namespace semlio_test
