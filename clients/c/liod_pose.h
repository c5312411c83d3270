/*
 * liod_pose.h: a C99 client of liod's pose socket, protocol version 2 (docs/pose-protocol.md,
 * installed as /usr/share/doc/liod/pose-protocol.md). One header, no dependency beyond libc and
 * POSIX sockets; every function is static inline, so include it from any number of files.
 *
 *   #define _POSIX_C_SOURCE 200809L      (before any system header, when compiling with -std=c99)
 *   #include <liod/liod_pose.h>
 *
 *   struct liod_client c;
 *   struct liod_message m;
 *   if (liod_client_open(&c, LIOD_POSE_DEFAULT_SOCKET) != 0) ...;       (errno says why)
 *   while (liod_client_read(&c, &m, 5000) == LIOD_READ_MESSAGE)
 *     if (m.type == LIOD_MSG_SCAN_POSE) use(&m.pose);
 *   liod_client_close(&c);
 *
 * Decoding alone (liod_decode) needs no socket: define LIOD_POSE_NO_SOCKET to leave the client
 * out on a system without POSIX sockets.
 *
 * Byte order: the protocol fixes every multi-byte field as little-endian and doubles as IEEE-754
 * binary64 (docs/pose-protocol.md, "Messages"). Fields are assembled byte by byte here, so the
 * host's byte order and the buffer's alignment never matter.
 */
#ifndef LIOD_POSE_H
#define LIOD_POSE_H

#if !defined(LIOD_POSE_NO_SOCKET) && !defined(_POSIX_C_SOURCE) && !defined(_GNU_SOURCE) && !defined(_DEFAULT_SOURCE)
/* Effective only when no system header came before this one; otherwise define it yourself. */
#define _POSIX_C_SOURCE 200809L
#endif

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Header: magic "LIOD", version, type, length of the whole message, sequence number. */
#define LIOD_POSE_VERSION 2u
#define LIOD_POSE_HEADER_SIZE 16u
#define LIOD_POSE_MESSAGE_SIZE 360u
/* The largest message liod sends or a client accepts (a health message's JSON). */
#define LIOD_POSE_MAX_MESSAGE_SIZE (1u << 20)
#define LIOD_POSE_DEFAULT_SOCKET "/run/liod/pose.sock"

enum liod_message_type {
  LIOD_MSG_SCAN_POSE = 1, /* scan-rate pose */
  LIOD_MSG_IMU_POSE = 2,  /* IMU-rate pose */
  LIOD_MSG_HEALTH = 3     /* health: UTF-8 JSON body */
};

/* Status flags (docs/pose-protocol.md, "Status flags"): bit i of liod_pose.flags. */
enum liod_pose_flag {
  LIOD_FLAG_INITIALIZING = 1u << 0,
  LIOD_FLAG_OK = 1u << 1, /* a controller may use the pose */
  LIOD_FLAG_DEGENERATE = 1u << 2,
  LIOD_FLAG_IMU_LOST = 1u << 3,
  LIOD_FLAG_LIDAR_LOST = 1u << 4,
  LIOD_FLAG_KEYFRAME = 1u << 5,
  LIOD_FLAG_FEW_FEATURES = 1u << 6,
  LIOD_FLAG_CLOCK_JUMP = 1u << 7,
  LIOD_FLAG_IMU_INCONSISTENT = 1u << 8,
  LIOD_FLAG_IMPLAUSIBLE = 1u << 9,
  LIOD_FLAG_SWEEP_TRUNCATED = 1u << 10,
  LIOD_FLAG_CALIBRATION_CHANGED = 1u << 11,
  LIOD_FLAG_IMU_SATURATED = 1u << 12,
  LIOD_FLAG_STALE = 1u << 13,        /* published long after its input arrived: not ok */
  LIOD_FLAG_NOT_LOCALIZED = 1u << 14, /* the map-frame pose is the odometry pose: no backend */
  LIOD_FLAG_EXTRINSICS_SUSPECT = 1u << 15 /* the configured LiDAR-IMU extrinsic or time offset looks off */
};
#define LIOD_FLAG_COUNT 16

