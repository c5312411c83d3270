#!/usr/bin/env bash
# Measures each paper component's effect: simulated drives (several routes and seeds) replayed
# with the full method and with one component switched off at a time; prints a Markdown table
# of ATE RMSE, KITTI drift and front-end time. Expects a built tree (scripts/demo.sh builds one).
#   scripts/ablation.sh [--routes "urban highway"] [--seeds "1 2"] [--duration 60] [--max-speed 12]
set -euo pipefail
cd "$(dirname "$0")/.."
routes="urban highway" seeds="1 2" duration=60 speed=12 work=out/ablation
while [ $# -gt 0 ]; do
  case "$1" in
    --routes) routes=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    --duration) duration=$2; shift 2 ;;
    --max-speed) speed=$2; shift 2 ;;
    --out) work=$2; shift 2 ;;
    *) echo "ablation.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
bin=${LIOD_BIN:-build/bin}
mkdir -p "$work"

variants=(
  "full|"
  "fixed curvature (5+5)|odometry: {curvature: fixed}"
  "no posts (edges on fitted lines only)|odometry: {post_edges: false}"
  "posts' edges where the returns were (not by their axis)|odometry: {post_max_width_m: 0}"
  "rail border crossings kept as edges|odometry: {crossing_edge_tolerance_m: 0}"
  "no beam calibration (published angles as they are)|odometry: {beam_calibration: false}"
  "no beam range offsets (elevations only)|odometry: {beam_range_calibration: false}"
  "no Hausdorff gating|odometry: {keyframe_gating: distance_angle}"
  "window of 25 keyframes (the paper)|odometry: {window_keyframes: 25}"
  "constant-velocity deskew|odometry: {deskew: constant_velocity}"
  "no deskew|odometry: {deskew: none}"
)

printf '| variant | drive | ATE RMSE (m) | KITTI trans. (%%) | KITTI rot. (deg/100 m) | front end median / p99 (ms) |\n'
printf '|---|---|---|---|---|---|\n'
for route in $routes; do
  for seed in $seeds; do
    drive="$work/${route}_s${seed}"
    mkdir -p "$drive"
    if [ ! -f "$drive/groundtruth.tum" ]; then
      "$bin/liod-sim" --route "$route" --seed "$seed" --duration "$duration" --max-speed "$speed" --out "$drive" >/dev/null
    fi
    for v in "${variants[@]}"; do
      name=${v%%|*}
      overlay=${v#*|}
      tag=$(echo "$name" | tr -c 'a-zA-Z0-9' '_')
      printf '%s\n' "$overlay" > "$drive/variant_$tag.yaml"
      "$bin/liod" --log-level warn replay --no-progress --config config/liod.yaml --config config/vehicles/liod-sim-car.yaml \
        --config "$drive/extrinsics.yaml" \
        --config "$drive/variant_$tag.yaml" --pcap "$drive/lidar.pcap" --imu "$drive/imu.csv" \
        --trajectory "$drive/est_$tag.tum" > "$drive/replay_$tag.txt"
      timing=$(grep -o 'median [0-9.]* ms, p99 [0-9.]* ms' "$drive/replay_$tag.txt" | awk '{print $2" / "$5}')
      "$bin/liod-eval" --gt "$drive/groundtruth.tum" --est "$drive/est_$tag.tum" --json > "$drive/eval_$tag.json" || true
      python3 - "$drive/eval_$tag.json" "$name" "${route} s${seed}" "$timing" <<'PY'
import json, sys
path, name, drive, timing = sys.argv[1:5]
try:
    e = json.load(open(path))
except Exception:
    print(f"| {name} | {drive} | failed | | | {timing} |"); sys.exit()
def get(d, *keys):
    for k in keys:
        if not isinstance(d, dict) or k not in d or d[k] is None: return None
        d = d[k]
    return d
ate = get(e, "ate", "rmse_m")
kt = get(e, "kitti", "translational_pct")
kr = get(e, "kitti", "rotational_deg_per_100m")
f = lambda v, p: "n/a" if v is None else f"{v:.{p}f}"
print(f"| {name} | {drive} | {f(ate,3)} | {f(kt,3)} | {f(kr,4)} | {timing} |")
PY
    done
  done
done
