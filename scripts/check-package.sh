#!/usr/bin/env bash
# Builds the Debian package from a configured build tree and checks it as installed:
#
#   scripts/check-package.sh BUILD_DIR
#
# 1. builds the `liod` target and the package (cpack -G DEB; cmake/Package.cmake) and lists it;
# 2. unpacks it into a staging root (dpkg-deb -x), where every path README.md's "Running on the
#    vehicle" section and the unit name must be, with /etc/liod/liod.yaml a conffile and the
#    runtime libraries in Depends;
# 3. systemd-analyze verify of the staged unit against the staged binary;
# 4. the staged binary accepts the staged configuration (liod check-config);
# 5. the sysusers.d and tmpfiles.d entries applied to a scratch root make the liod user in the
#    unit's groups and /var/lib/liod owned by it;
# 6. the C header compiles as C99 and the Python module imports, from the staging root.
# Prints what it checked; exits non-zero at the first failure. LIOD_EMULATOR (e.g. "qemu-aarch64-static
# -L SYSROOT", set by scripts/arm64.sh) runs the staged binary of a cross-built package.
set -euo pipefail
build=${1:?usage: scripts/check-package.sh BUILD_DIR}
cd "$(dirname "$0")/.."
src=$PWD
build=$(cd "$build" && pwd)

fail() { echo "check-package: FAILED: $*" >&2; exit 1; }
for tool in cpack dpkg-deb systemd-analyze systemd-sysusers systemd-tmpfiles cc python3; do
  command -v "$tool" >/dev/null || fail "$tool not installed (scripts/install-deps.sh)"
done