/* A pose message's body (types 1 and 2), in the protocol's units and frames. */
struct liod_pose {
  double time;            /* s, the IMU clock (Unix epoch on a synchronised vehicle) */
  double position[3];     /* m, body (IMU) origin in the odometry frame (continuous) */
  double orientation[4];  /* quaternion x, y, z, w: body to odometry frame */
  double velocity[3];     /* m/s, odometry frame */
  double angular_rate[3]; /* rad/s, body frame */
  double covariance[21];  /* upper triangle, row by row, of the 6x6 covariance of
                             [position x y z (m), rotation error x y z (rad)]: liod_pose_cov() */
  uint32_t flags;         /* enum liod_pose_flag */
  uint32_t correction_sequence; /* +1 each time the map correction changes; 0 before the first */
  double map_position[3];       /* m, body origin in the map frame (jumps when a loop closes) */
  double map_orientation[4];    /* quaternion x, y, z, w: body to map frame */
};

struct liod_message {
  uint16_t type;       /* enum liod_message_type */
  uint32_t sequence;   /* the server's message counter: a gap means this client skipped messages */
  uint32_t length;     /* of the whole message, bytes */
  struct liod_pose pose; /* types 1 and 2 */
  /* Type 3: the JSON body, not NUL-terminated; it points into the buffer given to liod_decode
   * (or the client's), valid until that buffer changes (the next liod_client_read). */
  const char* health;
  size_t health_length;
};

enum liod_decode_status {
  LIOD_DECODE_OK = 0,        /* a message was decoded; *consumed is its length */
  LIOD_DECODE_NEED_MORE = 1, /* the bytes are the start of a message: read more */
  LIOD_DECODE_INVALID = -1   /* not a liod v2 stream: wrong magic, version, type or length */
};

static inline uint16_t liod_get_u16le(const unsigned char* p) { return (uint16_t)(p[0] | (p[1] << 8)); }

