#pragma once
/// \file
/// Umbrella header: the library (everything except the simulator, which is
/// a tool: include <semlio/sim/simulator.hpp> for it).

#include <semlio/concepts.hpp>
#include <semlio/core/buffers.hpp>
#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/logger.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/core/stopwatch.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>

#include <semlio/io/g2o.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/kitti_sequence.hpp>
#include <semlio/io/oxts.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/io/ply.hpp>
#include <semlio/io/trajectory.hpp>

#include <semlio/features/loam_features.hpp>
#include <semlio/features/pca.hpp>
#include <semlio/features/preprocess.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/features/sensor_model.hpp>
#include <semlio/search/kdtree.hpp>
#include <semlio/search/voxel_grid.hpp>

#include <semlio/imu/deskew.hpp>
#include <semlio/imu/imu_factor.hpp>
#include <semlio/imu/inertial_init.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio/solve/gauss_newton.hpp>
#include <semlio/graph/inertial_graph.hpp>
#include <semlio/graph/keyframe_inertial_graph.hpp>
#include <semlio/graph/pose_graph.hpp>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/associate/normal_consistency.hpp>
#include <semlio/associate/normal_consistency_reference.hpp>
#include <semlio/keyframe/pose_threshold.hpp>
#include <semlio/keyframe/semantic_adaptive.hpp>
#include <semlio/loop/loop_closer.hpp>
#include <semlio/loop/radius_detector.hpp>
#include <semlio/loop/scan_context.hpp>
#include <semlio/map/local_map.hpp>
#include <semlio/map/semantic_map.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>
#include <semlio/residual/robust.hpp>
#include <semlio/residual/semantic_weighted.hpp>
#include <semlio/segment/geometric_segmenter.hpp>
#include <semlio/segment/scan_labels.hpp>

#include <semlio/pipeline/interpolate.hpp>
#include <semlio/pipeline/lidar_inertial.hpp>
#include <semlio/pipeline/odometry.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/pipeline/registration.hpp>
#include <semlio/pipeline/slam.hpp>

#include <semlio/eval/ate.hpp>
#include <semlio/eval/kitti_metric.hpp>
#include <semlio/eval/miou.hpp>
