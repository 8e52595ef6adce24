# semlio_run end to end (run by CTest; see tests/scripts.cmake):
#  1. the same three real KITTI scans read as a ROS 1 bag (python3-rosbag), an
#     MCAP file (@mcap/core), a KITTI odometry folder and a folder of PCDs give
#     byte-identical poses.txt;
#  2. a second run into the same OUT is refused without --overwrite, and with
#     it leaves only the new run's files;
#  3. SIGINT after 2 frames: exit 130, complete outputs for those 2 frames;
#  4. an OUT that cannot be created fails before the first frame;
#  5. --last -5 is a usage error; 6. a deleted scan is one "missing" frame;
#  7. the KITTI raw drive as published runs and is evaluated against OXTS;
#  8. a bag with several PointCloud2 topics names them;
#  9. header stamps mean what the sensor profile says (sweep end or start);
# 10. --sensor auto recognises KITTI scans in a bag and an MCAP file (point
#     order, the HDL-64E's elevations): the poses of --sensor hdl64e
#     --kitti-correction on, and report.json says how it was decided.
# Variables: SEMLIO_RUN, SEMLIO_CONVERT (binaries), DATA_DIR (tests/data), WORK_DIR.
cmake_minimum_required(VERSION 3.21)  # policies: quoted strings in if() are never variables
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(common --labels none --preset full --sensor hdl64e --kitti-correction on --map off --quiet)

function(run_ok name)
  execute_process(COMMAND "${SEMLIO_RUN}" ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name}: exit ${rc}\n${out}\n${err}")
  endif()
  set(last_out "${out}" PARENT_SCOPE)
endfunction()

# 1. One set of scans, four containers.
set(snippet "${DATA_DIR}/kitti_raw/snippet_22")
set(kitti "${WORK_DIR}/kitti")
set(pcds "${WORK_DIR}/pcds")
file(MAKE_DIRECTORY "${kitti}/velodyne" "${pcds}")
foreach(i 0 1 2)
  execute_process(COMMAND "${SEMLIO_CONVERT}" "${snippet}/000000000${i}.pcd" "${kitti}/velodyne/00000${i}.bin"
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "semlio_convert frame ${i}: exit ${rc}\n${err}")
  endif()
  file(COPY_FILE "${snippet}/000000000${i}.pcd" "${pcds}/000000000${i}.pcd")
endforeach()
# The bags' header stamps: 1317357625 s + i x 0.1 s.
set(times "1317357625.000000000\n1317357625.100000000\n1317357625.200000000\n")
file(WRITE "${kitti}/times.txt" "${times}")
file(WRITE "${pcds}/times.txt" "${times}")
run_ok(bag --input "${DATA_DIR}/bags/kitti3_lz4.bag" --out "${WORK_DIR}/out_bag" ${common})
if(NOT last_out MATCHES "lidar_topic +/kitti/velo/pointcloud \\(the only sensor_msgs/PointCloud2 topic\\)")
  message(FATAL_ERROR "bag: the summary does not say how the lidar topic was chosen:\n${last_out}")
endif()
run_ok(mcap --input "${DATA_DIR}/bags/kitti3_zstd.mcap" --out "${WORK_DIR}/out_mcap" ${common})
run_ok(kitti --input "${kitti}" --out "${WORK_DIR}/out_kitti" ${common})
run_ok(folder --input "${pcds}" --out "${WORK_DIR}/out_folder" ${common})
file(READ "${WORK_DIR}/out_bag/poses.txt" poses_bag)
string(REGEX MATCHALL "\n" lines "${poses_bag}")
list(LENGTH lines pose_count)
if(NOT pose_count EQUAL 3)
  message(FATAL_ERROR "bag: ${pose_count} poses for 3 clouds")
endif()
foreach(other mcap kitti folder)
  file(READ "${WORK_DIR}/out_${other}/poses.txt" poses_other)
  if(NOT poses_other STREQUAL poses_bag)
    message(FATAL_ERROR "poses.txt from ${other} differs from the ROS 1 bag's:\n${poses_other}\nvs\n${poses_bag}")
  endif()
