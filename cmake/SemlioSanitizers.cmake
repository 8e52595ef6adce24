# SEMLIO_SANITIZE: build semlio's own targets (tests, examples, benchmarks)
# with GCC's or Clang's sanitizers, e.g. "address,undefined" or "thread";
# empty (the default) = none. The library is header-only, so this
# instruments every line of it that the targets use. scripts/sanitize.sh
# builds and runs the test suite this way.
set(SEMLIO_SANITIZE "" CACHE STRING
    "Sanitizers for semlio's own targets, comma-separated (e.g. address,undefined or thread); empty = none")

if(SEMLIO_SANITIZE)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    message(FATAL_ERROR "SEMLIO_SANITIZE=${SEMLIO_SANITIZE} needs GCC or Clang, not ${CMAKE_CXX_COMPILER_ID}")
  endif()
  if(NOT PROJECT_IS_TOP_LEVEL)
    message(FATAL_ERROR "SEMLIO_SANITIZE applies to semlio's own build only; a parent project sets its own flags")
  endif()
  # Recover from nothing: a report fails the process that raised it, so a
  # test cannot pass with an error printed in its log. Frame pointers keep
  # the reports' stacks whole.
  add_compile_options(-fsanitize=${SEMLIO_SANITIZE} -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_link_options(-fsanitize=${SEMLIO_SANITIZE})
  message(STATUS "semlio: building with -fsanitize=${SEMLIO_SANITIZE}")
endif()
