// semlio_lio: lidar-inertial (or lidar-only) odometry on a KITTI-layout
// sequence with a KITTI raw oxts/ folder (a semlio_simulate drive writes one)
// and Tr_imu_velo in calib.txt. Writes OUT/poses.txt (KITTI camera-0 form
// when calib.txt has Tr, else lidar poses) and OUT/report.json (ATE when
// ground truth is found, IMU fallbacks, degeneracy along the road).
//
//   semlio_lio --sequence DIR --out DIR [--imu oxts|none] [--deskew on|off]
//              [--preset baseline|full] [--labels labels|predictions|none]
//              [--time-offset auto|SECONDS] [--first N] [--last N]
//              [--kitti-correction on|off|auto] [--velocity-hint auto|oxts|none]
//              [--degenerate-information none|remapped] [--reset-weak-directions auto|on|off]
//              [--velocity-factors on|off] [--trace FILE] [--quiet]
//
// --imu none: the lidar-only front end (constant velocity; --deskew on uses
// constant-velocity deskew). --time-offset auto: t_imu = t_lidar + offset with
// offset = first OXTS stamp - first scan stamp when the two clocks are more
// than 1000 s apart (the simulator's OXTS carries a date, times.txt starts at
// 0; both start together), else 0. --velocity-hint oxts (default with --imu
// oxts): the OXTS INS velocity (vf, vl, vu) guides the front end while the
// LIO initialises (LidarInertialOdometry::push_velocity) -- on a straight
// road entered at cruise speed nothing else observes the along-track motion.
// --imu none --velocity-hint oxts gives lidar-only the same start-up help
// for a fair comparison: the INS velocity (rotated into the lidar frame, no
// rotation) is its initial guess for the first init.min_frames frames (the
// LIO's shortest initialisation window), its constant-velocity model after.
// --reset-weak-directions (auto: on with --imu oxts, off for lidar-only):
// the scan-to-map solver puts directions its relative degeneracy test flags
// (a straight road's along-track axis) back at the prediction -- the IMU's,
// which is better there than the lidar's solution: on the simulated highway
// that one comes out short by ~5 % of the motion per frame (ring patterns on
// the flat ground pull it back), and the lidar-inertial graph gets no lidar
// information along those directions anyway.
// --velocity-factors on: the OXTS velocity also enters the inertial graph on
// every state (LidarInertialConfig::velocity_factors; INS-aided, not
// lidar-inertial alone; off by default).
// --trace FILE writes one line per frame (front-end, lidar-inertial,
// predicted and true positions, velocity, biases, gravity, the weakest
// direction); report.json holds the gravity error against the OXTS attitude
// of the first record.

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <semlio/eval/ate.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/imu/deskew.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/kitti_sequence.hpp>
#include <semlio/io/oxts.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/pipeline/lidar_inertial.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/segment/scan_labels.hpp>

#include "imu_oxts.hpp"
#include "json_writer.hpp"

namespace fs = std::filesystem;
using semlio::SE3d;

