# One row of tests/examples/bad_inputs.tsv, run by CTest (registered by
# tests/examples/bad_inputs.cmake): runs TOOL with ARGS and requires
#   - the exit status EXPECT_EXIT (never a signal),
#   - stdout + stderr matching EXPECT_REGEX (the message names the file or
#     option and the problem),
#   - no NaN in any output: stdout, stderr or a file the tool wrote (a bad
#     value echoed in quotes, 'nan', is the message naming it, not a NaN),
#   - every .json file the tool wrote parses as JSON.
# Placeholders in ARGS: @DATA@ = tests/data, @BAD@ = tests/examples/bad_inputs,
# @OUT@ = this case's scratch folder, which also holds zero.<ext> links to
# /dev/zero and fifo.bin / fifo.g2o (named pipes) for the non-regular-file cases.
# Variables: TOOL, ARGS, EXPECT_EXIT, EXPECT_REGEX, DATA_DIR, BAD_DIR, WORK_DIR.
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
foreach(ext bin pcd ply g2o txt yaml)
  file(CREATE_LINK /dev/zero "${WORK_DIR}/zero.${ext}" SYMBOLIC)
endforeach()
foreach(name fifo.bin fifo.g2o fifo.txt)
  execute_process(COMMAND mkfifo "${WORK_DIR}/${name}" RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "mkfifo ${WORK_DIR}/${name} failed")
  endif()
endforeach()

string(REPLACE "@DATA@" "${DATA_DIR}" args "${ARGS}")
string(REPLACE "@BAD@" "${BAD_DIR}" args "${args}")
string(REPLACE "@OUT@" "${WORK_DIR}" args "${args}")
separate_arguments(args UNIX_COMMAND "${args}")
execute_process(COMMAND "${TOOL}" ${args} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                TIMEOUT 120)
set(all "${out}${err}")
get_filename_component(tool_name "${TOOL}" NAME)
set(what "${tool_name} ${args}\nexit: ${rc}\nstdout:\n${out}\nstderr:\n${err}")
if(NOT rc MATCHES "^[0-9]+$")
  message(FATAL_ERROR "did not exit normally (${rc}): ${what}")
endif()
if(NOT rc EQUAL EXPECT_EXIT)
  message(FATAL_ERROR "exit ${rc}, expected ${EXPECT_EXIT}: ${what}")
endif()
if(NOT all MATCHES "${EXPECT_REGEX}")
  message(FATAL_ERROR "message does not match '${EXPECT_REGEX}': ${what}")
endif()
# A printed NaN ("nan", "-nan" from printf / std::to_string), not the word
# NaN in a message and not a bad value echoed in quotes ('nan').
set(nan_regex "(^|[^'A-Za-z_.])-?nan([^'A-Za-z_]|$)")
if(all MATCHES "${nan_regex}")
  message(FATAL_ERROR "output contains a NaN: ${what}")
endif()
file(GLOB_RECURSE written LIST_DIRECTORIES false "${WORK_DIR}/*")
foreach(f IN LISTS written)
  if(IS_SYMLINK "${f}" OR f MATCHES "/fifo\\.")
    continue()
  endif()
  file(STRINGS "${f}" text LIMIT_INPUT 1000000)
  if(text MATCHES "${nan_regex}")
    message(FATAL_ERROR "${f} (written by the tool) contains a NaN: ${what}")
  endif()
  if(f MATCHES "\\.json$")
    file(READ "${f}" json)
    string(JSON type ERROR_VARIABLE json_error TYPE "${json}")
    if(json_error)
      message(FATAL_ERROR "${f} is not valid JSON (${json_error}): ${what}")
    endif()
  endif()
endforeach()