static inline uint32_t liod_get_u32le(const unsigned char* p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static inline double liod_get_f64le(const unsigned char* p) {
  uint64_t bits = 0;
  double d;
  int i;
  for (i = 7; i >= 0; --i) bits = (bits << 8) | p[i];
  /* The 64 bits are the binary64 value; copying them is how C99 reinterprets without aliasing UB. */
  memcpy(&d, &bits, sizeof d);
  return d;
}

/* Element (row, col) of the 6x6 pose covariance, either triangle (0 <= row, col < 6). */
static inline double liod_pose_cov(const struct liod_pose* pose, int row, int col) {
  int r = row < col ? row : col;
  int c = row < col ? col : row;
  /* Rows before r hold 6 + 5 + ... entries: r * 6 - r * (r - 1) / 2. */
  return pose->covariance[r * 6 - r * (r - 1) / 2 + (c - r)];
}

/* The name of flag bit `bit` (0..LIOD_FLAG_COUNT-1) as docs/pose-protocol.md and `liod pose`
 * spell it, or NULL. */
static inline const char* liod_flag_name(int bit) {
  static const char* const names[LIOD_FLAG_COUNT] = {
      "initializing", "ok",          "degenerate",      "imu_lost",            "lidar_lost",
      "keyframe",     "few_features", "clock_jump",     "imu_inconsistent",    "implausible",
      "sweep_truncated", "calibration_changed", "imu_saturated", "stale",            "not_localized",
      "extrinsics_suspect"};
  return bit >= 0 && bit < LIOD_FLAG_COUNT ? names[bit] : NULL;
}

/* Writes the set flags' names joined by '|' ("ok|keyframe"; "none" when none is set, unknown bits
 * as "bitN") into buf, truncated to size - 1 bytes; returns buf. */
static inline char* liod_flag_names(uint32_t flags, char* buf, size_t size) {
  size_t used = 0;
  int bit;
  if (size == 0) return buf;
  buf[0] = '\0';
  for (bit = 0; bit < 32; ++bit) {
    char unknown[8];
    const char* name = liod_flag_name(bit);
    size_t n;
    if ((flags & (1u << bit)) == 0) continue;
    if (name == NULL) {
      unknown[0] = 'b', unknown[1] = 'i', unknown[2] = 't';
      unknown[3] = (char)('0' + bit / 10), unknown[4] = (char)('0' + bit % 10), unknown[5] = '\0';
      name = unknown;
    }
    if (used > 0 && used + 1 < size) buf[used++] = '|';
    n = strlen(name);
    if (used + n >= size) n = size - 1 - used;
    memcpy(buf + used, name, n);
    used += n;
    buf[used] = '\0';
  }
  if (used == 0) {
    strncpy(buf, "none", size - 1);
    buf[size - 1] = '\0';
  }
  return buf;
}

/* Decodes the message at the front of bytes[0..size). A wrong magic is reported as soon as its
 * bytes are there, a wrong version, type or length once the header is. */
static inline int liod_decode(const unsigned char* bytes, size_t size, struct liod_message* out, size_t* consumed) {
  static const unsigned char magic[4] = {0x4C, 0x49, 0x4F, 0x44};
  uint16_t type;
  uint32_t length;
  size_t i;
  *consumed = 0;
  for (i = 0; i < size && i < 4; ++i) {
    if (bytes[i] != magic[i]) return LIOD_DECODE_INVALID;
  }
  if (size < LIOD_POSE_HEADER_SIZE) return LIOD_DECODE_NEED_MORE;
  if (liod_get_u16le(bytes + 4) != LIOD_POSE_VERSION) return LIOD_DECODE_INVALID;
  type = liod_get_u16le(bytes + 6);
  length = liod_get_u32le(bytes + 8);
  if (type == LIOD_MSG_SCAN_POSE || type == LIOD_MSG_IMU_POSE) {
    if (length != LIOD_POSE_MESSAGE_SIZE) return LIOD_DECODE_INVALID;
  } else if (type == LIOD_MSG_HEALTH) {
    if (length < LIOD_POSE_HEADER_SIZE || length > LIOD_POSE_MAX_MESSAGE_SIZE) return LIOD_DECODE_INVALID;
  } else {
    return LIOD_DECODE_INVALID;
  }
  if (size < length) return LIOD_DECODE_NEED_MORE;
  out->type = type;
  out->length = length;
  out->sequence = liod_get_u32le(bytes + 12);
  out->health = NULL;
  out->health_length = 0;
  if (type == LIOD_MSG_HEALTH) {
    out->health = (const char*)(bytes + LIOD_POSE_HEADER_SIZE);
    out->health_length = length - LIOD_POSE_HEADER_SIZE;
  } else {
    /* Body offsets: docs/pose-protocol.md, "Pose body". */
    struct liod_pose* p = &out->pose;
    p->time = liod_get_f64le(bytes + 16);
    for (i = 0; i < 3; ++i) p->position[i] = liod_get_f64le(bytes + 24 + 8 * i);
    for (i = 0; i < 4; ++i) p->orientation[i] = liod_get_f64le(bytes + 48 + 8 * i);
    for (i = 0; i < 3; ++i) p->velocity[i] = liod_get_f64le(bytes + 80 + 8 * i);
    for (i = 0; i < 3; ++i) p->angular_rate[i] = liod_get_f64le(bytes + 104 + 8 * i);
    for (i = 0; i < 21; ++i) p->covariance[i] = liod_get_f64le(bytes + 128 + 8 * i);
    p->flags = liod_get_u32le(bytes + 296);
    p->correction_sequence = liod_get_u32le(bytes + 300);
    for (i = 0; i < 3; ++i) p->map_position[i] = liod_get_f64le(bytes + 304 + 8 * i);
    for (i = 0; i < 4; ++i) p->map_orientation[i] = liod_get_f64le(bytes + 328 + 8 * i);
  }
  *consumed = length;
  return LIOD_DECODE_OK;
}

#ifndef LIOD_POSE_NO_SOCKET

#include <errno.h>
#include <poll.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <sys/un.h>
#include <unistd.h>

/* A connection to the pose socket and the bytes received but not yet decoded. */
struct liod_client {
  int fd;
  unsigned char* buffer;
  size_t capacity, start, end; /* undecoded bytes: buffer[start..end) */
};

enum liod_read_status {
  LIOD_READ_MESSAGE = 1, /* *out holds the next message */
  LIOD_READ_TIMEOUT = 0, /* no complete message within the timeout; the connection stays */
  LIOD_READ_CLOSED = -1, /* the server closed the connection, or a socket error (errno) */
  LIOD_READ_INVALID = -2 /* the stream is not liod v2 (another version?): disconnected */
};

/* Connects to the socket at `path` (binary mode, scan-rate and IMU-rate poses). Returns 0, or -1
 * with errno set (ENAMETOOLONG for a path that does not fit a sockaddr_un). */
static inline int liod_client_open(struct liod_client* c, const char* path) {
  struct sockaddr_un addr;
  size_t n = strlen(path);
  c->fd = -1;
  c->buffer = NULL;
  c->capacity = c->start = c->end = 0;
  memset(&addr, 0, sizeof addr);
  addr.sun_family = AF_UNIX;
  if (n >= sizeof addr.sun_path) {
    errno = ENAMETOOLONG;
    return -1;
  }
  memcpy(addr.sun_path, path, n + 1);
  c->fd = socket(AF_UNIX, SOCK_STREAM, 0);
  if (c->fd < 0) return -1;
  if (connect(c->fd, (const struct sockaddr*)&addr, sizeof addr) != 0) {
    int saved = errno;
    close(c->fd);
    c->fd = -1;
    errno = saved;
    return -1;
  }
  return 0;
}

static inline void liod_client_close(struct liod_client* c) {
  if (c->fd >= 0) close(c->fd);
  free(c->buffer);
  c->fd = -1;
  c->buffer = NULL;
  c->capacity = c->start = c->end = 0;
}

/* Sends a request line (docs/pose-protocol.md, "Requests"): "json", "binary", "scan" or "all";
 * the newline is added. This client decodes binary mode only: "json" is for readers of lines.
 * Returns 0, or -1 with errno set. */
static inline int liod_client_request(struct liod_client* c, const char* line) {
  char buf[64];
  size_t n = strlen(line);
  size_t sent = 0;
  if (n + 1 > sizeof buf) {
    errno = EINVAL;
    return -1;
  }
  memcpy(buf, line, n);
  buf[n++] = '\n';
  while (sent < n) {
    ssize_t w = send(c->fd, buf + sent, n - sent, MSG_NOSIGNAL);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return -1;
    sent += (size_t)w;
  }
  return 0;
}

/* Makes room for at least `want` more bytes after end: moves the undecoded bytes to the front and
 * grows the buffer up to one largest message plus a read's worth. */
static inline int liod_client_reserve(struct liod_client* c, size_t want) {
  if (c->start > 0) {
    memmove(c->buffer, c->buffer + c->start, c->end - c->start);
    c->end -= c->start;
    c->start = 0;
  }
  if (c->capacity - c->end < want) {
    size_t capacity = c->capacity == 0 ? 65536 : c->capacity * 2;
    unsigned char* grown;
    while (capacity - c->end < want) capacity *= 2;
    grown = (unsigned char*)realloc(c->buffer, capacity);
    if (grown == NULL) return -1;
    c->buffer = grown;
    c->capacity = capacity;
  }
  return 0;
}

/* The next message. Each time it needs more bytes it waits up to timeout_ms for them (< 0: without
 * limit); LIOD_READ_TIMEOUT when none came. */
static inline int liod_client_read(struct liod_client* c, struct liod_message* out, int timeout_ms) {
  for (;;) {
    size_t used = 0;
    struct pollfd pfd;
    ssize_t got;
    int status;
    if (c->fd < 0) return LIOD_READ_CLOSED;
    /* No buffer before the first read: NULL + 0 is not valid C. */
    status = c->buffer == NULL ? LIOD_DECODE_NEED_MORE : liod_decode(c->buffer + c->start, c->end - c->start, out, &used);
    if (status == LIOD_DECODE_OK) {
      c->start += used;
      return LIOD_READ_MESSAGE;
    }
    if (status == LIOD_DECODE_INVALID) {
      close(c->fd);
      c->fd = -1;
      return LIOD_READ_INVALID;
    }
    pfd.fd = c->fd;
    pfd.events = POLLIN;
    pfd.revents = 0;
    status = poll(&pfd, 1, timeout_ms);
    if (status < 0 && errno == EINTR) continue;
    if (status < 0) return LIOD_READ_CLOSED;
    if (status == 0) return LIOD_READ_TIMEOUT;
    if (liod_client_reserve(c, 16384) != 0) return LIOD_READ_CLOSED;
    got = recv(c->fd, c->buffer + c->end, c->capacity - c->end, 0);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) {
      close(c->fd);
      c->fd = -1;
      return LIOD_READ_CLOSED;
    }
    c->end += (size_t)got;
  }
}

#endif /* LIOD_POSE_NO_SOCKET */

#ifdef __cplusplus
}
#endif

#endif /* LIOD_POSE_H */
