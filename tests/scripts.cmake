# Short versions of the measurement scripts in scripts/ (label "scripts"):
# the README's numbers come from the long versions, CI proves on every change
# that each script still runs end to end against this build and that its
# checks pass where a short run can decide them. Needs the example binaries.
if(NOT SEMLIO_BUILD_EXAMPLES)
  return()
endif()
find_program(SEMLIO_BASH bash REQUIRED)
set(script_out "${CMAKE_CURRENT_BINARY_DIR}/script_runs")
set(script_env SKIP_BUILD=1 "BUILD_DIR=${PROJECT_BINARY_DIR}")

# name, then the command line after `bash scripts/`
function(semlio_add_script_test name)
  add_test(NAME script_${name}
           COMMAND ${CMAKE_COMMAND} -E env ${script_env} "OUT=${script_out}/${name}" ${ARGN}
           WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}")
  set_tests_properties(script_${name} PROPERTIES LABELS scripts TIMEOUT 900)
endfunction()

# The main job on a 20-frame drive (both presets, side-by-side table).
semlio_add_script_test(demo ${CMAKE_COMMAND} -E env FRAMES=20 ${SEMLIO_BASH} scripts/demo.sh)
# Issue 5's accuracy run on 20 frames.
semlio_add_script_test(accuracy_sim ${SEMLIO_BASH} scripts/accuracy_sim.sh 20 none labels 1)
# Forward/backward consistency on the 3 real KITTI raw frames of tests/data
# (the bounds need the 22-frame snippet; here every run must complete).
semlio_add_script_test(kitti_raw_consistency ${CMAKE_COMMAND} -E env REPORT_ONLY=1
  ${SEMLIO_BASH} scripts/kitti_raw_consistency.sh tests/data/kitti_raw/snippet_22)
# Every bundled g2o graph reaches its reference chi2 within 1e-6 (a real check).
semlio_add_script_test(pgo_validate ${SEMLIO_BASH} scripts/pgo_validate.sh "${PROJECT_BINARY_DIR}")
# GeometricSegmenter mIoU table, 2 frames per world.
semlio_add_script_test(segmenter_miou ${SEMLIO_BASH} scripts/segmenter_miou.sh 2 1
  tests/data/kitti/sequences/00 tests/data/kitti/semantickitti_00_labels)

# The paper's evaluation on small drives: docs/results_quick.md must be what
# this build produces (scripts/reproduce.sh --quick regenerates it).
semlio_add_script_test(reproduce_quick ${SEMLIO_BASH} scripts/reproduce.sh --quick --check)
# ~1 min on an idle 2-core machine; 16 min measured while eight builds shared it.
set_tests_properties(script_reproduce_quick PROPERTIES TIMEOUT 1800)
# The rule behind results.md's real-drive resolution table: the alignment
# against numpy's SVD, and worse / better / not resolved on known cases.
# (/usr/bin/python3: the interpreter reproduce.sh runs its report with.)
semlio_add_script_test(ate_resolution /usr/bin/python3 scripts/ate_resolution.py --self-test)
# Batch runs over two small drives (the real 2-scan KITTI sequence and a
# 6-frame simulated one); both must complete and land in the table. (No ';'
# in the command: CMake would split it into several arguments.)
semlio_add_script_test(batch ${SEMLIO_BASH} -c
  "mkdir -p \"$OUT\" && \"$BUILD_DIR/examples/semlio_simulate\" --world urban --traffic none --frames 6 --out \"$OUT/sim6\" > /dev/null && printf '%s\\n' tests/data/kitti/sequences/00 \"$OUT/sim6\" > \"$OUT/inputs.txt\" && OUT=\"$OUT/batch\" JOBS=2 scripts/batch.sh \"$OUT/inputs.txt\" -- --labels none --map off && grep -q '2 of 2 runs complete' \"$OUT/batch/summary.md\"")

# semlio_kitti keeps going over unreadable frames (--bad-scans skip) and stops
# on them with --bad-scans stop.
add_test(NAME semlio_kitti_bad_scans
         COMMAND ${CMAKE_COMMAND} "-DSEMLIO_KITTI=$<TARGET_FILE:semlio_kitti>"
                 "-DDATA_DIR=${CMAKE_CURRENT_SOURCE_DIR}/data" "-DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/bad_scans_check"
                 -P "${CMAKE_CURRENT_SOURCE_DIR}/examples/run_bad_scans_check.cmake")
set_tests_properties(semlio_kitti_bad_scans PROPERTIES LABELS examples TIMEOUT 300)

# The bad-input catalogue of the command-line tools (tests/examples/bad_inputs.tsv).
include("${CMAKE_CURRENT_SOURCE_DIR}/examples/bad_inputs.cmake")