endforeach()
# 10. --sensor auto on the same bags.
set(auto_opts --labels none --preset full --sensor auto --map off --quiet)
foreach(container bag mcap)
  if(container STREQUAL "bag")
    set(file "${DATA_DIR}/bags/kitti3_lz4.bag")
  else()
    set(file "${DATA_DIR}/bags/kitti3_zstd.mcap")
  endif()
  run_ok(auto_${container} --input "${file}" --out "${WORK_DIR}/auto_${container}" ${auto_opts})
  file(READ "${WORK_DIR}/auto_${container}/poses.txt" poses_auto)
  if(NOT poses_auto STREQUAL poses_bag)
    message(FATAL_ERROR "--sensor auto on the ${container}: poses differ from --sensor hdl64e --kitti-correction on:\n"
                        "${poses_auto}\nvs\n${poses_bag}")
  endif()
  file(READ "${WORK_DIR}/auto_${container}/report.json" report)
  string(JSON profile GET "${report}" sensor profile)
  string(JSON decided GET "${report}" sensor decided_by)
  if(NOT profile STREQUAL "hdl64e" OR NOT decided MATCHES "KITTI HDL-64E")
    message(FATAL_ERROR "--sensor auto on the ${container}: profile '${profile}', decided_by '${decided}'")
  endif()
endforeach()

file(READ "${WORK_DIR}/out_mcap/report.json" report)
string(JSON fmt GET "${report}" input format)
string(JSON status GET "${report}" status)
if(NOT fmt STREQUAL "mcap" OR NOT status STREQUAL "complete")
  message(FATAL_ERROR "mcap report: input.format '${fmt}', status '${status}'")
endif()

# 2. OUT guarded: refused without --overwrite; --overwrite removes the old run's files.
run_ok(map_run --input "${kitti}" --out "${WORK_DIR}/guard" --labels none --sensor hdl64e --quiet)
if(NOT EXISTS "${WORK_DIR}/guard/map.ply")
  message(FATAL_ERROR "guard: the first run wrote no map.ply")
endif()
file(READ "${WORK_DIR}/guard/poses.txt" first_poses)
execute_process(COMMAND "${SEMLIO_RUN}" --input "${kitti}" --out "${WORK_DIR}/guard" ${common} --last 1
                RESULT_VARIABLE rc ERROR_VARIABLE err)
file(READ "${WORK_DIR}/guard/poses.txt" kept_poses)
if(NOT rc EQUAL 1 OR NOT err MATCHES "another run's outputs.*--overwrite" OR NOT kept_poses STREQUAL first_poses)
  message(FATAL_ERROR "guard: a second run without --overwrite: exit ${rc}, poses kept: "
                      "${kept_poses} vs ${first_poses}\n${err}")
endif()
run_ok(overwrite --input "${kitti}" --out "${WORK_DIR}/guard" ${common} --last 1 --overwrite)
file(STRINGS "${WORK_DIR}/guard/poses.txt" new_poses)
list(LENGTH new_poses n)
if(EXISTS "${WORK_DIR}/guard/map.ply" OR NOT n EQUAL 2)
  message(FATAL_ERROR "--overwrite: the old map.ply is still there or poses.txt has ${n} lines, not 2")
endif()

# 3. SIGINT after 2 of 3 frames.
execute_process(COMMAND ${CMAKE_COMMAND} -E env SEMLIO_INTERRUPT_AFTER_FRAMES=2
                        "${SEMLIO_RUN}" --input "${kitti}" --out "${WORK_DIR}/interrupted" ${common}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 130)
  message(FATAL_ERROR "interrupt: exit ${rc}, expected 130\n${out}\n${err}")
endif()
file(STRINGS "${WORK_DIR}/interrupted/poses.txt" ip)
list(LENGTH ip n)
file(READ "${WORK_DIR}/interrupted/report.json" report)
string(JSON status GET "${report}" status)
string(JSON done GET "${report}" frames_done)
string(JSON nframes LENGTH "${report}" frames)
file(GLOB partial "${WORK_DIR}/interrupted/.*")
if(NOT n EQUAL 2 OR NOT status STREQUAL "interrupted" OR NOT done EQUAL 2 OR NOT nframes EQUAL 2 OR partial)
  message(FATAL_ERROR "interrupt: ${n} poses, status ${status}, frames_done ${done}, ${nframes} frame entries, "
                      "left-over temporary files '${partial}'")
endif()

# 4. An OUT that cannot be created: fails at once, names it.
file(WRITE "${WORK_DIR}/a_file" "x")
execute_process(COMMAND "${SEMLIO_RUN}" --input "${kitti}" --out "${WORK_DIR}/a_file/out" ${common}
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "a_file/out")
  message(FATAL_ERROR "unwritable --out: exit ${rc}\n${err}")
endif()

# 5. A negative --last other than -1.
execute_process(COMMAND "${SEMLIO_RUN}" --input "${kitti}" --out "${WORK_DIR}/last" ${common} --last -5
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "--last -5")
  message(FATAL_ERROR "--last -5: exit ${rc}\n${err}")
endif()

