# semlio_convert's dataset mode end to end (run by CTest; see tests/scripts.cmake):
#  1. the ROS 1 bag, the MCAP file and the KITTI raw drive converted to KITTI
#     folders: semlio_run on each folder and on its original input gives
#     byte-identical poses.txt (also with --gt and --calib: camera-0 outputs
#     and evaluation); the folder's files and convert.json; KITTI -> KITTI is
#     the identity;
#  2. the bag converted to a PCD folder: semlio_run --format folder gives the
#     bag's poses.txt byte for byte;
#  3. ring and time fields: lost to KITTI (warning, convert.json), kept in PCD;
#  4. a corrupt scan costs one frame (a KITTI gap, a 0-point PCD) and semlio_run
#     reads both back; a corrupt last scan ends the KITTI folder; --first/--last;
#  5. OUT guarded: refused when not empty, --overwrite replaces a previous
#     conversion only; 6. a bad topic is an error naming it; a bad option exits 2.
# Variables: SEMLIO_RUN, SEMLIO_CONVERT (binaries), DATA_DIR (tests/data), WORK_DIR.
cmake_minimum_required(VERSION 3.21)  # policies: quoted strings in if() are never variables
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(run_opts --preset full --sensor hdl64e --kitti-correction on --map off --quiet)
set(common --labels none ${run_opts})
set(raw "${DATA_DIR}/kitti_raw/2011_09_26/2011_09_26_drive_0009_sync")

function(convert_ok name)
  execute_process(COMMAND "${SEMLIO_CONVERT}" ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "convert ${name}: exit ${rc}\n${out}\n${err}")
  endif()
  set(last_out "${out}" PARENT_SCOPE)
  set(last_err "${err}" PARENT_SCOPE)
endfunction()

function(convert_fails name code pattern)
  execute_process(COMMAND "${SEMLIO_CONVERT}" ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL code OR NOT err MATCHES "${pattern}")
    message(FATAL_ERROR "convert ${name}: exit ${rc} (expected ${code}), stderr does not match '${pattern}':\n${out}\n${err}")
  endif()
endfunction()

function(run_ok name)
  execute_process(COMMAND "${SEMLIO_RUN}" ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "semlio_run ${name}: exit ${rc}\n${out}\n${err}")
  endif()
endfunction()

function(same_poses a b)
  file(READ "${WORK_DIR}/${a}/poses.txt" pa)
  file(READ "${WORK_DIR}/${b}/poses.txt" pb)
  string(REGEX MATCHALL "\n" lines "${pa}")
  list(LENGTH lines n)
  if(n LESS 1 OR NOT pa STREQUAL pb)
    message(FATAL_ERROR "poses.txt of ${a} (${n} lines) and ${b} differ:\n${pa}\nvs\n${pb}")
  endif()
endfunction()

# same_poses, and the same ATE in both runs' report.json (`what` names the case).
function(same_poses_and_ate a b what)
  same_poses(${a} ${b})
  foreach(r ${a} ${b})
    file(READ "${WORK_DIR}/${r}/report.json" report)
    string(JSON ate_${r} GET "${report}" evaluation ate_all_frames rmse_m)
  endforeach()
  if(NOT ate_${a} STREQUAL ate_${b})
    message(FATAL_ERROR "${what}: ATE ${ate_${a}} m from the input, ${ate_${b}} m from its conversion")
  endif()
endfunction()

# 1. Bag, MCAP, KITTI raw -> KITTI folders; semlio_run on both sides.
convert_ok(bag --input "${DATA_DIR}/bags/kitti3_lz4.bag" --out "${WORK_DIR}/k_bag")
if(NOT last_out MATCHES "frames out +3 of 3" OR NOT last_out MATCHES "imu +not converted")
  message(FATAL_ERROR "bag: summary:\n${last_out}")
