#!/usr/bin/env bash
# Relocalisation on simulated town pairs (docs/results.md, "Relocalisation"): for each seed, drive A
# (liod-sim's default urban route) maps the town into a state directory; drive B, another route
# through the same town (--route-seed, the first of SEED*1000+1.. that drives at least 8 s along A's
# streets, starting 2-45 s in), replays on that state; then B replays on the state of the next
# seed's town, where it must never be placed. Prints one line per pair.
#   scripts/relocalization/pairs.sh OUT_DIR SEED...      (after building liod and liod-sim)
set -euo pipefail
out=$1; shift
root=$(cd "$(dirname "$0")/../.." && pwd)
here="$root/scripts/relocalization"
sim="$root/build/bin/liod-sim"
mkdir -p "$out"
replay() {  # drive state log
  printf 'backend:\n  enabled: true\n  persist: true\noutput:\n  state_dir: %s\n' "$2" > "$2.yaml"
  "$root/build/bin/liod" replay --config "$root/config/liod.yaml" --config "$root/config/vehicles/liod-sim-car.yaml" \
    --config "$1/extrinsics.yaml" --config "$2.yaml" --pcap "$1/lidar.pcap" --imu "$1/imu.csv" \
    --trajectory "$3.tum" --map-frame-trajectory "$3.map.tum" > "$3.log" 2>&1
}
for s in "$@"; do
  w="$out/town$s"; mkdir -p "$w/a" "$w/b"
  [ -f "$w/a/imu.csv" ] || "$sim" --route urban --seed "$s" --duration 60 --out "$w/a" --quiet
  for r in $(seq 1 15); do
    "$sim" --route urban --seed "$s" --duration 60 --route-seed $((1000 * s + r)) --out "$w/b" --quiet
    first=$(python3 "$here/stretch.py" "$w/a/groundtruth.tum" "$w/b/groundtruth.tum" 8 | sed -n 's/^enters.*: \([0-9.]*\)$/\1/p')
    if [ -n "$first" ] && python3 -c "import sys; sys.exit(0 if 2 < $first < 45 else 1)"; then break; fi
  done
  rm -rf "$w/state"; mkdir -p "$w/state"
  replay "$w/a" "$w/state" "$w/a-run"
  cp -r "$w/state" "$w/map-of-a"   # A's map alone, for the next seed's drive B
  replay "$w/b" "$w/state" "$w/b-run"
  echo "town $s, B route seed $((1000 * s + r)): $(grep 'in the saved map' "$w/b-run.log" | tail -1) |" \
       "$(python3 "$here/score_pair.py" "$w/a/groundtruth.tum" "$w/a-run.map.tum" "$w/b/groundtruth.tum" "$w/b-run.map.tum")"
done
seeds=("$@")
for i in "${!seeds[@]}"; do
  s=${seeds[$i]}; o=${seeds[$(( (i + 1) % ${#seeds[@]} ))]}
  [ "$s" = "$o" ] && continue
  x="$out/town$s-in-town$o"; rm -rf "$x"; cp -r "$out/town$o/map-of-a" "$x"
  replay "$out/town$s/b" "$x" "$x-run"
  echo "drive B of town $s in the map of town $o: $(grep 'in the saved map' "$x-run.log" | tail -1), $(grep -vc '^#' "$x-run.map.tum" || true) poses placed"
done
