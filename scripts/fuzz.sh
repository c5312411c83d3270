#!/usr/bin/env bash
# Builds liod's libFuzzer targets (fuzz/) with clang, ASan and UBSan, and runs each one for a fixed
# time on a scratch copy of its seed corpus, one after the other.
#
#   scripts/fuzz.sh [seconds-per-target (60)] [build-dir (build-fuzz)]
#
# Fails when any target crashes, leaks, hangs (one input > 10 s), allocates more than 256 MB at
# once (the inputs are a few KB) or breaks one of its checks. The input that did it is kept as
# <build-dir>/fuzz-runs/<target>/{crash,leak,timeout,oom}-<hash>, next to the target's full log;
# replay it with <build-dir>/bin/<target> FILE.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
build=${2:-build-fuzz}
targets=(fuzz_rs_helios fuzz_pcap_reader fuzz_imu_csv fuzz_mtdata2 fuzz_can_imu fuzz_angles_csv fuzz_time_sync fuzz_config
  fuzz_pose_socket fuzz_pipeline)

command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ not found (scripts/install-deps.sh installs it)" >&2; exit 1; }
cmake -S . -B "$build" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Release -DLIOD_FUZZ=ON \
  -DLIOD_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j"$(nproc)" --target fuzz

runs="$build/fuzz-runs"
rm -rf "$runs"
"$build/bin/liod-fuzz-seeds" "$runs/seeds"

# The last "cov: N ft: M" libFuzzer printed, and one of its final statistics.
coverage() { grep -o 'cov: [0-9]* ft: [0-9]*' "$1" | tail -n 1 | awk '{print $2 "/" $4}'; }
final_stat() { sed -n "s/^stat::$2: *//p" "$1" | tail -n 1; }

failed=()
summary=$(printf '%-18s %12s %9s %13s  %s' target execs exec/s "cov/features" result)
for t in "${targets[@]}"; do
  dir="$runs/$t"
  mkdir -p "$dir/corpus"
  cp "$runs/seeds/$t"/* "$dir/corpus/"
  echo "fuzz.sh: $t for ${seconds} s"
  result=ok
  if ! UBSAN_OPTIONS=print_stacktrace=1 "$build/bin/$t" -max_total_time="$seconds" -timeout=10 \
       -malloc_limit_mb=256 -print_final_stats=1 -artifact_prefix="$dir/" "$dir/corpus" >"$dir/log.txt" 2>&1; then
    result="FAILED (see $dir/log.txt)"
    failed+=("$t")
  fi
  summary+=$(printf '\n%-18s %12s %9s %13s  %s' "$t" "$(final_stat "$dir/log.txt" number_of_executed_units)" \
    "$(final_stat "$dir/log.txt" average_exec_per_sec)" "$(coverage "$dir/log.txt")" "$result")
done

echo "$summary"
for t in "${failed[@]}"; do
  echo "---- $t: end of $runs/$t/log.txt"
  tail -n 40 "$runs/$t/log.txt"
done
if [ ${#failed[@]} -ne 0 ]; then
  echo "fuzz.sh: ${#failed[@]} target(s) failed: ${failed[*]}" >&2
  exit 1
fi
echo "fuzz.sh: all ${#targets[@]} targets ran ${seconds} s each without a failure"