endif()
foreach(f velodyne/000000.bin velodyne/000001.bin velodyne/000002.bin times.txt calib.txt convert.json)
  if(NOT EXISTS "${WORK_DIR}/k_bag/${f}")
    message(FATAL_ERROR "bag: no ${f} in the KITTI folder")
  endif()
endforeach()
file(GLOB partial "${WORK_DIR}/.k_bag*")
if(EXISTS "${WORK_DIR}/k_bag/poses.txt" OR partial)
  message(FATAL_ERROR "bag: poses.txt without ground truth, or a left-over staging folder '${partial}'")
endif()
file(STRINGS "${WORK_DIR}/k_bag/times.txt" times)
list(LENGTH times n)
list(GET times 0 t0)
list(GET times 1 t1)
file(STRINGS "${WORK_DIR}/k_bag/calib.txt" calib)
if(NOT n EQUAL 3 OR NOT t0 STREQUAL "0" OR NOT t1 MATCHES "^0\\.(1|0999)" OR NOT calib STREQUAL "Tr: 1 0 0 0 0 1 0 0 0 0 1 0")
  message(FATAL_ERROR "bag: times.txt '${times}' (seconds since frame 0) or calib.txt '${calib}' (identity Tr)")
endif()
file(READ "${WORK_DIR}/k_bag/convert.json" report)
string(JSON fmt GET "${report}" input format)
string(JSON topic GET "${report}" input lidar_topic)
string(JSON nout GET "${report}" frames_out)
string(JSON imu GET "${report}" imu)
if(NOT fmt STREQUAL "bag" OR NOT topic MATCHES "^/kitti/velo/pointcloud" OR NOT nout EQUAL 3 OR NOT imu MATCHES "not converted")
  message(FATAL_ERROR "bag: convert.json: format ${fmt}, topic ${topic}, frames_out ${nout}, imu ${imu}")
endif()
convert_ok(mcap --input "${DATA_DIR}/bags/kitti3_zstd.mcap" --out "${WORK_DIR}/k_mcap")
convert_ok(raw --input "${raw}" --out "${WORK_DIR}/k_raw")
file(STRINGS "${WORK_DIR}/k_raw/poses.txt" gt)
list(LENGTH gt n)
if(NOT n EQUAL 3)
  message(FATAL_ERROR "raw: poses.txt (OXTS ground truth) has ${n} lines, not 3")
endif()

run_ok(bag --input "${DATA_DIR}/bags/kitti3_lz4.bag" --out "${WORK_DIR}/r_bag" ${common})
run_ok(k_bag --input "${WORK_DIR}/k_bag" --format kitti --out "${WORK_DIR}/r_k_bag" ${common})
same_poses(r_bag r_k_bag)
run_ok(mcap --input "${DATA_DIR}/bags/kitti3_zstd.mcap" --out "${WORK_DIR}/r_mcap" ${common})
run_ok(k_mcap --input "${WORK_DIR}/k_mcap" --format kitti --out "${WORK_DIR}/r_k_mcap" ${common})
same_poses(r_mcap r_k_mcap)
# The raw drive with semlio_run's automatic sensor choice on both sides.
set(auto --labels none --map off --quiet)
run_ok(raw --input "${raw}" --out "${WORK_DIR}/r_raw" ${auto})
run_ok(k_raw --input "${WORK_DIR}/k_raw" --format kitti --out "${WORK_DIR}/r_k_raw" ${auto})
same_poses_and_ate(r_raw r_k_raw "raw (ATE against OXTS)")

# A bag with ground truth and a camera calibration (--gt, --calib): calib.txt
# keeps the input's entries, poses.txt is the ground truth as given (camera-0
# frame); semlio_run writes the same camera-0 poses and evaluation from both.
set(gt "${WORK_DIR}/k_raw/poses.txt")
set(calib "${DATA_DIR}/kitti/sequences/00/calib.txt")
convert_ok(bag_gt --input "${DATA_DIR}/bags/kitti3_lz4.bag" --gt "${gt}" --calib "${calib}" --out "${WORK_DIR}/k_bag_gt")
file(READ "${gt}" gt_text)
file(READ "${WORK_DIR}/k_bag_gt/poses.txt" copied)
file(STRINGS "${WORK_DIR}/k_bag_gt/calib.txt" calib_lines REGEX "^(P0|Tr):")
list(LENGTH calib_lines n)
if(NOT copied STREQUAL gt_text OR NOT n EQUAL 2)
  message(FATAL_ERROR "bag with --gt/--calib: poses.txt is not the ground truth as given, or calib.txt lacks P0/Tr")
