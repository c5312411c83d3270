#!/usr/bin/env bash
# The main job: installs what is missing, builds liod, simulates a 60 s urban drive with a loop
# (RS-Helios-5515 packets + 200 Hz MEMS IMU), replays it through liod's pipeline and prints the
# trajectory accuracy against the simulator's ground truth.
#   scripts/demo.sh [--route urban] [--seed 1] [--duration 60] [--max-speed 12] [--out out/demo]
set -euo pipefail
cd "$(dirname "$0")/.."
route=urban seed=1 duration=60 speed=12 out=out/demo
while [ $# -gt 0 ]; do
  case "$1" in
    --route) route=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --duration) duration=$2; shift 2 ;;
    --max-speed) speed=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "demo.sh: unknown option $1" >&2; exit 2 ;;
  esac
done

bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target liod liod-sim liod-eval

mkdir -p "$out"
echo "== simulating a ${duration} s ${route} drive (seed ${seed}, up to ${speed} m/s) into ${out}"
build/bin/liod-sim --route "$route" --seed "$seed" --duration "$duration" --max-speed "$speed" --out "$out"
configs=(--config config/liod.yaml --config config/vehicles/liod-sim-car.yaml --config "$out/extrinsics.yaml")
echo "== replaying it through liod: odometry only"
build/bin/liod replay "${configs[@]}" --pcap "$out/lidar.pcap" --imu "$out/imu.csv" \
  --trajectory "$out/odometry.tum" --scan-log "$out/scans.csv"
echo "== replaying it through liod: odometry + loop closure (config/examples/slam.yaml)"
build/bin/liod replay "${configs[@]}" --config config/examples/slam.yaml --pcap "$out/lidar.pcap" \
  --imu "$out/imu.csv" --trajectory "$out/slam.tum"
echo "== accuracy of the odometry against the ground truth"
build/bin/liod-eval --gt "$out/groundtruth.tum" --est "$out/odometry.tum" --plot "$out/odometry.png"
echo "== accuracy with loop closure"
build/bin/liod-eval --gt "$out/groundtruth.tum" --est "$out/slam.tum" --plot "$out/slam.png"
echo "plots: $out/odometry.png $out/slam.png"