echo "== package"
cmake --build "$build" --target liod >/dev/null
rm -rf "$build/package"
(cd "$build" && cpack -G DEB >/dev/null)
debs=("$build"/package/liod_*.deb)
[ ${#debs[@]} -eq 1 ] && [ -f "${debs[0]}" ] || fail "expected one liod_*.deb in $build/package"
deb=${debs[0]}
echo "$(basename "$deb"): $(du -h "$deb" | cut -f1)"
dpkg-deb -c "$deb" | awk '{ print $1, $6 }'

work=$(mktemp -d "${TMPDIR:-/tmp}/liod-check-package.XXXXXX")
trap 'rm -rf "$work"' EXIT
stage=$work/stage
dpkg-deb -x "$deb" "$stage"
dpkg-deb -e "$deb" "$work/control"

echo "== files"
# Debian 12 keeps units in /lib/systemd/system (systemd.pc); later releases in /usr/lib.
unit=
for dir in lib/systemd/system usr/lib/systemd/system; do
  [ -f "$stage/$dir/liod.service" ] && unit=$dir/liod.service
done
[ -n "$unit" ] || fail "no liod.service under /lib/systemd/system or /usr/lib/systemd/system"
expected=(
  usr/bin/liod etc/liod/liod.yaml "$unit"
  usr/lib/sysusers.d/liod.conf usr/lib/tmpfiles.d/liod.conf usr/lib/sysctl.d/60-liod.conf
  usr/share/doc/liod/README.md usr/share/doc/liod/pose-protocol.md usr/share/doc/liod/design.md
  usr/share/doc/liod/backend.md usr/share/doc/liod/robustness.md usr/share/doc/liod/results.md
  usr/include/liod/liod_pose.h usr/lib/python3/dist-packages/liod_pose.py
  usr/share/doc/liod/examples/example_print_poses.c usr/share/doc/liod/examples/example_print_poses.py
  usr/share/doc/liod/examples/example_log_csv.py
)
# The installed paths README.md's "Running on the vehicle" section names, and the unit's
# ExecStart binary and Documentation file.
section=$(awk '/^## Running on the vehicle/ { on = 1; next } /^## / { on = 0 } on' README.md)
[ -n "$section" ] || fail "README.md has no section 'Running on the vehicle'"
mapfile -t named < <(grep -oE '(^|[`( ])(/usr|/etc|/lib)/[A-Za-z0-9_./-]*[A-Za-z0-9_]' <<<"$section" | sed 's|^[^/]*||' | sort -u)
mapfile -t from_unit < <(sed -n -e 's|^ExecStart=\([^ ]*\).*|\1|p' -e 's|^Documentation=file://||p' "$stage/$unit")
for path in "${named[@]}" "${from_unit[@]}"; do expected+=("${path#/}"); done
for path in "${expected[@]}"; do
  [ -e "$stage/$path" ] || fail "/$path is not in the package"
done
[ -x "$stage/usr/bin/liod" ] || fail "/usr/bin/liod is not executable"
echo "${#expected[@]} paths present (README.md names ${#named[@]}, the unit ${#from_unit[@]})"
grep -qx /etc/liod/liod.yaml "$work/control/conffiles" || fail "/etc/liod/liod.yaml is not a conffile"
for script in postinst prerm postrm; do
  [ -x "$work/control/$script" ] || fail "maintainer script $script missing or not executable"
  sh -n "$work/control/$script" || fail "$script: syntax error"
done
depends=$(dpkg-deb -f "$deb" Depends)
for lib in libc6 libstdc++6 libyaml-cpp libspdlog libsystemd0 libgpiod; do
  grep -q "$lib" <<<"$depends" || fail "Depends lacks $lib: $depends"
done
echo "conffiles: $(tr '\n' ' ' <"$work/control/conffiles")"
echo "Depends: $depends"

echo "== systemd-analyze verify"
# verify --root=STAGE looks for systemd's own units (sysinit.target) in the root too, which a
# package's staging root does not hold; instead verify a copy of the unit whose ExecStart names
# the staged binary (verify checks that it exists and is executable).
sed "s|^ExecStart=/usr/bin/liod|ExecStart=$stage/usr/bin/liod|" "$stage/$unit" >"$work/liod.service"
grep -q "^ExecStart=$stage/usr/bin/liod run" "$work/liod.service" || fail "the unit's ExecStart is not /usr/bin/liod run ..."
systemd-analyze verify "$work/liod.service" || fail "systemd-analyze verify"
echo "verify: OK"

echo "== check-config"
${LIOD_EMULATOR:-} "$stage/usr/bin/liod" check-config --config "$stage/etc/liod/liod.yaml"

echo "== sysusers.d, tmpfiles.d"
root=$work/root
mkdir -p "$root/etc"
echo 'root:x:0:0:root:/root:/bin/bash' >"$root/etc/passwd"
printf 'root:x:0:\ndialout:x:20:\n' >"$root/etc/group"
systemd-sysusers --root="$root" "$stage/usr/lib/sysusers.d/liod.conf" 2>&1
systemd-tmpfiles --root="$root" --create "$stage/usr/lib/tmpfiles.d/liod.conf"
groups=$(sed -n 's/^SupplementaryGroups=//p' "$stage/$unit")
uid=$(awk -F: '$1 == "liod" { print $3 }' "$root/etc/passwd")
gid=$(awk -F: '$1 == "liod" { print $4 }' "$root/etc/passwd")
[ -n "$uid" ] || fail "no liod user"
grep -qE "^liod:x:$gid:" "$root/etc/group" || fail "the liod user's primary group is not liod"
for group in $groups; do
  grep -qE "^$group:x:[0-9]+:(.*,)?liod(,|$)" "$root/etc/group" || fail "liod is not in group $group"
done
[ "$(stat -c '%u %a' "$root/var/lib/liod")" = "$uid 750" ] || fail "/var/lib/liod: $(stat -c '%u %a' "$root/var/lib/liod")"
echo "user liod (uid $uid) in groups: liod $groups; /var/lib/liod mode 750"

echo "== clients"
cc -std=c99 -Wall -Wextra -Wpedantic -Werror -I"$stage/usr/include" -o "$work/print_poses" \
  "$stage/usr/share/doc/liod/examples/example_print_poses.c"
PYTHONPATH="$stage/usr/lib/python3/dist-packages" python3 -c 'import liod_pose; assert liod_pose.POSE_MESSAGE_SIZE == 360'
echo "C header and example build (C99), Python module imports"
echo "check-package: OK ($(basename "$deb"))"