endif()
run_ok(bag_gt --input "${DATA_DIR}/bags/kitti3_lz4.bag" --gt "${gt}" --calib "${calib}" --out "${WORK_DIR}/r_bag_gt" ${common})
run_ok(k_bag_gt --input "${WORK_DIR}/k_bag_gt" --format kitti --out "${WORK_DIR}/r_k_bag_gt" ${common})
same_poses_and_ate(r_bag_gt r_k_bag_gt "bag with --gt/--calib")
file(READ "${WORK_DIR}/r_bag/poses.txt" lidar_poses)
file(READ "${WORK_DIR}/r_bag_gt/poses.txt" camera_poses)
if(lidar_poses STREQUAL camera_poses)
  message(FATAL_ERROR "bag with --gt/--calib: Tr was not applied (camera-0 poses equal the lidar ones)")
endif()

# A KITTI odometry sequence (calib.txt with P0 and Tr, official poses,
# times.txt) and a SemanticKITTI one (labels/): the scans and ground truth
# come through byte for byte, semlio_run gives the same poses and ATE, and
# the labels the same classes (written back as their static raw ids).
convert_ok(seq00 --input "${DATA_DIR}/kitti/sequences/00" --out "${WORK_DIR}/k_seq00")
foreach(f velodyne/000000.bin velodyne/000001.bin poses.txt)
  file(SHA256 "${DATA_DIR}/kitti/sequences/00/${f}" a)
  file(SHA256 "${WORK_DIR}/k_seq00/${f}" b)
  if(NOT a STREQUAL b)
    message(FATAL_ERROR "KITTI sequence 00: ${f} differs from the input's")
  endif()
endforeach()
run_ok(seq00 --input "${DATA_DIR}/kitti/sequences/00" --out "${WORK_DIR}/r_seq00" ${common})
run_ok(k_seq00 --input "${WORK_DIR}/k_seq00" --out "${WORK_DIR}/r_k_seq00" ${common})
same_poses_and_ate(r_seq00 r_k_seq00 "KITTI sequence 00")
set(sk "${DATA_DIR}/kitti/semantickitti_subset/00")
convert_ok(semantickitti --input "${sk}" --out "${WORK_DIR}/k_sk")
file(READ "${WORK_DIR}/k_sk/convert.json" report)
string(JSON labels GET "${report}" labels_written)
if(NOT labels OR NOT EXISTS "${WORK_DIR}/k_sk/labels/000000.label")
  message(FATAL_ERROR "SemanticKITTI: no labels/ written (labels_written ${labels})")
endif()
# The labels read back as the same classes: both folders give the same PCD
# (its label field holds the raw id of each point's class).
convert_ok(sk_pcd --input "${sk}" --out "${WORK_DIR}/p_sk" --to pcd)
convert_ok(k_sk_pcd --input "${WORK_DIR}/k_sk" --out "${WORK_DIR}/p_k_sk" --to pcd)
file(SHA256 "${WORK_DIR}/p_sk/000000.pcd" a)
file(SHA256 "${WORK_DIR}/p_k_sk/000000.pcd" b)
file(STRINGS "${WORK_DIR}/p_sk/000000.pcd" header LIMIT_COUNT 3)
if(NOT a STREQUAL b OR NOT header MATCHES "FIELDS x y z intensity label")
  message(FATAL_ERROR "SemanticKITTI: the labels do not read back as the same classes ('${header}')")
endif()

