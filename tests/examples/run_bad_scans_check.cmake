# semlio_kitti on a sequence with unreadable frames (run by CTest; see
# tests/scripts.cmake). Two real KITTI scans from tests/data, then an empty
# .bin, a truncated one and the second scan again:
#   --bad-scans skip (default): exit 0, one pose per frame, the two bad frames
#     reported as too_few_features with their input_error, unreadable_frames 2;
#   --bad-scans stop: exit 1, the error names the first bad file.
# Variables: SEMLIO_KITTI (the binary), DATA_DIR (tests/data), WORK_DIR.
file(REMOVE_RECURSE "${WORK_DIR}")
set(seq "${WORK_DIR}/sequence")
file(MAKE_DIRECTORY "${seq}/velodyne")
set(src "${DATA_DIR}/kitti/sequences/00/velodyne")
file(COPY_FILE "${src}/000000.bin" "${seq}/velodyne/000000.bin")
file(COPY_FILE "${src}/000001.bin" "${seq}/velodyne/000001.bin")
file(WRITE "${seq}/velodyne/000002.bin" "")
file(WRITE "${seq}/velodyne/000003.bin" "0123456789")  # 10 bytes: not a multiple of 16
file(COPY_FILE "${src}/000001.bin" "${seq}/velodyne/000004.bin")
file(WRITE "${seq}/times.txt" "0.0\n0.1\n0.2\n0.3\n0.4\n")

execute_process(COMMAND "${SEMLIO_KITTI}" --sequence "${seq}" --labels none --preset baseline --map off --quiet
                        --out "${WORK_DIR}/skip"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "--bad-scans skip: exit ${rc}\n${out}\n${err}")
endif()
file(STRINGS "${WORK_DIR}/skip/poses.txt" poses)
list(LENGTH poses pose_count)
if(NOT pose_count EQUAL 5)
  message(FATAL_ERROR "--bad-scans skip: ${pose_count} poses for 5 frames")
endif()
file(READ "${WORK_DIR}/skip/report.json" report)
string(JSON unreadable GET "${report}" unreadable_frames)
if(NOT unreadable EQUAL 2)
  message(FATAL_ERROR "--bad-scans skip: unreadable_frames ${unreadable}, expected 2")
endif()
foreach(frame 2 3)
  string(JSON status GET "${report}" frames ${frame} status)
  string(JSON why GET "${report}" frames ${frame} input_error)
  if(NOT status STREQUAL "too_few_features" OR NOT why MATCHES "00000${frame}.bin")
    message(FATAL_ERROR "frame ${frame}: status ${status}, input_error '${why}'")
  endif()
endforeach()
string(JSON status GET "${report}" frames 4 status)
if(NOT status MATCHES "^(tracked|degenerate)$")
  message(FATAL_ERROR "frame 4 after the bad frames: status ${status}, expected tracked")
endif()
if(NOT err MATCHES "frame 2 is unreadable, processed as an empty scan")
  message(FATAL_ERROR "no warning on stderr for frame 2:\n${err}")
endif()

execute_process(COMMAND "${SEMLIO_KITTI}" --sequence "${seq}" --labels none --preset baseline --map off --quiet
                        --bad-scans stop --out "${WORK_DIR}/stop"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "000002.bin: empty .bin file")
  message(FATAL_ERROR "--bad-scans stop: exit ${rc}, expected 1 with the error of 000002.bin\n${err}")
endif()
