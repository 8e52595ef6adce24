# semlio_run --labels onnx end to end (run by CTest; see tests/scripts.cmake):
#  1. on the three real KITTI raw scans of tests/data/kitti_raw/snippet_22 with
#     the tiny model of tests/data/onnx: exit 0, one pose per frame, a
#     labelled map, report.json naming the labels and the model;
#  2. --labels onnx without --model: exit 1 with a message, OUT not created;
#  3. a model card whose model is missing: exit 1 naming it, OUT not created.
# Without the ONNX component (HAVE_ONNX off) only 2 runs, and --labels onnx
# with a card must say the build has no ONNX segmenter.
# Variables: SEMLIO_RUN (binary), DATA_DIR (tests/data), WORK_DIR, HAVE_ONNX.
cmake_minimum_required(VERSION 3.21)
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(card "${DATA_DIR}/onnx/tiny_kitti.yaml")
set(common --input "${DATA_DIR}/kitti_raw/snippet_22" --sensor hdl64e --kitti-correction on --quiet)

function(run_fails name regex out)
  execute_process(COMMAND "${SEMLIO_RUN}" ${ARGN} --out "${out}" RESULT_VARIABLE rc OUTPUT_VARIABLE stdout
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 1)
    message(FATAL_ERROR "${name}: exit ${rc}, expected 1\n${stdout}\n${err}")
  endif()
  if(NOT err MATCHES "${regex}")
    message(FATAL_ERROR "${name}: the message does not match '${regex}':\n${err}")
  endif()
  if(EXISTS "${out}")
    message(FATAL_ERROR "${name}: ${out} was created by a run refused before its first frame")
  endif()
endfunction()

# 2. No model card.
run_fails(no_model "--labels onnx needs --model" "${WORK_DIR}/out_no_model" ${common} --labels onnx)

if(NOT HAVE_ONNX)
  run_fails(no_component "this build has no ONNX segmenter" "${WORK_DIR}/out_no_component" ${common} --labels onnx
            --model "${card}")
  return()
endif()

# 3. A card naming a model that is not there.
file(WRITE "${WORK_DIR}/missing_model.yaml" "model: nowhere.onnx\nclasses: [unlabeled, car]\n")
run_fails(missing_model "nowhere.onnx: ONNX model not found" "${WORK_DIR}/out_missing" ${common} --labels onnx
          --model "${WORK_DIR}/missing_model.yaml")

# 1. The real snippet.
set(out "${WORK_DIR}/out")
execute_process(COMMAND "${SEMLIO_RUN}" ${common} --labels onnx --model "${card}" --out "${out}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE stdout ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "snippet: exit ${rc}\n${stdout}\n${err}")
endif()
file(READ "${out}/poses.txt" poses)
string(REGEX MATCHALL "\n" lines "${poses}")
list(LENGTH lines pose_count)
if(NOT pose_count EQUAL 3)
  message(FATAL_ERROR "snippet: ${pose_count} poses for 3 scans")
endif()
file(READ "${out}/report.json" report)
string(JSON labels GET "${report}" labels)
string(JSON model GET "${report}" label_model)
string(JSON model_card GET "${report}" label_model_card)
if(NOT labels STREQUAL "onnx" OR NOT model MATCHES "tiny_linear\\.onnx$" OR NOT model_card STREQUAL card)
  message(FATAL_ERROR "snippet: report.json says labels '${labels}', model '${model}', card '${model_card}'")
endif()
# The map carries the network's classes: the tiny model labels a real scan
# with several of its six classes (tests/segment/test_onnx_segmenter.cpp).
file(READ "${out}/map.ply" ply LIMIT 2000)
if(NOT ply MATCHES "property [a-z0-9]+ label")
  message(FATAL_ERROR "snippet: map.ply has no label property:\n${ply}")
endif()