namespace {

struct Options {
  std::string sequence;
  std::string out;
  std::string imu = "oxts";
  std::string deskew = "off";
  std::string preset = "baseline";
  std::string labels = "labels";
  std::string time_offset = "auto";
  std::string kitti_correction = "auto";
  std::string velocity_hint = "auto";
  std::string degenerate_information = "none";
  std::string reset_weak = "auto";
  std::string velocity_factors = "off";
  std::string trace;
  std::string lidar_information = "hessian";
  double lidar_residual_sigma_m = -1.0;  // < 0: the library default
  double degeneracy_ratio = -1.0;        // < 0: the front end's default
  long first = 0;
  long last = -1;
  bool quiet = false;
};

// Facts kept per frame for the report.
struct FrameFacts {
  SE3d T_map_lidar;
  std::string status;
  bool degenerate = false;
  double degenerate_along_track = 0.0;  // |cos| between the weakest direction's translation and the motion
  bool imu_predicted = false;
  bool imu_fallback = false;
  double total_ms = 0.0;
};

// |cos| of the angle between the translation part of the weakest Hessian
// direction and the frame's motion (both in the lidar frame): the true motion
// when the sequence has ground truth (a front end that did not see the motion
// along the road has none to compare with), else the estimated one.
double along_track(const semlio::FrameReport& r, const SE3d& T_prev, const SE3d& T_cur) {
  const Eigen::Vector3d t = r.solve.eigenvectors.col(0).head<3>();
  const Eigen::Vector3d d = (T_prev.inverse() * T_cur).translation();
  if (t.norm() < 1e-9 || d.norm() < 1e-6) return 0.0;
  return std::abs(t.normalized().dot(d.normalized()));
}

// Sets the solver's relative degeneracy test when it has one.
template <typename SolverConfig>
bool set_degeneracy_ratio(SolverConfig& c, double ratio) {
  if constexpr (requires { c.degeneracy_ratio = ratio; }) {
    c.degeneracy_ratio = ratio;
    return true;
  } else {
    return false;
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"semlio_lio: lidar-inertial odometry on a KITTI-layout sequence with oxts/"};
  app.add_option("--sequence", opt.sequence, "sequence directory (velodyne/, calib.txt, times.txt, oxts/)")->required();
  app.add_option("--out", opt.out, "output directory")->required();
  app.add_option("--imu", opt.imu, "oxts: lidar-inertial; none: lidar-only")->check(CLI::IsMember({"oxts", "none"}));
  app.add_option("--deskew", opt.deskew, "deskew sweeps (raw data / --distortion on drives)")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_option("--preset", opt.preset, "front end: baseline or full")->check(CLI::IsMember({"baseline", "full"}));
  app.add_option("--labels", opt.labels, "label folder, or none")
      ->check(CLI::IsMember({"labels", "predictions", "none"}));
  app.add_option("--time-offset", opt.time_offset, "t_imu = t_lidar + offset [s], or auto");
  app.add_option("--kitti-correction", opt.kitti_correction, "KITTI vertical-angle fix (auto: off for sim.json drives)")
      ->check(CLI::IsMember({"on", "off", "auto"}));
  app.add_option("--first", opt.first, "first frame (inclusive)");
  app.add_option("--last", opt.last, "last frame (inclusive)");
  app.add_option("--velocity-hint", opt.velocity_hint,
                 "oxts: the INS velocity guides the front end while the LIO initialises (lidar-only: over the "
                 "first init.min_frames frames); none: no INS velocity; auto: oxts with --imu oxts, else none")
      ->check(CLI::IsMember({"auto", "oxts", "none"}));
  app.add_option("--degenerate-information", opt.degenerate_information,
                 "lidar information along degenerate directions: none (every flagged direction) or remapped "
                 "(none only where the solver froze the prediction)")
      ->check(CLI::IsMember({"none", "remapped"}));
  app.add_option("--reset-weak-directions", opt.reset_weak,
                 "scan-to-map solver: directions flagged by the relative degeneracy test stay at the prediction, "
                 "on frames with an IMU/INS prior or a constant-velocity-deskewed sweep (auto: on with --imu oxts)")
      ->check(CLI::IsMember({"auto", "on", "off"}));
  app.add_option("--velocity-factors", opt.velocity_factors,
                 "on: the OXTS velocity also constrains every inertial state (INS-aided)")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_option("--trace", opt.trace, "per-frame trace file (see the file comment)");
  app.add_option("--lidar-information", opt.lidar_information,
                 "front-end pose information in the inertial graph: hessian (scan-to-map Hessian, capped) or diagonal")
      ->check(CLI::IsMember({"hessian", "diagonal"}));
  app.add_option("--lidar-residual-sigma", opt.lidar_residual_sigma_m,
                 "residual sigma turning the Hessian into information [m] (default: the library's)");
  app.add_option("--degeneracy-ratio", opt.degeneracy_ratio,
                 "scan-to-map solver: degenerate when an eigenvalue is below this x the mean diagonal of its part "
                 "of H (when the solver supports it; default: the front end's)");
  app.add_flag("--quiet", opt.quiet, "no progress output");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  try {
    semlio::io::KittiSequenceConfig sc;
    sc.label_folder = opt.labels == "none" ? "" : opt.labels;
    const semlio::io::KittiSequence seq(opt.sequence, sc);
    const long n_frames = static_cast<long>(seq.size());
    const long last = opt.last < 0 ? n_frames - 1 : std::min(opt.last, n_frames - 1);
    if (opt.first < 0 || opt.first > last) {
      std::cerr << "semlio_lio: --first/--last select no frame of " << n_frames << "\n";
      return 2;
    }
    const auto first = static_cast<std::size_t>(opt.first);
    const auto last_u = static_cast<std::size_t>(last);
    const bool simulated = fs::exists(fs::path(seq.directory()) / "sim.json");
    const bool deskew = opt.deskew == "on";
    if (opt.velocity_hint == "auto") opt.velocity_hint = opt.imu == "oxts" ? "oxts" : "none";
    if (opt.reset_weak == "auto") opt.reset_weak = opt.imu == "oxts" ? "on" : "off";

    semlio::PipelineSettings settings;
    settings.odometry.kitti_vertical_correction =
        opt.kitti_correction == "on" || (opt.kitti_correction == "auto" && !simulated);

    // IMU and extrinsic.
    std::vector<semlio::ImuSample> imu;
    std::vector<semlio_examples::OxtsVelocity> velocities;
    semlio::LidarInertialConfig lc;
    lc.deskew = deskew;
    lc.velocity_factors = opt.velocity_factors == "on";
    if (lc.velocity_factors && opt.velocity_hint != "oxts") {
      std::cerr << "semlio_lio: --velocity-factors on needs --velocity-hint oxts\n";
      return 2;
    }
    lc.degenerate_information = opt.degenerate_information == "remapped" ? semlio::DegenerateInformation::kRemappedOnly
                                                                         : semlio::DegenerateInformation::kNone;
    lc.lidar_information =
        opt.lidar_information == "diagonal" ? semlio::LidarInformation::kDiagonal : semlio::LidarInformation::kHessian;
    if (opt.lidar_residual_sigma_m > 0.0) lc.lidar_residual_sigma_m = opt.lidar_residual_sigma_m;
    settings.odometry.solver.reset_weak_directions = opt.reset_weak == "on";
    if (opt.degeneracy_ratio >= 0.0) {
      if (!set_degeneracy_ratio(settings.odometry.solver, opt.degeneracy_ratio)) {
        std::cerr << "semlio_lio: this build's solver has no degeneracy_ratio; --degeneracy-ratio ignored\n";
      }
    }
    // Per-point times from the azimuth (.bin scans carry none): KITTI raw
    // sweeps start facing forward, the simulator's facing backwards; both spin
    // clockwise. A wrong start shifts half of every sweep by half a period.
    semlio::PointTimeConfig point_times;
    if (simulated) point_times.start_azimuth_rad = std::numbers::pi;
    lc.point_times = point_times;
    std::optional<Eigen::Vector3d> g_map_true;  // gravity in the map (first lidar) frame from the first OXTS attitude
    if (opt.imu == "oxts" || opt.velocity_hint == "oxts") {
      const std::vector<semlio::io::OxtsRecord> records =
          semlio::io::read_oxts((fs::path(seq.directory()) / "oxts").string());
      imu = semlio::io::imu_samples(records);
      if (opt.velocity_hint == "oxts") velocities = semlio_examples::oxts_velocities(records);
      if (!records.empty() && seq.calibration() && seq.calibration()->T_imu_velo) {
        const semlio::io::OxtsRecord& r0 = records.front();
        const Eigen::Matrix3d R_heading_imu = (Eigen::AngleAxisd(r0.pitch_rad, Eigen::Vector3d::UnitY()) *
                                               Eigen::AngleAxisd(r0.roll_rad, Eigen::Vector3d::UnitX()))
                                                  .toRotationMatrix();
        g_map_true = seq.calibration()->T_imu_velo->rotation().transpose() *
                     (R_heading_imu.transpose() * Eigen::Vector3d(0.0, 0.0, -lc.imu.gravity_world_mps2.norm()));
      }
      if (!seq.calibration() || !seq.calibration()->T_imu_velo) {
        std::cerr << "semlio_lio: " << seq.directory() << "/calib.txt has no Tr_imu_velo (lidar -> IMU extrinsic)\n";
        return 2;
      }
      lc.T_imu_lidar = *seq.calibration()->T_imu_velo;
      if (opt.time_offset == "auto") {
        const double d = imu.empty() ? 0.0 : imu.front().stamp_s - seq.stamp(first);
        lc.imu_time_offset_s = std::abs(d) > 1000.0 ? imu.front().stamp_s - seq.stamp(0) : 0.0;
      } else {
        lc.imu_time_offset_s = std::stod(opt.time_offset);
      }
    }

    std::vector<SE3d> gt_motion_ref;  // ground truth per frame (lidar), for the along-track measure
    if (seq.has_ground_truth()) gt_motion_ref = seq.ground_truth_lidar();
    // Motion reference of frame i: (previous pose, this pose), true when known.
    const auto motion_ref = [&](std::size_t i, const SE3d& T_prev_est, const SE3d& T_cur_est) {
      if (i > 0 && i < gt_motion_ref.size()) return std::pair<SE3d, SE3d>(gt_motion_ref[i - 1], gt_motion_ref[i]);
      return std::pair<SE3d, SE3d>(T_prev_est, T_cur_est);
    };
    std::vector<FrameFacts> facts;
    facts.reserve(last_u - first + 1);
    std::optional<std::size_t> init_frame;
    Eigen::Vector3d g_map_final = Eigen::Vector3d::Zero();  // the LIO's gravity after the last frame
    std::ofstream trace;
    if (!opt.trace.empty()) {
      trace.open(opt.trace);
      if (!trace) throw std::runtime_error("cannot write --trace " + opt.trace);
      trace << "# frame stamp status degenerate_dirs weakest_eigenvalue weak_t_x weak_t_y weak_t_z prediction deskew "
               "init fe_x fe_y fe_z est_x est_y est_z prior_x prior_y prior_z gt_x gt_y gt_z v_x v_y v_z "
               "bg_x bg_y bg_z ba_x ba_y ba_z g_x g_y g_z (positions: lidar in the map frame; v, g: map frame; "
               "v is the IMU's)\n";
      trace.precision(9);
    }
    // Ground truth of frame i relative to the first processed frame (nan when unknown).
    const auto gt_position = [&](std::size_t i) -> Eigen::Vector3d {
      if (i >= gt_motion_ref.size() || first >= gt_motion_ref.size()) return Eigen::Vector3d::Constant(std::nan(""));
      return (gt_motion_ref[first].inverse() * gt_motion_ref[i]).translation();
    };
    const auto write_trace = [&](std::size_t i, const semlio::FrameReport& fr, const SE3d& T_est,
                                 const std::optional<SE3d>& prior, const char* prediction, const char* deskew_src,
                                 const char* init, const semlio::NavState* x, const semlio::ImuBias* b,
                                 const Eigen::Vector3d& g) {
      if (!trace) return;
      const auto v3 = [&](const Eigen::Vector3d& v) { trace << ' ' << v.x() << ' ' << v.y() << ' ' << v.z(); };
      const Eigen::Vector3d nan3 = Eigen::Vector3d::Constant(std::nan(""));
      trace << i << ' ' << fr.stamp_s << ' ' << semlio::to_string(fr.status) << ' ' << fr.solve.degenerate_directions
            << ' ' << fr.solve.eigenvalues[0];
      v3(fr.solve.eigenvectors.col(0).head<3>());
      trace << ' ' << prediction << ' ' << deskew_src << ' ' << init;
      v3(fr.T_map_lidar.translation());
      v3(T_est.translation());
      v3(prior ? Eigen::Vector3d(prior->translation()) : nan3);
      v3(gt_position(i));
      v3(x ? x->v_world_mps : nan3);
      v3(b ? b->gyro_radps : nan3);
      v3(b ? b->accel_mps2 : nan3);
      v3(x ? g : nan3);
      trace << '\n';
    };
    const auto start = std::chrono::steady_clock::now();
    const auto run = [&](auto&& step) {
      for (std::size_t i = first; i <= last_u; ++i) {
        semlio::Scan scan = seq.read(i);
        facts.push_back(step(scan, i));
        if (!opt.quiet && (i - first) % 100 == 0) std::fprintf(stderr, "[semlio_lio] frame %zu/%zu\n", i, last_u);
      }
    };

    const auto run_front = [&](auto make) {
      if (opt.imu == "oxts") {
        semlio::LidarInertialOdometry lio(make, lc);
        std::size_t next = 0;
        std::size_t next_v = 0;
        SE3d T_prev;
        run([&](semlio::Scan& scan, std::size_t i) {
          const double until = scan.stamp_s + lc.imu_time_offset_s + lc.sweep_period_s + 1e-6;
          while (next < imu.size() && imu[next].stamp_s <= until) lio.push_imu(imu[next++]);
          // and the first sample after the sweep (semlio_run's ImuFeed: a 10 Hz IMU's next sample)
          if (next < imu.size() && (next == 0 || imu[next - 1].stamp_s <= until)) lio.push_imu(imu[next++]);
          while (next_v < velocities.size() && velocities[next_v].stamp_s <= until) {
            lio.push_velocity(velocities[next_v].stamp_s, velocities[next_v].v_imu_mps);
            ++next_v;
          }
          const semlio::LidarInertialReport r = lio.process(scan);
          if (r.initialized && !init_frame) init_frame = i;
          if (r.initialized) g_map_final = r.gravity_map_mps2;
          write_trace(i, r.frame, r.T_map_lidar, r.T_map_lidar_prior, semlio::to_string(r.prediction),
                      semlio::to_string(r.deskew), r.init_status ? semlio::to_string(*r.init_status) : "-",
                      r.initialized ? &r.state : nullptr, r.initialized ? &r.bias : nullptr, r.gravity_map_mps2);
          FrameFacts f;
          f.T_map_lidar = r.T_map_lidar;
          f.status = semlio::to_string(r.frame.status);
          f.degenerate = r.frame.solve.degenerate();
          if (f.degenerate) {
            const auto [A, B] = motion_ref(i, T_prev, r.frame.T_map_lidar);
            f.degenerate_along_track = along_track(r.frame, A, B);
          }
          f.imu_predicted = r.prediction == semlio::PredictionSource::kImu;
          f.imu_fallback = r.imu_fallback;
          f.total_ms = r.frame.timings.total_ms;
          T_prev = r.frame.T_map_lidar;
          return f;
        });
      } else {
        auto odometry = make();
        SE3d T_prev;
        const semlio::SO3d R_lidar_imu = lc.T_imu_lidar.so3().inverse();
        std::size_t next_v = 0;
        std::optional<Eigen::Vector3d> v_hint_imu;  // latest INS velocity up to this scan (IMU frame)
        double prev_stamp = 0.0;
        run([&](semlio::Scan& scan, std::size_t i) {
          if (deskew && !scan.has_times()) semlio::assign_times_from_azimuth(scan, point_times);
          // Start-up hint (--velocity-hint oxts): the INS velocity at the previous scan over the time since.
          std::optional<SE3d> prior;
          if (!velocities.empty() && i > first && i - first < lc.init.min_frames && v_hint_imu) {
            prior = T_prev * SE3d(semlio::SO3d(), R_lidar_imu * *v_hint_imu * (scan.stamp_s - prev_stamp));
          }
          const double t_imu = scan.stamp_s + lc.imu_time_offset_s;
          while (next_v < velocities.size() && velocities[next_v].stamp_s <= t_imu + 1e-6) {
            v_hint_imu = velocities[next_v++].v_imu_mps;
          }
          prev_stamp = scan.stamp_s;
          const semlio::FrameReport r = odometry.process(scan, prior);
          write_trace(i, r, r.T_map_lidar, prior, prior ? "velocity_hint" : "constant_velocity", deskew ? "cv" : "none",
                      "-", nullptr, nullptr, Eigen::Vector3d::Zero());
          FrameFacts f;
          f.T_map_lidar = r.T_map_lidar;
          f.status = semlio::to_string(r.status);
          f.degenerate = r.solve.degenerate();
          if (f.degenerate) {
            const auto [A, B] = motion_ref(i, T_prev, r.T_map_lidar);
            f.degenerate_along_track = along_track(r, A, B);
          }
          f.total_ms = r.timings.total_ms;
          T_prev = r.T_map_lidar;
          return f;
        });
      }
    };
    const semlio::ScanLabels seg{};
    const auto s = settings;
    // Lidar-only with deskew: the front end's own deskew slot (constant velocity).
    if (opt.imu == "none" && deskew) {
      if (opt.preset == "baseline") {
        run_front([&] {
          return semlio::Odometry(seg, semlio::NearestK(s.nearest),
                                  semlio::LoamResiduals{semlio::PointToLine(s.line), semlio::PointToPlane(s.plane)},
                                  semlio::PoseThreshold(s.pose_threshold), s.odometry, semlio::ConstantVelocityDeskew{});
        });
      } else {
        run_front([&] {
          return semlio::Odometry(
              seg, semlio::NormalConsistency(s.normal),
              semlio::LoamResiduals{semlio::SemanticWeighted<semlio::PointToLine>(semlio::PointToLine(s.line)),
                                    semlio::SemanticWeighted<semlio::PointToPlane>(semlio::PointToPlane(s.plane))},
              semlio::SemanticAdaptive(s.semantic_keyframes), s.odometry, semlio::ConstantVelocityDeskew{});
        });
      }
    } else if (opt.preset == "baseline") {
      run_front([&] { return semlio::make_baseline_odometry(seg, s); });
    } else {
      run_front([&] { return semlio::make_full_odometry(seg, s); });
    }
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    // Outputs.
    fs::create_directories(opt.out);
    std::vector<SE3d> poses;
    for (const FrameFacts& f : facts) poses.push_back(f.T_map_lidar);
    const std::optional<SE3d> Tr = seq.calibration() ? seq.calibration()->T_cam0_velo : std::nullopt;
    semlio::io::write_kitti_poses((fs::path(opt.out) / "poses.txt").string(),
                                  Tr ? semlio::io::lidar_to_camera(poses, *Tr) : poses);
    std::optional<semlio::eval::AteReport> ate;
    if (seq.has_ground_truth()) {
      std::vector<SE3d> gt_all = seq.ground_truth_lidar();
      std::vector<SE3d> gt(gt_all.begin() + static_cast<std::ptrdiff_t>(first),
                           gt_all.begin() + static_cast<std::ptrdiff_t>(last_u) + 1);
      const SE3d T0 = gt.front().inverse();
      for (SE3d& T : gt) T = T0 * T;
      ate = semlio::eval::ate(gt, poses);
    }
    std::size_t degenerate = 0;
    std::size_t degenerate_along = 0;
    double along_sum = 0.0;
    std::size_t imu_predicted = 0;
    std::size_t fallbacks = 0;
    for (const FrameFacts& f : facts) {
      if (f.degenerate) {
        ++degenerate;
        along_sum += f.degenerate_along_track;
        degenerate_along += f.degenerate_along_track > 0.9 ? 1U : 0U;
      }
      imu_predicted += f.imu_predicted ? 1U : 0U;
      fallbacks += f.imu_fallback ? 1U : 0U;
    }
    std::ofstream js(fs::path(opt.out) / "report.json");
    semlio_examples::JsonWriter j(js);
    j.begin_object();
    j.field("sequence", seq.directory()).field("imu", opt.imu).field("deskew", opt.deskew).field("preset", opt.preset);
    j.field("frames", static_cast<double>(facts.size())).field("wall_s", wall_s);
    j.field("imu_time_offset_s", lc.imu_time_offset_s);
    j.field("velocity_hint", opt.velocity_hint).field("reset_weak_directions", opt.reset_weak);
    j.field("velocity_factors", opt.velocity_factors);
    if (g_map_true && opt.imu == "oxts" && init_frame) {
      // Gravity error of the LIO (map frame) against the first OXTS attitude,
      // and its component along the direction of travel (first to last true
      // position; an along-track error turns into an along-track acceleration).
      const Eigen::Vector3d& gt = *g_map_true;
      j.field("gravity_error_deg", std::atan2(g_map_final.cross(gt).norm(), g_map_final.dot(gt)) * 180.0 / std::numbers::pi);
      const Eigen::Vector3d travel = gt_position(last_u) - gt_position(first);
      if (travel.allFinite() && travel.norm() > 1.0) {
        j.field("gravity_error_along_track_mps2", (g_map_final - gt).dot(travel.normalized()));
      }
    }
    j.field("lidar_information", opt.lidar_information).field("lidar_residual_sigma_m", lc.lidar_residual_sigma_m);
    j.field("initialized_at_frame", init_frame ? static_cast<double>(*init_frame) : -1.0);
    j.field("imu_predicted_frames", static_cast<double>(imu_predicted));
    j.field("imu_fallback_frames", static_cast<double>(fallbacks));
    j.field("degenerate_frames", static_cast<double>(degenerate));
    j.field("degenerate_along_track_frames", static_cast<double>(degenerate_along));
    j.field("degenerate_along_track_mean_abs_cos", degenerate > 0 ? along_sum / static_cast<double>(degenerate) : 0.0);
    if (ate) {
      j.key("ate").begin_object();
      j.field("rmse_m", ate->rmse_m).field("mean_m", ate->mean_m).field("max_m", ate->max_m);
      j.end_object();
    }
    j.end_object();
    js << "\n";
    if (!opt.quiet) {
      std::printf("semlio_lio  %s  imu=%s deskew=%s preset=%s  frames %zu  %.1f s\n", seq.directory().c_str(),
                  opt.imu.c_str(), opt.deskew.c_str(), opt.preset.c_str(), facts.size(), wall_s);
      if (opt.imu == "oxts") {
        std::printf("  initialised at frame %ld, IMU-predicted frames %zu, IMU fallbacks %zu\n",
                    init_frame ? static_cast<long>(*init_frame) : -1L, imu_predicted, fallbacks);
      }
      std::printf("  degenerate frames %zu (%zu along the direction of travel)\n", degenerate, degenerate_along);
      if (ate) std::printf("  ATE RMSE %.3f m (mean %.3f, max %.3f)\n", ate->rmse_m, ate->mean_m, ate->max_m);
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "semlio_lio: " << e.what() << "\n";
    return 1;
  }
}
