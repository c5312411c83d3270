# liod_add_test(NAME SOURCES... LIBS ...): one GoogleTest executable, registered with CTest.
function(liod_add_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main liod_warnings)
  target_include_directories(${name} PRIVATE ${CMAKE_SOURCE_DIR}/tests/support)
  target_compile_definitions(${name} PRIVATE
    LIOD_SHARED_DIR="${LIOD_SHARED_DIR}" LIOD_SOURCE_DIR="${CMAKE_SOURCE_DIR}"
    LIOD_BINARY_DIR="${CMAKE_BINARY_DIR}")
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 900 LABELS ${name})
endfunction()

# liod_add_benchmark(NAME SOURCES... LIBS ...): one Google Benchmark executable (not a CTest test).
function(liod_add_benchmark name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} benchmark::benchmark benchmark::benchmark_main liod_warnings)
  target_include_directories(${name} PRIVATE ${CMAKE_SOURCE_DIR}/tests/support)
  target_compile_definitions(${name} PRIVATE
    LIOD_SHARED_DIR="${LIOD_SHARED_DIR}" LIOD_SOURCE_DIR="${CMAKE_SOURCE_DIR}" LIOD_BINARY_DIR="${CMAKE_BINARY_DIR}")
endfunction()