# A KITTI folder converted again is the same folder, file for file.
convert_ok(kitti_again --input "${WORK_DIR}/k_bag_gt" --out "${WORK_DIR}/k_again")
foreach(f velodyne/000000.bin velodyne/000002.bin times.txt calib.txt poses.txt)
  file(SHA256 "${WORK_DIR}/k_bag_gt/${f}" a)
  file(SHA256 "${WORK_DIR}/k_again/${f}" b)
  if(NOT a STREQUAL b)
    message(FATAL_ERROR "KITTI -> KITTI: ${f} differs")
  endif()
endforeach()

# Every bag fixture (ROS 1 with each compression and unindexed, MCAP with
# each chunking and encoding, rosbag2 sqlite3; Velodyne, Ouster, Hesai,
# RoboSense, Livox and big-endian layouts): the PCD folder gives semlio_run
# the bag's poses.txt byte for byte, and so does the KITTI folder when KITTI
# .bin loses no field (with ring or time fields it would not: semlio_run
# infers rings and times that the bag carried). The synthetic clouds are too
# small to track (identity poses), so for them the real check is that the PCD
# folder read back and written again gives the same files byte for byte:
# every field of every scan, and the stamps, survive the round trip.
foreach(case kitti3_lz4.bag kitti3_zstd.mcap small_lz4.mcap small_unchunked.mcap small_streamed.mcap
             small_bigendian.mcap small_ros1.mcap small_none.mcap=/padded/points ros2_sqlite=/points
             quirks_none.bag=/velodyne_points quirks_bz2.bag=/ouster/points quirks_lz4_unindexed.bag=/hesai/pandar
             quirks_none.bag=/rslidar_points quirks_none.bag=/livox/lidar quirks_none.bag=/bigendian/points)
  string(REPLACE "=" ";" parts "${case}")
  list(GET parts 0 file)
  set(topic)
  list(LENGTH parts np)
  if(np EQUAL 2)
    list(GET parts 1 t)
    set(topic --lidar-topic ${t})
  endif()
  string(MAKE_C_IDENTIFIER "${case}" id)
  set(in --input "${DATA_DIR}/bags/${file}" ${topic})
  convert_ok(${case} ${in} --out "${WORK_DIR}/all/k_${id}")
  convert_ok(${case} ${in} --out "${WORK_DIR}/all/p_${id}" --to pcd)
  run_ok(${case} ${in} --out "${WORK_DIR}/all/r_${id}" ${common})
  run_ok(${case} --input "${WORK_DIR}/all/p_${id}" --format folder --out "${WORK_DIR}/all/r_p_${id}" ${common})
  same_poses(all/r_${id} all/r_p_${id})
  convert_ok(${case} --input "${WORK_DIR}/all/p_${id}" --format folder --out "${WORK_DIR}/all/pp_${id}" --to pcd)
  file(GLOB pcds RELATIVE "${WORK_DIR}/all/p_${id}" "${WORK_DIR}/all/p_${id}/*.pcd")
  list(LENGTH pcds n)
  if(n LESS 3)
    message(FATAL_ERROR "${case}: ${n} PCD files")
  endif()
  foreach(f ${pcds} times.txt)
    file(SHA256 "${WORK_DIR}/all/p_${id}/${f}" a)
    file(SHA256 "${WORK_DIR}/all/pp_${id}/${f}" b)
    if(NOT a STREQUAL b)
      message(FATAL_ERROR "${case}: ${f} differs after PCD folder -> PCD folder")
    endif()
  endforeach()
  file(READ "${WORK_DIR}/all/k_${id}/convert.json" report)
  string(JSON nlost LENGTH "${report}" fields_lost)
  if(nlost EQUAL 0)
    run_ok(${case} --input "${WORK_DIR}/all/k_${id}" --format kitti --out "${WORK_DIR}/all/r_k_${id}" ${common})
    same_poses(all/r_${id} all/r_k_${id})
    list(APPEND kitti_checked ${case})
  endif()