# 6. A deleted scan costs one frame (status missing); --missing-frames stop refuses the input.
set(gap "${WORK_DIR}/gap")
file(MAKE_DIRECTORY "${gap}/velodyne")
file(COPY_FILE "${kitti}/velodyne/000000.bin" "${gap}/velodyne/000000.bin")
file(COPY_FILE "${kitti}/velodyne/000002.bin" "${gap}/velodyne/000002.bin")
run_ok(gap --input "${gap}" --out "${WORK_DIR}/out_gap" ${common})
file(READ "${WORK_DIR}/out_gap/report.json" report)
string(JSON status GET "${report}" frames 1 status)
string(JSON missing GET "${report}" missing_frames)
file(STRINGS "${WORK_DIR}/out_gap/poses.txt" gp)
list(LENGTH gp n)
if(NOT status STREQUAL "missing" OR NOT missing EQUAL 1 OR NOT n EQUAL 3)
  message(FATAL_ERROR "gap: frame 1 status ${status}, missing_frames ${missing}, ${n} poses")
endif()
execute_process(COMMAND "${SEMLIO_RUN}" --input "${gap}" --out "${WORK_DIR}/out_gap_stop" ${common}
                        --missing-frames stop RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "000001.bin")
  message(FATAL_ERROR "--missing-frames stop: exit ${rc}\n${err}")
endif()

# 7. The KITTI raw drive exactly as published: OXTS reference, lidar frame.
run_ok(kitti_raw --input "${DATA_DIR}/kitti_raw/2011_09_26/2011_09_26_drive_0009_sync" --out "${WORK_DIR}/raw"
       --labels none --map off --quiet)
file(READ "${WORK_DIR}/raw/report.json" report)
string(JSON fmt GET "${report}" input format)
string(JSON ate GET "${report}" evaluation ate_all_frames rmse_m)
if(NOT fmt STREQUAL "kitti-raw" OR ate GREATER 0.1)
  message(FATAL_ERROR "kitti raw: format ${fmt}, ATE ${ate} m against OXTS over 3 frames")
endif()

# 8. Several PointCloud2 topics: an error that lists them.
execute_process(COMMAND "${SEMLIO_RUN}" --input "${DATA_DIR}/bags/quirks_none.bag" --out "${WORK_DIR}/quirks" ${common}
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "/velodyne_points" OR NOT err MATCHES "/ouster/points" OR NOT err MATCHES "--lidar-topic")
  message(FATAL_ERROR "several PointCloud2 topics: exit ${rc}\n${err}")
endif()
run_ok(quirks_topic --input "${DATA_DIR}/bags/quirks_none.bag" --lidar-topic /ouster/points --imu-topic /imu/data
       --out "${WORK_DIR}/quirks_ouster" --labels none --map off --quiet)

# 9. What a header stamp means follows the sensor profile: the Velodyne
#    driver stamps a cloud at the sweep's end (hdl64e), Ouster's at its start
#    (os1-64); the KITTI folder's times.txt holds the same stamps as sweep
#    starts. Clouds without per-point times start 0.1 s before their stamp
#    under hdl64e and at it under os1-64.
function(first_tum_stamp dir var)
  file(STRINGS "${dir}/poses_tum.txt" lines LIMIT_COUNT 1)
  string(REGEX MATCH "^[0-9.]+" s "${lines}")
  set(${var} "${s}" PARENT_SCOPE)
endfunction()
run_ok(stamp_os --input "${DATA_DIR}/bags/kitti3_lz4.bag" --out "${WORK_DIR}/stamp_os" --labels none --sensor os1-64
       --map off --quiet)
first_tum_stamp("${WORK_DIR}/out_bag" stamp_velodyne)
first_tum_stamp("${WORK_DIR}/stamp_os" stamp_ouster)
first_tum_stamp("${WORK_DIR}/out_kitti" stamp_times)
file(READ "${WORK_DIR}/out_bag/report.json" report)
string(JSON how GET "${report}" input stamps)
# The ground segmenter's sensor height follows the profile too (Ouster: 1 m).
file(READ "${WORK_DIR}/stamp_os/report.json" report_os)
string(JSON height GET "${report_os}" sensor mount_height_m)
if(NOT height MATCHES "^1\\.0+$")
  message(FATAL_ERROR "os1-64: sensor.mount_height_m ${height}, expected the profile's 1 m")
endif()
if(NOT stamp_velodyne MATCHES "^1317357624\\.9" OR NOT stamp_ouster MATCHES "^1317357625(\\.0+)?$"
   OR NOT stamp_times STREQUAL stamp_ouster OR NOT how MATCHES "sweep end")
  message(FATAL_ERROR "header stamps: hdl64e ${stamp_velodyne}, os1-64 ${stamp_ouster}, times.txt ${stamp_times} "
                      "(expected 1317357624.9 and 1317357625 twice); report: ${how}")
endif()
