"""A client of liod's pose socket, protocol version 2, using only the standard library.

The protocol is docs/pose-protocol.md (installed as /usr/share/doc/liod/pose-protocol.md)::

    import liod_pose
    with liod_pose.PoseClient("/run/liod/pose.sock") as client:
        for message in client:                      # ends when liod closes the socket
            if isinstance(message, liod_pose.PoseMessage) and message.ok:
                print(message.time, message.position)
            elif isinstance(message, liod_pose.HealthMessage):
                print(message.data["odometry"]["scans"])

Every multi-byte field is little-endian and doubles are IEEE-754 binary64, whatever the host
(docs/pose-protocol.md, "Messages"): the struct formats below say "<" explicitly.
"""

from __future__ import annotations

import enum
import json
import select
import socket
import struct
from dataclasses import dataclass
from typing import Iterator, Optional, Tuple, Union

DEFAULT_SOCKET = "/run/liod/pose.sock"
VERSION = 2
MAGIC = b"LIOD"
# magic, version, type, length of the whole message, sequence number
HEADER = struct.Struct("<4sHHII")
# time, position[3], orientation xyzw[4], velocity[3], angular rate[3], covariance[21], flags,
# correction sequence, map position[3], map orientation xyzw[4]
POSE_BODY = struct.Struct("<" + "d" * 35 + "II" + "d" * 7)
POSE_MESSAGE_SIZE = HEADER.size + POSE_BODY.size  # 360
MAX_MESSAGE_SIZE = 1 << 20


class MessageType(enum.IntEnum):
    SCAN_POSE = 1
    IMU_POSE = 2
    HEALTH = 3


class Flag(enum.IntFlag):
    """Status flags (docs/pose-protocol.md, "Status flags")."""

    INITIALIZING = 1 << 0
    OK = 1 << 1
    DEGENERATE = 1 << 2
    IMU_LOST = 1 << 3
    LIDAR_LOST = 1 << 4
    KEYFRAME = 1 << 5
    FEW_FEATURES = 1 << 6
    CLOCK_JUMP = 1 << 7
    IMU_INCONSISTENT = 1 << 8
    IMPLAUSIBLE = 1 << 9
    SWEEP_TRUNCATED = 1 << 10
    CALIBRATION_CHANGED = 1 << 11
    IMU_SATURATED = 1 << 12
    STALE = 1 << 13
    NOT_LOCALIZED = 1 << 14
    EXTRINSICS_SUSPECT = 1 << 15


def flag_names(flags: int) -> str:
    """The set flags as liod spells them, joined by "|" ("ok|keyframe"), or "none"."""
    names = []
    for bit in range(32):
        if flags & (1 << bit):
            try:
                names.append(Flag(1 << bit).name.lower())
            except ValueError:
                names.append(f"bit{bit}")
    return "|".join(names) if names else "none"


Vector3 = Tuple[float, float, float]


