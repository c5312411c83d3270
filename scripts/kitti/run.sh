#!/usr/bin/env bash
# KITTI raw against RS-Helios on the same route (docs/results.md, "KITTI raw layout"; issue 58): for
# each seed, the route driven twice by liod-sim with the same world, trajectory, mounting and IMU
# samples (100 Hz, the OXTS extract's rate): once with the Velodyne HDL-64E written in KITTI raw's
# layout (--lidar hdl64e), replayed by `liod replay --kitti-raw` and scored by liod-eval against the
# drive's oxts/ (the devkit's conversion), once with the RS-Helios (--imu-rate 100), replayed from
# its pcap and scored against groundtruth.tum. Both replays use config/liod.yaml +
# config/vehicles/liod-sim-car.yaml (the Helios also its extrinsics.yaml; the KITTI drive its
# calib_imu_to_velo.txt). Prints one row per seed: ATE RMSE and KITTI drift of each, their ratio.
#   scripts/kitti/run.sh [--route urban] [--duration 60] [--max-speed 12] OUT_DIR SEED...
#                                                  (after building liod, liod-sim, liod-eval)
# Drives already simulated in OUT_DIR with the same options are reused. Each step runs under
# flock /tmp/liod-build.lock when flock exists (the build machines share their cores).
set -euo pipefail
route=urban duration=60 speed=12
while [ $# -gt 0 ]; do
  case "$1" in
    --route) route=$2; shift 2 ;;
    --duration) duration=$2; shift 2 ;;
    --max-speed) speed=$2; shift 2 ;;
    -*) echo "run.sh: unknown option $1" >&2; exit 2 ;;
    *) break ;;
  esac
done
[ $# -ge 2 ] || { echo "usage: scripts/kitti/run.sh [options] OUT_DIR SEED..." >&2; exit 2; }
out=$1; shift
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${LIOD_BIN:-$root/build/bin}
lock=(); command -v flock >/dev/null && lock=(flock /tmp/liod-build.lock)
config=(--config "$root/config/liod.yaml" --config "$root/config/vehicles/liod-sim-car.yaml")

# simulate DIR OPTIONS...: a drive, unless DIR already holds it with these options
simulate() {
  local d=$1; shift
  mkdir -p "$d"
  if [ ! -f "$d/groundtruth.tum" ] || [ "$(cat "$d/sim-options" 2>/dev/null)" != "$*" ]; then
    "${lock[@]}" "$bin/liod-sim" "$@" --quiet --out "$d"
    echo "$*" > "$d/sim-options"
  fi
}
# score GT EST: "ATE drift" from liod-eval's JSON ("nan nan" when it fails)
score() {
  "$bin/liod-eval" --gt "$1" --est "$2" --json 2>/dev/null | python3 -c '
import json, sys
try:
    e = json.load(sys.stdin); d = e["kitti"]["translational_pct"]
    print(e["ate"]["rmse_m"], "nan" if d is None else d)
except Exception:
    print("nan nan")'
}

printf '| seed | HDL-64E (KITTI raw) ATE m / drift %% | RS-Helios ATE m / drift %% | ratio ATE / drift |\n|---|---|---|---|\n'
for s in "$@"; do
  opts=(--route "$route" --seed "$s" --duration "$duration" --max-speed "$speed")
  k="$out/${route}_s${s}_hdl64e" h="$out/${route}_s${s}_helios"
  simulate "$k" --lidar hdl64e "${opts[@]}"
  simulate "$h" --imu-rate 100 "${opts[@]}"
  drive=$(sed -n 's/^  kitti_raw_drive: "\(.*\)"/\1/p' "$k/scenario.yaml")
  "${lock[@]}" "$bin/liod" --log-level warn replay --no-progress "${config[@]}" --kitti-raw "$drive" \
    --trajectory "$k/odometry.tum" > "$k/replay.txt" 2>&1 || true
  "${lock[@]}" "$bin/liod" --log-level warn replay --no-progress "${config[@]}" --config "$h/extrinsics.yaml" \
    --pcap "$h/lidar.pcap" --imu "$h/imu.csv" --trajectory "$h/odometry.tum" > "$h/replay.txt" 2>&1 || true
  read -r ka kd < <(score "$drive" "$k/odometry.tum")
  read -r ha hd < <(score "$h/groundtruth.tum" "$h/odometry.tum")
  python3 -c '
import sys
s, ka, kd, ha, hd = sys.argv[1], *map(float, sys.argv[2:])
r = lambda a, b: f"{a / b:.2f}" if b > 0 else "n/a"
print(f"| {s} | {ka:.4f} / {kd:.3f} | {ha:.4f} / {hd:.3f} | {r(ka, ha)} / {r(kd, hd)} |")' "$s" "$ka" "$kd" "$ha" "$hd"
done
