#!/usr/bin/env bash
# Runs liod's whole test suite from a fresh clone: installs what is missing, builds the Release
# tree (tests, tools, benchmarks) and runs every test; builds the clang AddressSanitizer + UBSan
# tree and runs the tests there; fuzzes every parser of outside bytes briefly from that same tree;
# and runs the threaded parts of the daemon under ThreadSanitizer. Prints each stage's duration.
# The trees are configured by scripts/trees.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/trees.sh
jobs=$(nproc)

# CPU seconds (user + system) of the finished commands this script ran so far: the script's
# children's times in /proc (fields cutime and cstime, in clock ticks).
clock_ticks=$(getconf CLK_TCK)
children_cpu() { awk -v hz="$clock_ticks" '{ printf "%d", ($16 + $17) / hz }' "/proc/$$/stat"; }

stage_names=()
stage_starts=()
stage_cpu=()
stage() {
  stage_names+=("$1")
  stage_starts+=("$SECONDS")
  stage_cpu+=("$(children_cpu)")
  echo "== test.sh: $1 (${SECONDS} s since start)"
}
# Each stage's wall time and CPU time, printed however the run ends: on a machine shared with other
# work, a stage whose wall time grew but not its CPU time waited for the machine.
summary() {
  local status=$? i
  local ends=("${stage_starts[@]:1}" "$SECONDS") cpu_ends=("${stage_cpu[@]:1}" "$(children_cpu)")
  echo "== test.sh: stage durations (wall, and CPU of $(nproc) cores)"
  for i in "${!stage_names[@]}"; do
    printf '   %-24s %5d s  %6d CPU-s\n' "${stage_names[$i]}" "$((ends[i] - stage_starts[i]))" "$((cpu_ends[i] - stage_cpu[i]))"
  done
  printf '   %-24s %5d s  %6d CPU-s  (%s)\n' total "$SECONDS" "$(children_cpu)" \
    "$([ "$status" -eq 0 ] && echo "all passed" || echo "FAILED")"
}
trap summary EXIT

# ctest starts the longest tests first when it knows their times, so that no long test starts
# last and leaves a core idle at the end. A sanitizer tree without times of its own takes the
# Release run's (Testing/Temporary/CTestCostData.txt): the order of the tests' lengths is the same.
seed_test_times() {
  local times=Testing/Temporary/CTestCostData.txt
  if [ ! -f "$1/$times" ] && [ -f "build/$times" ]; then
    mkdir -p "$1/Testing/Temporary"
    cp "build/$times" "$1/$times"
  fi
}

stage "install dependencies"
bash scripts/install-deps.sh

# Release first: a change that does not build or fails a plain test stops the run here, before the
# slower sanitizer trees.
stage "Release build"
configure_tree release build
cmake --build build -j"$jobs"
stage "Release tests"
(cd build && ctest --output-on-failure -j"$jobs")
# The Debian package of the Release tree: built, unpacked and checked as installed (the unit
# verified against the packaged binary, the packaged configuration checked).
stage "Debian package"
bash scripts/check-package.sh build

# AddressSanitizer + UndefinedBehaviorSanitizer: every test, less those that run code other
# sanitized tests run, on more data or against the clock (the Release tree runs them all):
# - pace: LiveVsReplay at 5x (the recorded pace runs the same code), BackendLoad and Overload
#   (they assert what the odometry does when it keeps the recorded pace or falls behind by a set
#   amount: under ASan, sharing 2 cores, it misses the pace by itself);
# - long runs of covered code: the map frame's 70 s loop drive (the other pipeline tests run its
#   code), `liod calibrate` on its three drives (its math runs on synthetic motion), the IMU
#   plausibility drives (the range gate has unit tests; ImuCutFive runs the gap path), 60 keyframes
#   of relocalisation in another town (Relocalizer and Backend tests place keyframes in a saved map);
# - of the fault-injection drives, all but those whose faults reach the decoders and the IMU-gap
#   path (all take ~17 CPU-minutes under ASan).
# The same tree builds the libFuzzer targets. Its tests read the simulated drives the Release
# tests made (LIOD_TEST_DRIVES, tests/support/test_env.hpp): a clang-built liod-sim draws its
# random worlds in another order than the gcc-built one the tests' bounds were set on.
sanitized=(test_drivers test_core test_config test_odometry test_backend test_eval test_sim test_daemon test_calibration)
sanitized_faults='FaultInjection\.(GarbageIn20|ImuCutFive)'
unsanitized='LiveVsReplay\.FiveTimesPace|BackendLoad\..*|Overload\..*|MapFrame\.Corrections.*|CalibrateDrive\..*|ImuPlausibility\..*|Backend\.ARunThroughAnotherTownIsNeverPlaced'

stage "ASan + UBSan build"
configure_tree asan build-asan
cmake --build build-asan -j"$jobs" --target "${sanitized[@]}" test_fault liod-sim liod fuzz  # liod: the systemd unit test verifies it
stage "ASan + UBSan tests"
seed_test_times build-asan
# One ctest run (the cores stay busy to the end): the sanitized labels and test_fault, less the
# unsanitized tests and the fault tests not in sanitized_faults.
unsanitized_faults=$(cd build-asan && ctest -N -L '^test_fault$' | sed -n 's/^ *Test *#[0-9]*: //p' |
  { grep -Ev "$sanitized_faults" || true; } | paste -sd'|')
(cd build-asan && export ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 LIOD_TEST_DRIVES="$PWD/../build" &&
   ctest --output-on-failure -j"$jobs" -L "^($(IFS='|'; echo "${sanitized[*]}")|test_fault)\$" \
     -E "^($unsanitized|$unsanitized_faults)\$")

# libFuzzer: a short run of every fuzz target (scripts/fuzz.sh 60 is the long run).
stage "libFuzzer"
bash scripts/fuzz.sh 10 build-asan

# ThreadSanitizer: the daemon's rings, pose socket and pipeline threads (ClockJump: the live
# pipeline with IMU-rate poses made on the IMU thread; Foxglove: the live view's io thread fed by
# the pipeline's).
stage "TSan build"
configure_tree tsan build-tsan
cmake --build build-tsan -j"$jobs" --target test_daemon
stage "TSan tests"
seed_test_times build-tsan
# The pipeline tests replay the drives the Release tests made (LIOD_TEST_DRIVES, as in the ASan tree).
(cd build-tsan && export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" LIOD_TEST_DRIVES="$PWD/../build" &&
   ctest --output-on-failure -j"$jobs" -L test_daemon -R 'SpscRing|PoseSocket|PoseProtocol|StuckClient|UdpLidar|SerialImu|AnchorExchange|ClockJump|Foxglove')
