# The bad-input catalogue (label "bad_inputs"): one CTest entry per row of
# tests/examples/bad_inputs.tsv, run by run_bad_input.cmake. Adding a case is
# adding a row: name, tool (an example target), expected exit status, a CMake
# regex the message must match, the arguments (tab-separated; see the TSV's
# header for the placeholders). The tool must be an example target (the
# examples are added after tests/, so it is resolved at generate time).
file(STRINGS "${CMAKE_CURRENT_SOURCE_DIR}/examples/bad_inputs.tsv" semlio_bad_rows ENCODING UTF-8)
foreach(row IN LISTS semlio_bad_rows)
  if(row MATCHES "^#" OR row MATCHES "^[ \t]*$")
    continue()
  endif()
  string(REPLACE "\t" ";" cells "${row}")
  list(LENGTH cells n)
  if(n LESS 4)
    message(FATAL_ERROR "bad_inputs.tsv: a row needs name, tool, exit, regex[, args]: '${row}'")
  endif()
  list(GET cells 0 case_name)
  list(GET cells 1 tool)
  list(GET cells 2 exit_status)
  list(GET cells 3 regex)
  set(case_args "")
  if(n GREATER 4)
    list(GET cells 4 case_args)
  endif()
  if(TEST bad_input_${case_name})
    message(FATAL_ERROR "bad_inputs.tsv: case name '${case_name}' appears twice")
  endif()
  add_test(NAME bad_input_${case_name}
           COMMAND ${CMAKE_COMMAND} "-DTOOL=$<TARGET_FILE:${tool}>" "-DARGS=${case_args}"
                   "-DEXPECT_EXIT=${exit_status}" "-DEXPECT_REGEX=${regex}"
                   "-DDATA_DIR=${CMAKE_CURRENT_SOURCE_DIR}/data"
                   "-DBAD_DIR=${CMAKE_CURRENT_SOURCE_DIR}/examples/bad_inputs"
                   "-DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/bad_inputs/${case_name}"
                   -P "${CMAKE_CURRENT_SOURCE_DIR}/examples/run_bad_input.cmake")
  set_tests_properties(bad_input_${case_name} PROPERTIES LABELS "examples;bad_inputs" TIMEOUT 180)
endforeach()