endforeach()
message(STATUS "KITTI folders compared with their bag (no field lost): ${kitti_checked}")

# 2. Bag -> PCD folder -> semlio_run --format folder.
convert_ok(pcd --input "${DATA_DIR}/bags/kitti3_lz4.bag" --out "${WORK_DIR}/p_bag" --to pcd)
run_ok(p_bag --input "${WORK_DIR}/p_bag" --format folder --out "${WORK_DIR}/r_p_bag" ${common})
same_poses(r_bag r_p_bag)

# 3. Ring and time fields (the quirk bag's Velodyne layout): lost to KITTI, kept in PCD.
set(quirks --input "${DATA_DIR}/bags/quirks_none.bag" --lidar-topic /velodyne_points --imu-topic /imu/data)
convert_ok(quirks_kitti ${quirks} --out "${WORK_DIR}/k_quirks")
file(READ "${WORK_DIR}/k_quirks/convert.json" report)
string(JSON nlost LENGTH "${report}" fields_lost)
string(JSON lost0 GET "${report}" fields_lost 0)
string(JSON lost1 GET "${report}" fields_lost 1)
set(lost "${lost0} ${lost1}")
if(NOT last_err MATCHES "warning: per-point fields lost.*ring, time.*--to pcd" OR NOT nlost EQUAL 2 OR NOT lost STREQUAL "ring time")
  message(FATAL_ERROR "quirks: no warning about ring/time, or fields_lost '${lost}':\n${last_err}")
endif()
convert_ok(quirks_pcd ${quirks} --out "${WORK_DIR}/p_quirks" --to pcd)
file(STRINGS "${WORK_DIR}/p_quirks/000000.pcd" header LIMIT_COUNT 3)
if(NOT header MATCHES "FIELDS x y z intensity ring time" OR last_err MATCHES "warning")
  message(FATAL_ERROR "quirks: the PCD does not carry ring and time: '${header}'\n${last_err}")
endif()

# 4. A corrupt middle scan is a gap; a corrupt last scan ends the folder.
set(bad "${WORK_DIR}/bad")
file(MAKE_DIRECTORY "${bad}/velodyne")
foreach(i 0 1 2 3)
  file(COPY_FILE "${WORK_DIR}/k_bag/velodyne/000000.bin" "${bad}/velodyne/00000${i}.bin")
endforeach()
file(WRITE "${bad}/velodyne/000001.bin" "not a scan")
file(WRITE "${bad}/velodyne/000003.bin" "")
convert_ok(bad --input "${bad}" --out "${WORK_DIR}/k_bad")
file(READ "${WORK_DIR}/k_bad/convert.json" report)
string(JSON unreadable GET "${report}" unreadable_frames)
string(JSON trailing GET "${report}" trailing_bad_frames_dropped)
string(JSON skipped0 GET "${report}" skipped 0 input_frame)
file(STRINGS "${WORK_DIR}/k_bad/times.txt" times)
list(LENGTH times n)
if(NOT unreadable EQUAL 2 OR NOT trailing EQUAL 1 OR NOT skipped0 EQUAL 1 OR NOT n EQUAL 3
   OR EXISTS "${WORK_DIR}/k_bad/velodyne/000001.bin" OR NOT EXISTS "${WORK_DIR}/k_bad/velodyne/000002.bin")
  message(FATAL_ERROR "bad scans: unreadable ${unreadable}, trailing ${trailing}, first skipped ${skipped0}, "
                      "${n} times\n${report}")
endif()
convert_ok(bad_pcd --input "${bad}" --out "${WORK_DIR}/p_bad" --to pcd)
file(GLOB pcds "${WORK_DIR}/p_bad/*.pcd")
list(LENGTH pcds n)
if(NOT n EQUAL 4)
  message(FATAL_ERROR "bad scans to PCD: ${n} files, not 4 (bad frames are 0-point PCDs)")
