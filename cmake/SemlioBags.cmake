# semlio::io_bags: the optional bag readers (include/semlio/io/bag/: ROS 1
# bags, MCAP, rosbag2 sqlite3). Header-only like the rest, but their headers
# include libbz2, liblz4, libzstd and libsqlite3, so they get a target of their
# own that links those; semlio::semlio never needs them. Built when all four
# are found (Debian: libbz2-dev liblz4-dev libzstd-dev libsqlite3-dev), or
# never with -DSEMLIO_WITH_BAGS=OFF.
option(SEMLIO_WITH_BAGS "Build the bag readers (semlio::io_bags) when their libraries are found" ON)
set(SEMLIO_HAVE_BAGS OFF)
if(SEMLIO_WITH_BAGS)
  find_package(BZip2 QUIET)
  find_package(SQLite3 QUIET)
  find_package(PkgConfig QUIET)
  if(PkgConfig_FOUND)
    pkg_check_modules(SEMLIO_LZ4 QUIET IMPORTED_TARGET GLOBAL liblz4)
    pkg_check_modules(SEMLIO_ZSTD QUIET IMPORTED_TARGET GLOBAL libzstd)
  endif()
  if(BZip2_FOUND AND SQLite3_FOUND AND SEMLIO_LZ4_FOUND AND SEMLIO_ZSTD_FOUND)
    set(SEMLIO_HAVE_BAGS ON)
    add_library(semlio_io_bags INTERFACE)
    add_library(semlio::io_bags ALIAS semlio_io_bags)
    set_target_properties(semlio_io_bags PROPERTIES EXPORT_NAME io_bags)
    target_link_libraries(semlio_io_bags INTERFACE semlio BZip2::BZip2 SQLite::SQLite3
                          PkgConfig::SEMLIO_LZ4 PkgConfig::SEMLIO_ZSTD)
    message(STATUS "semlio: bag readers (semlio::io_bags) enabled")
  else()
    message(STATUS "semlio: bag readers disabled (need libbz2, liblz4, libzstd, libsqlite3)")
  endif()
endif()
