#!/usr/bin/env bash
# Hard drives (docs/results.md, "Hard drives"; issue 56): for each seed, a liod-sim drive with every
# road condition on (--hard: traffic, wind, an open stretch, road vibration, a consumer IMU, random
# dropouts, rain), replayed odometry-only by `liod replay` as the other figures are
# (config/liod.yaml + config/vehicles/liod-sim-car.yaml + the drive's extrinsics) and scored by
# liod-eval. Prints one row per seed (ATE RMSE, KITTI drift, front-end ms per scan) and the median
# and largest. Seeds 1-10 are the tuning set, 101-110 the held-out set that no tuning may use.
#   scripts/hard/run.sh [--route urban|highway] [--duration 90] [--max-speed 15]
#                       [--conditions "--hard"] [--config FILE] OUT_DIR SEED...
#                       (after building liod, liod-sim, liod-eval)
# --conditions replaces --hard by other liod-sim options (e.g. "--traffic": that condition alone;
# "" none). --config layers FILE over the default configuration and names that replay's files after
# it (odometry-NAME.tum for NAME.yaml), so that variants share the drives. Drives already simulated
# in OUT_DIR with the same options are reused. Each step runs under flock /tmp/liod-build.lock when flock exists (the build machines share their cores).
set -euo pipefail
route=urban duration=90 speed=15 conditions="--hard" extra=() tag=odometry
while [ $# -gt 0 ]; do
  case "$1" in
    --route) route=$2; shift 2 ;;
    --duration) duration=$2; shift 2 ;;
    --max-speed) speed=$2; shift 2 ;;
    --conditions) conditions=$2; shift 2 ;;
    --config) extra=(--config "$(realpath "$2")"); tag="odometry-$(basename "$2" .yaml)"; shift 2 ;;
    -*) echo "run.sh: unknown option $1" >&2; exit 2 ;;
    *) break ;;
  esac
done
[ $# -ge 2 ] || { echo "usage: scripts/hard/run.sh [options] OUT_DIR SEED..." >&2; exit 2; }
out=$1; shift
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${LIOD_BIN:-$root/build/bin}
lock=(); command -v flock >/dev/null && lock=(flock /tmp/liod-build.lock)
mkdir -p "$out"
rows="$out/rows-$tag.txt"; : > "$rows"
printf '| seed | ATE RMSE (m) | KITTI drift (%%) | front end median (ms/scan) |\n|---|---|---|---|\n'
for s in "$@"; do
  d="$out/${route}_s$s"; mkdir -p "$d"
  opts="--route $route --seed $s --duration $duration --max-speed $speed $conditions"
  if [ ! -f "$d/groundtruth.tum" ] || [ "$(cat "$d/sim-options" 2>/dev/null)" != "$opts" ]; then
    # shellcheck disable=SC2086  # $conditions is a list of options
    "${lock[@]}" "$bin/liod-sim" $opts --quiet --out "$d"
    echo "$opts" > "$d/sim-options"
  fi
  "${lock[@]}" "$bin/liod" --log-level warn replay --no-progress --config "$root/config/liod.yaml" \
    --config "$root/config/vehicles/liod-sim-car.yaml" --config "$d/extrinsics.yaml" \
    "${extra[@]}" --pcap "$d/lidar.pcap" --imu "$d/imu.csv" --trajectory "$d/$tag.tum" > "$d/$tag-replay.txt" 2>&1 || true
  ms=$(grep -o 'median [0-9.]* ms' "$d/$tag-replay.txt" | head -1 | awk '{print $2}')
  "$bin/liod-eval" --gt "$d/groundtruth.tum" --est "$d/$tag.tum" --json > "$d/$tag-eval.json" 2>/dev/null || true
  python3 - "$d/$tag-eval.json" "$s" "${ms:-n/a}" "$rows" <<'PY'
import json, sys
path, seed, ms, rows = sys.argv[1:5]
try:
    e = json.load(open(path)); ate = e["ate"]["rmse_m"]; drift = e["kitti"]["translational_pct"]
except Exception:
    print(f"| {seed} | failed | | {ms} |"); sys.exit()
print(f"| {seed} | {ate:.4f} | {'n/a' if drift is None else f'{drift:.3f}'} | {ms} |")
open(rows, "a").write(f"{ate} {'nan' if drift is None else drift}\n")
PY
done
python3 - "$rows" <<'PY'
import math, statistics, sys
r = [tuple(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
if r:
    a = [x[0] for x in r]; d = [x[1] for x in r if not math.isnan(x[1])]
    dm = f"{statistics.median(d):.3f} / {max(d):.3f}" if d else "n/a"
    print(f"| median / largest ({len(r)} drives) | {statistics.median(a):.4f} / {max(a):.4f} | {dm} | |")
PY
