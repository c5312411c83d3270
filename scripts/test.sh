#!/usr/bin/env bash
# Runs liod's whole test suite from a fresh clone: installs what is missing, builds every test
# with AddressSanitizer + UndefinedBehaviorSanitizer and runs them, the threaded ones with
# ThreadSanitizer, fuzzes every parser of outside bytes briefly, then builds the Release tree
# (tests, tools, benchmarks) and runs every test.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
stage() { echo "== test.sh: $1 (${SECONDS} s since start)"; }
# Sanitizer trees: -g1 (line tables, enough for the reports' stack traces) compiles ~20 % faster
# than the full debug information of RelWithDebInfo.
sanitizer_flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG")

bash scripts/install-deps.sh

# AddressSanitizer + UndefinedBehaviorSanitizer: every test (LiveVsReplay once, at recorded pace:
# 5x pace runs the same code), and the fault-injection drives whose faults reach the decoders and
# the IMU-gap path (all 18 take ~17 CPU-minutes under ASan; the Release tree below runs them all).
sanitized=(test_drivers test_core test_config test_odometry test_backend test_eval test_sim test_daemon)
sanitized_faults='FaultInjection\.(GarbageIn20|ImuCutFive)'

stage "AddressSanitizer + UBSan build"
cmake -S . -B build-asan "${sanitizer_flags[@]}" -DLIOD_SANITIZE="address;undefined" >/dev/null
cmake --build build-asan -j"$jobs" --target "${sanitized[@]}" test_fault liod-sim liod  # liod: the systemd unit test verifies it
stage "AddressSanitizer + UBSan tests"
(cd build-asan && export ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 &&
   ctest --output-on-failure -j"$jobs" -L "$(IFS='|'; echo "${sanitized[*]}")" -E 'LiveVsReplay\.FiveTimesPace' &&
   ctest --output-on-failure -j"$jobs" -R "$sanitized_faults")

# ThreadSanitizer: the daemon's rings, pose socket and pipeline threads (ClockJump: the live
# pipeline with IMU-rate poses made on the IMU thread).
stage "ThreadSanitizer"
cmake -S . -B build-tsan "${sanitizer_flags[@]}" -DLIOD_SANITIZE=thread >/dev/null
cmake --build build-tsan -j"$jobs" --target test_daemon liod-sim  # liod-sim: the drive the pipeline tests use
(cd build-tsan && TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" \
   ctest --output-on-failure -j"$jobs" -L test_daemon -R 'SpscRing|PoseSocket|PoseProtocol|StuckClient|UdpLidar|SerialImu|AnchorExchange|ClockJump')

# libFuzzer: a short run of every fuzz target (scripts/fuzz.sh 60 is the long run).
stage "libFuzzer"
bash scripts/fuzz.sh 10

stage "Release build"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$jobs"
stage "Release tests"
(cd build && ctest --output-on-failure -j"$jobs")
stage "all passed"