# Short versions of the speed and must-hold scripts the issues name. Each run
# must complete and print its table; REPORT_ONLY=1 where a short run cannot
# decide the must-hold (the README's numbers come from the long runs).
# These two run benchmark binaries (bench_association, bench_frame_time):
# only in a build that has them (scripts/sanitize.sh builds none).
if(SEMLIO_BUILD_BENCHMARKS)
  # Association kernel ratios (issue #4) with a tiny measuring time.
  semlio_add_script_test(bench_association ${SEMLIO_BASH} scripts/bench_association.sh --benchmark_min_time=0.01)
  set_tests_properties(script_bench_association PROPERTIES FAIL_REGULAR_EXPRESSION "no association rows")
  # Frame time per stage (issue #5) on the 3 real KITTI raw frames and a 12-frame drive.
  semlio_add_script_test(frame_time ${CMAKE_COMMAND} -E env FRAMES=12 ${SEMLIO_BASH} scripts/frame_time.sh
    tests/data/kitti_raw/snippet_22)
endif()
# Frame time under settings files (issue #5's speed trade-offs), alternated,
# on the two real KITTI scans of tests/data.
file(WRITE "${script_out}/configs/shipped.yaml" "{}\n")
file(WRITE "${script_out}/configs/reassociate_2.yaml" "solver: {reassociate_every: 2}\n")
semlio_add_script_test(frame_time_configs ${CMAKE_COMMAND} -E env ROUNDS=2 ${SEMLIO_BASH} scripts/frame_time_configs.sh
  tests/data/kitti/sequences/00 "${script_out}/configs/shipped.yaml" "${script_out}/configs/reassociate_2.yaml")
# The data-sources page (issue #37) from the 3-scan KITTI raw drive of
# tests/data and a 12-frame simulated VLP-16 drive through every container;
# the page goes to OUT, the README is left alone.
semlio_add_script_test(data_sources ${CMAKE_COMMAND} -E env SENSORS=vlp16 "PAGE=${script_out}/data_sources/page.md"
  README= ${SEMLIO_BASH} scripts/data_sources.sh tests/data/kitti_raw/2011_09_26/2011_09_26_drive_0009_sync - 12)
set_tests_properties(script_data_sources PROPERTIES PASS_REGULAR_EXPRESSION "data_sources.sh: wrote")
# Lidar-inertial must-holds (issue #7) on 30-frame drives.
semlio_add_script_test(lio_accuracy ${CMAKE_COMMAND} -E env REPORT_ONLY=1 "OUT_ROOT=${script_out}/lio_accuracy"
  ${SEMLIO_BASH} scripts/lio_accuracy.sh 30 1)
# Loop closure and the long run (issue #6) on 60-frame drives.
semlio_add_script_test(loop_accuracy ${CMAKE_COMMAND} -E env REPORT_ONLY=1 FRAMES=60 ONE_RUN=1
  ${SEMLIO_BASH} scripts/loop_accuracy.sh)
semlio_add_script_test(long_run ${CMAKE_COMMAND} -E env REPORT_ONLY=1 FRAMES=60 WINDOW=12
  ${SEMLIO_BASH} scripts/long_run.sh)
# The bag writers against the reference readers (python3-rosbag, @mcap/core
# + @foxglove/cdr) on 3-frame drives of five sensors and field sets.
if(SEMLIO_HAVE_BAGS)
  semlio_add_script_test(check_sim_bags ${SEMLIO_BASH} scripts/check_sim_bags.sh 3)
endif()

# End-to-end checks of semlio_run and semlio_convert on the committed data:
# tests/examples/NAME_check.cmake, run with both binaries, in a work folder
# of its own.
function(semlio_add_tool_check test check timeout)
  add_test(NAME ${test}
           COMMAND ${CMAKE_COMMAND} "-DSEMLIO_RUN=$<TARGET_FILE:semlio_run>" "-DSEMLIO_CONVERT=$<TARGET_FILE:semlio_convert>"
                   "-DDATA_DIR=${CMAKE_CURRENT_SOURCE_DIR}/data" "-DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/${check}"
                   -P "${CMAKE_CURRENT_SOURCE_DIR}/examples/${check}.cmake")
  set_tests_properties(${test} PROPERTIES LABELS examples TIMEOUT ${timeout})
endfunction()
if(SEMLIO_HAVE_BAGS)
  # semlio_run on every input format (bag, MCAP, KITTI folder, PCD folder,
  # KITTI raw drive), output guarding, SIGINT, missing frames, topic choice,
  # header stamps.
  semlio_add_tool_check(semlio_run_inputs run_tool_check 600)
  # semlio_convert's dataset mode: bag, MCAP and KITTI raw drive to KITTI and
  # PCD folders that semlio_run reads back to byte-identical poses; lost
  # fields, bad frames, output guard, bad topic.
  semlio_add_tool_check(semlio_convert_dataset convert_dataset_check 120)
endif()
# semlio_run --labels onnx on the real KITTI raw snippet with the tiny model of
# tests/data/onnx; --labels onnx without --model or with a missing model fails.
add_test(NAME semlio_run_onnx_labels
         COMMAND ${CMAKE_COMMAND} "-DSEMLIO_RUN=$<TARGET_FILE:semlio_run>" "-DHAVE_ONNX=${SEMLIO_HAVE_ONNX}"
                 "-DDATA_DIR=${CMAKE_CURRENT_SOURCE_DIR}/data" "-DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/onnx_run_check"
                 -P "${CMAKE_CURRENT_SOURCE_DIR}/segment/onnx_run_check.cmake")
set_tests_properties(semlio_run_onnx_labels PROPERTIES LABELS examples TIMEOUT 300)
