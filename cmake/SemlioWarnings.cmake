# Warning flags for semlio's own targets (tests, examples, benchmarks). CI
# builds with GCC 12 and -DSEMLIO_WARNINGS_AS_ERRORS=ON; third-party headers
# come in as SYSTEM includes and are exempt.
function(semlio_set_warnings target)
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow
      -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Wunused -Woverloaded-virtual
      -Wnull-dereference -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough)
    if(SEMLIO_WARNINGS_AS_ERRORS)
      target_compile_options(${target} PRIVATE -Werror)
    endif()
  elseif(MSVC)
    target_compile_options(${target} PRIVATE /W4 $<$<BOOL:${SEMLIO_WARNINGS_AS_ERRORS}>:/WX>)
  endif()
endfunction()
