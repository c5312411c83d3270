# LIOD_FUZZ: the libFuzzer targets in fuzz/ (clang only). They are built in the AddressSanitizer +
# UBSan tree the tests run in (LIOD_SANITIZE=address;undefined), so one build of the libraries
# serves the tests and the fuzzers, and every fuzz run checks the very code the daemon runs.
# fuzz/CMakeLists.txt gives libFuzzer's coverage instrumentation to the libraries the targets link;
# the rest of the tree, which only the tests run, goes without it.
if(LIOD_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "LIOD_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++")
  endif()
  if(NOT "address" IN_LIST LIOD_SANITIZE OR NOT "undefined" IN_LIST LIOD_SANITIZE)
    message(FATAL_ERROR "LIOD_FUZZ builds in the sanitizer tree: configure with -DLIOD_SANITIZE='address;undefined'")
  endif()
endif()