@dataclass(frozen=True)
class PoseMessage:
    """A scan-rate (type 1) or IMU-rate (type 2) pose, in the protocol's units and frames."""

    type: MessageType
    sequence: int
    time: float  # s, the IMU clock (Unix epoch on a synchronised vehicle)
    position: Vector3  # m, body (IMU) origin in the odometry frame (continuous)
    orientation: Tuple[float, float, float, float]  # quaternion x, y, z, w: body to odometry frame
    velocity: Vector3  # m/s, odometry frame
    angular_rate: Vector3  # rad/s, body frame
    covariance: Tuple[float, ...]  # 21 values: upper triangle, row by row, of [position, rotation error]
    flags: int
    correction_sequence: int  # +1 each time the map correction changes; 0 before the first
    map_position: Vector3  # m, body origin in the map frame (jumps when a loop closes)
    map_orientation: Tuple[float, float, float, float]  # quaternion x, y, z, w: body to map frame

    @property
    def ok(self) -> bool:
        """Whether a controller may use the pose (flag ok)."""
        return bool(self.flags & Flag.OK)

    @property
    def status(self) -> str:
        return flag_names(self.flags)

    def covariance_at(self, row: int, col: int) -> float:
        """Element (row, col) of the 6x6 covariance, either triangle."""
        r, c = min(row, col), max(row, col)
        return self.covariance[r * 6 - r * (r - 1) // 2 + (c - r)]

    def covariance_matrix(self) -> list:
        """The 6x6 covariance as a list of rows."""
        return [[self.covariance_at(r, c) for c in range(6)] for r in range(6)]


@dataclass(frozen=True)
class HealthMessage:
    """A health report (type 3): its JSON text and, decoded, its data."""

    sequence: int
    text: str

    @property
    def data(self) -> dict:
        return json.loads(self.text)


Message = Union[PoseMessage, HealthMessage]


class ProtocolError(Exception):
    """The bytes are not a liod protocol version 2 stream (wrong magic, version, type or length)."""


def decode(buffer: Union[bytes, bytearray, memoryview]) -> Tuple[Optional[Message], int]:
    """Decodes the message at the front of `buffer`: (message, its length), or (None, 0) when the
    buffer holds only the start of one. Raises ProtocolError on a stream that is not liod v2."""
    view = memoryview(buffer)
    prefix = bytes(view[:4])
    if prefix != MAGIC[: len(prefix)]:
        raise ProtocolError(f"bad magic {prefix!r}")
    if len(view) < HEADER.size:
        return None, 0
    _, version, kind, length, sequence = HEADER.unpack_from(view)
    if version != VERSION:
        raise ProtocolError(f"protocol version {version}, this client reads {VERSION}")
    if kind in (MessageType.SCAN_POSE, MessageType.IMU_POSE):
        if length != POSE_MESSAGE_SIZE:
            raise ProtocolError(f"pose message of {length} bytes")
    elif kind == MessageType.HEALTH:
        if not HEADER.size <= length <= MAX_MESSAGE_SIZE:
            raise ProtocolError(f"health message of {length} bytes")
    else:
        raise ProtocolError(f"message type {kind}")
    if len(view) < length:
        return None, 0
    if kind == MessageType.HEALTH:
        return HealthMessage(sequence, bytes(view[HEADER.size : length]).decode("utf-8")), length
    f = POSE_BODY.unpack_from(view, HEADER.size)
    pose = PoseMessage(
        type=MessageType(kind),
        sequence=sequence,
        time=f[0],
        position=(f[1], f[2], f[3]),
        orientation=(f[4], f[5], f[6], f[7]),
        velocity=(f[8], f[9], f[10]),
        angular_rate=(f[11], f[12], f[13]),
        covariance=tuple(f[14:35]),
        flags=f[35],
        correction_sequence=f[36],
        map_position=(f[37], f[38], f[39]),
        map_orientation=(f[40], f[41], f[42], f[43]),
    )
    return pose, length


class PoseClient:
    """A connection to the pose socket (binary mode; scan-rate and IMU-rate poses unless
    scan_only). `timeout` (s) bounds each wait for bytes: read() returns None, iteration stops."""

    def __init__(self, path: str = DEFAULT_SOCKET, timeout: Optional[float] = 5.0, scan_only: bool = False):
        self.timeout = timeout
        self._buffer = bytearray()
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            self._sock.connect(path)
        except OSError:
            self._sock.close()
            raise
        self.closed = False
        if scan_only:
            self.request("scan")

    def request(self, line: str) -> None:
        """Sends a request line: "scan", "all" (docs/pose-protocol.md, "Requests"). "json" would
        switch the server to text lines, which this binary client does not read."""
        self._sock.sendall(line.encode("ascii") + b"\n")

    def read(self) -> Optional[Message]:
        """The next message; None on timeout or when liod closed the socket (then `closed`)."""
        while True:
            message, used = decode(self._buffer)
            if message is not None:
                del self._buffer[:used]
                return message
            if self.closed:
                return None
            ready, _, _ = select.select([self._sock], [], [], self.timeout)
            if not ready:
                return None
            chunk = self._sock.recv(65536)
            if not chunk:
                self.closed = True
                return None
            self._buffer += chunk

    def __iter__(self) -> Iterator[Message]:
        while True:
            message = self.read()
            if message is None:
                return
            yield message

    def poses(self) -> Iterator[PoseMessage]:
        """The pose messages only."""
        return (m for m in self if isinstance(m, PoseMessage))

    def close(self) -> None:
        self._sock.close()
        self.closed = True

    def __enter__(self) -> "PoseClient":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
