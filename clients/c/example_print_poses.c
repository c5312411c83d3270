/*
 * Prints the poses a running liod publishes, one line each, with liod_pose.h:
 *
 *   cc -std=c99 -o print_poses example_print_poses.c          (the header in /usr/include/liod)
 *   ./print_poses [--socket /run/liod/pose.sock] [--count N] [--scan-only] [--health]
 *
 * A line: "scan|imu SEQ TIME X Y Z QX QY QZ QW FLAGS STATUS", numbers with 17 significant digits
 * (a double's exact decimal round trip), e.g. for a program that parses them; health messages
 * (--health) as "health SEQ JSON". Exits 0 after N poses (or when liod closes the socket after
 * some), 1 when it cannot connect or nothing came for 5 s.
 */
#define _POSIX_C_SOURCE 200809L
#include <liod/liod_pose.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void print_pose(const struct liod_message* m) {
  const struct liod_pose* p = &m->pose;
  char status[256];
  printf("%s %lu %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %lu %s %lu %.17g %.17g %.17g\n",
         m->type == LIOD_MSG_SCAN_POSE ? "scan" : "imu", (unsigned long)m->sequence, p->time, p->position[0],
         p->position[1], p->position[2], p->orientation[0], p->orientation[1], p->orientation[2], p->orientation[3],
         (unsigned long)p->flags, liod_flag_names(p->flags, status, sizeof status),
         (unsigned long)p->correction_sequence, p->map_position[0], p->map_position[1], p->map_position[2]);
}

int main(int argc, char** argv) {
  const char* path = LIOD_POSE_DEFAULT_SOCKET;
  long count = 0, poses = 0;
  int scan_only = 0, health = 0, i, status = LIOD_READ_MESSAGE;
  struct liod_client client;
  struct liod_message m;
  for (i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--socket") == 0 && i + 1 < argc) path = argv[++i];
    else if (strcmp(argv[i], "--count") == 0 && i + 1 < argc) count = strtol(argv[++i], NULL, 10);
    else if (strcmp(argv[i], "--scan-only") == 0) scan_only = 1;
    else if (strcmp(argv[i], "--health") == 0) health = 1;
    else {
      fprintf(stderr, "usage: %s [--socket PATH] [--count N] [--scan-only] [--health]\n", argv[0]);
      return 2;
    }
  }
  if (liod_client_open(&client, path) != 0) {
    perror(path);
    return 1;
  }
  if (scan_only && liod_client_request(&client, "scan") != 0) perror("request");
  while (count == 0 || poses < count) {
    status = liod_client_read(&client, &m, 5000);
    if (status != LIOD_READ_MESSAGE) {
      if (status == LIOD_READ_INVALID) fprintf(stderr, "%s: not a liod protocol v2 stream\n", path);
      if (status == LIOD_READ_TIMEOUT) fprintf(stderr, "%s: nothing for 5 s\n", path);
      break;
    }
    if (m.type == LIOD_MSG_HEALTH) {
      if (health) printf("health %lu %.*s\n", (unsigned long)m.sequence, (int)m.health_length, m.health);
      continue;
    }
    print_pose(&m);
    ++poses;
  }
  fflush(stdout);
  liod_client_close(&client);
  return poses > 0 && (count == 0 || poses == count || status == LIOD_READ_CLOSED) ? 0 : 1;
}
