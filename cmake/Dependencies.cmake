# Every dependency is a Debian/Ubuntu package; scripts/install-deps.sh installs them.
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(spdlog REQUIRED)
find_package(CLI11 REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(Threads REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(SYSTEMD REQUIRED IMPORTED_TARGET libsystemd)
pkg_check_modules(GPIOD REQUIRED IMPORTED_TARGET libgpiod)
# Bag and MCAP chunks (drivers/include/liod/drivers/bag_reader.hpp): bzip2, LZ4 frames, Zstandard,
# and zlib's CRC-32.
find_package(BZip2 REQUIRED)
find_package(ZLIB REQUIRED)
pkg_check_modules(LZ4 REQUIRED IMPORTED_TARGET liblz4)
pkg_check_modules(ZSTD REQUIRED IMPORTED_TARGET libzstd)
# The live view's WebSocket server (daemon/src/foxglove_server.cpp): Boost.Beast on Boost.Asio,
# header-only; included by that one file.
find_package(Boost 1.74 REQUIRED)
if(LIOD_BUILD_TESTS)
  find_package(GTest REQUIRED)
  find_package(benchmark REQUIRED)
endif()
# Ceres is found where it is used (the backend library), to keep its slow headers contained.
# PCL only for test_state_dir, which reads the PCDs liod writes with PCL's reader
# (daemon/include/liod/daemon/map_export.hpp says why liod does not write them with PCL).
find_package(PCL QUIET REQUIRED COMPONENTS common io)