endif()
# Both folders read back: one missing (KITTI gap) or empty (PCD) frame each.
run_ok(k_bad --input "${WORK_DIR}/k_bad" --format kitti --out "${WORK_DIR}/r_k_bad" ${common})
run_ok(p_bad --input "${WORK_DIR}/p_bad" --format folder --out "${WORK_DIR}/r_p_bad" ${common})
file(READ "${WORK_DIR}/r_k_bad/report.json" report)
string(JSON status GET "${report}" frames 1 status)
file(STRINGS "${WORK_DIR}/r_p_bad/poses.txt" pp)
list(LENGTH pp n)
if(NOT status STREQUAL "missing" OR NOT n EQUAL 4)
  message(FATAL_ERROR "bad scans read back: KITTI frame 1 status ${status}, ${n} PCD-folder poses (expected 4)")
endif()

# --first on a bag (read in order from its start): frame 1 becomes frame 0.
convert_ok(first --input "${DATA_DIR}/bags/kitti3_lz4.bag" --out "${WORK_DIR}/k_first1" --first 1 --last 1)
file(SHA256 "${WORK_DIR}/k_first1/velodyne/000000.bin" a)
file(SHA256 "${WORK_DIR}/k_bag/velodyne/000001.bin" b)
file(STRINGS "${WORK_DIR}/k_first1/times.txt" times)
if(NOT a STREQUAL b OR NOT times STREQUAL "0" OR EXISTS "${WORK_DIR}/k_first1/velodyne/000001.bin")
  message(FATAL_ERROR "--first 1 --last 1: not the bag's frame 1 alone (times '${times}')")
endif()

# 5. OUT guarded.
convert_fails(guard 1 "not empty.*--overwrite" --input "${raw}" --out "${WORK_DIR}/k_bag")
file(READ "${WORK_DIR}/k_bag/convert.json" report)
string(JSON fmt GET "${report}" input format)
if(NOT fmt STREQUAL "bag")
  message(FATAL_ERROR "guard: the refused conversion changed OUT (input.format ${fmt})")
endif()
convert_ok(overwrite --input "${raw}" --out "${WORK_DIR}/k_bag" --overwrite --last 1)
file(STRINGS "${WORK_DIR}/k_bag/times.txt" times)
list(LENGTH times n)
if(NOT n EQUAL 2 OR NOT EXISTS "${WORK_DIR}/k_bag/poses.txt")
  message(FATAL_ERROR "--overwrite: ${n} times (expected 2) or no poses.txt from the raw drive")
endif()
file(MAKE_DIRECTORY "${WORK_DIR}/precious")
file(WRITE "${WORK_DIR}/precious/notes.txt" "mine")
convert_fails(overwrite_foreign 1 "only a previous semlio_convert output" --input "${raw}" --out "${WORK_DIR}/precious"
              --overwrite)
if(NOT EXISTS "${WORK_DIR}/precious/notes.txt")
  message(FATAL_ERROR "--overwrite removed a folder that is not a conversion")
endif()

# 6. Bad topic, bad options.
convert_fails(topic 1 "no topic /nope .--lidar-topic.; topics: .*/kitti/velo/pointcloud"
              --input "${DATA_DIR}/bags/kitti3_lz4.bag" --lidar-topic /nope --out "${WORK_DIR}/k_topic")
convert_fails(several 1 "sensor_msgs/PointCloud2 topics.*--lidar-topic"
              --input "${DATA_DIR}/bags/quirks_none.bag" --out "${WORK_DIR}/k_several")
convert_fails(to 2 "--to" --input "${raw}" --out "${WORK_DIR}/k_to" --to ply)
convert_fails(first 2 "--first" --input "${raw}" --out "${WORK_DIR}/k_first" --first 5)
if(EXISTS "${WORK_DIR}/k_topic" OR EXISTS "${WORK_DIR}/k_several" OR EXISTS "${WORK_DIR}/k_first")
  message(FATAL_ERROR "a failed conversion left its OUT behind")
endif()
