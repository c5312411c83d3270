#!/usr/bin/env python3
"""Logs the poses a running liod publishes to a CSV file, with liod_pose.py:

    python3 example_log_csv.py --out poses.csv [--socket /run/liod/pose.sock] [--count N] [--scan-only]

One row a pose: type, sequence, time (s), position (m), orientation quaternion x y z w, velocity
(m/s), angular rate (rad/s), the position and rotation standard deviations (square roots of the
covariance's diagonal: m, rad), flags and their names; every value exactly as received (repr).
Health reports go to stderr as one summary line each.
"""
import argparse
import csv
import math
import os
import sys

sys.path.append(os.path.dirname(os.path.abspath(__file__)))
import liod_pose  # noqa: E402

COLUMNS = ["type", "seq", "time", "x", "y", "z", "qx", "qy", "qz", "qw", "vx", "vy", "vz", "wx", "wy", "wz",
           "sd_x", "sd_y", "sd_z", "sd_roll", "sd_pitch", "sd_yaw", "flags", "status"]


def row(m: liod_pose.PoseMessage) -> list:
    sds = [math.sqrt(max(0.0, m.covariance_at(i, i))) for i in range(6)]
    kind = "scan" if m.type == liod_pose.MessageType.SCAN_POSE else "imu"
    numbers = [m.time, *m.position, *m.orientation, *m.velocity, *m.angular_rate, *sds]
    return [kind, m.sequence, *(repr(v) for v in numbers), m.flags, m.status]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="CSV file to write ('-': standard output)")
    parser.add_argument("--socket", default=liod_pose.DEFAULT_SOCKET)
    parser.add_argument("--count", type=int, default=0, help="exit after this many poses (0: until liod goes away)")
    parser.add_argument("--scan-only", action="store_true", help="scan-rate poses only")
    parser.add_argument("--timeout", type=float, default=5.0, help="give up after this long without a message (s)")
    args = parser.parse_args()
    out = sys.stdout if args.out == "-" else open(args.out, "w", newline="")
    writer = csv.writer(out)
    writer.writerow(COLUMNS)
    poses = 0
    with liod_pose.PoseClient(args.socket, timeout=args.timeout, scan_only=args.scan_only) as client:
        for m in client:
            if isinstance(m, liod_pose.HealthMessage):
                health = m.data
                odometry = health.get("odometry", {})
                print(f"health: {odometry.get('scans')} scans, {odometry.get('scan_rate_hz')} Hz", file=sys.stderr)
                continue
            writer.writerow(row(m))
            poses += 1
            if poses == args.count:
                break
    out.flush()
    if out is not sys.stdout:
        out.close()
    return 0 if poses > 0 and (args.count == 0 or poses == args.count or client.closed) else 1


if __name__ == "__main__":
    sys.exit(main())
