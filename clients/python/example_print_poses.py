#!/usr/bin/env python3
"""Prints the poses a running liod publishes, one line each, with liod_pose.py:

    python3 example_print_poses.py [--socket /run/liod/pose.sock] [--count N] [--scan-only] [--health]

A line: "scan|imu SEQ TIME X Y Z QX QY QZ QW FLAGS STATUS", numbers as Python's repr (the shortest
text that reads back as the same double); health messages (--health) as "health SEQ JSON". The
module is found installed (/usr/lib/python3/dist-packages) or beside this file (a checkout).
"""
import argparse
import os
import sys

sys.path.append(os.path.dirname(os.path.abspath(__file__)))
import liod_pose  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--socket", default=liod_pose.DEFAULT_SOCKET)
    parser.add_argument("--count", type=int, default=0, help="exit after this many poses (0: until liod goes away)")
    parser.add_argument("--scan-only", action="store_true", help="scan-rate poses only")
    parser.add_argument("--health", action="store_true", help="also print the health messages")
    parser.add_argument("--timeout", type=float, default=5.0, help="give up after this long without a message (s)")
    args = parser.parse_args()
    poses = 0
    with liod_pose.PoseClient(args.socket, timeout=args.timeout, scan_only=args.scan_only) as client:
        for m in client:
            if isinstance(m, liod_pose.HealthMessage):
                if args.health:
                    print("health", m.sequence, m.text, flush=True)
                continue
            kind = "scan" if m.type == liod_pose.MessageType.SCAN_POSE else "imu"
            numbers = " ".join(repr(v) for v in (m.time, *m.position, *m.orientation))
            map_numbers = " ".join(repr(v) for v in m.map_position)
            print(kind, m.sequence, numbers, m.flags, m.status, m.correction_sequence, map_numbers, flush=True)
            poses += 1
            if poses == args.count:
                break
    return 0 if poses > 0 and (args.count == 0 or poses == args.count or client.closed) else 1


if __name__ == "__main__":
    sys.exit(main())
