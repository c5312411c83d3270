#!/usr/bin/env bash
# liod for arm64 (aarch64, the Jetson Orin): the Release build, its Debian package and its tests.
#
#   scripts/arm64.sh [--sysroot DIR] [--build DIR] [--no-tests] [--no-replay]
#
# On an x86-64 Debian 12 host (a cross build; needs root or sudo for apt-get, the first time):
#  1. installs the cross compiler (crossbuild-essential-arm64), qemu-user-static and mmdebstrap;
#  2. makes an arm64 sysroot (default ../arm64-root, beside the clone; about 2 GB) with the arm64
#     -dev packages liod builds against: mmdebstrap --variant=extract unpacks them without running
#     anything arm64, then absolute symlinks, the BLAS/LAPACK alternatives and the absolute library
#     paths of the packages' CMake files are pointed into the sysroot. A sysroot rather than
#     multiarch :arm64 packages on the host: several -dev packages (PCL's, Boost's, VTK's) are not
#     Multi-Arch: same, and apt would remove the host's amd64 ones. Made once; again when the
#     package list below changes;
#  3. cross-compiles the Release tree (cmake/aarch64-linux-gnu.cmake) in build-arm64/: liod and the
#     unit-test programs;
#  4. builds the arm64 .deb and checks it (scripts/check-package.sh, liod run under qemu), and that
#     its Depends names the package of every library the arm64 liod links;
#  5. runs the unit tests under qemu-aarch64-static (ctest; CMAKE_CROSSCOMPILING_EMULATOR);
#  6. replays a 10 s liod-sim drive (made by the host's liod-sim) with the x86-64 liod and with the
#     arm64 liod under qemu, and compares the trajectories with liod-eval (no alignment): the
#     largest position and rotation difference must stay within 1 mm and 0.01 deg (why: below).
#
# On an arm64 host (the Orin itself, Debian 12 or Ubuntu 22.04): steps 3-5 natively, no sysroot,
# no emulator; the .deb then depends on the host's own library packages.
#
# The cross-built .deb is for Debian 12 (bookworm) arm64, the sysroot's release; a Jetson on Ubuntu
# 22.04 (JetPack 6) has other library versions (libspdlog1, libfmt8), so build on it natively.
# Not part of scripts/test.sh or .ci/run: the emulated tests take minutes the CI does not have.
set -euo pipefail
cd "$(dirname "$0")/.."
src=$PWD
sysroot=$src/../arm64-root
build=build-arm64
tests=1
replay=1
while [ $# -gt 0 ]; do
  case "$1" in
    --sysroot) sysroot=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --no-tests) tests=0; shift ;;
    --no-replay) replay=0; shift ;;
    *) echo "arm64.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
fail() { echo "arm64.sh: FAILED: $*" >&2; exit 1; }
sysroot=$(realpath -m "$sysroot")
gen=(); command -v ninja >/dev/null && [ ! -f "$build/CMakeCache.txt" ] && gen=(-G Ninja)
jobs=$(nproc)

# The unit-test programs run under qemu, and the tests left out of them: qemu runs liod's code
# about 8-13x slower than the host, so the drive tests (whole simulated drives through the
# pipeline: test_backend's Backend.*, 31 s natively, and the programs not listed: test_daemon,
# test_odometry, test_sim, test_fault, test_calibration, test_relocalization, test_state_dir,
# test_clients; about 600 CPU-s natively) would take one to two hours; they test nothing
# arm64-specific that the unit tests and the replay below do not.
test_programs=(test_core test_drivers test_config test_eval test_backend)
slow_tests='^Backend\.'

# The arm64 packages the sysroot holds: scripts/install-deps.sh's libraries.
sysroot_packages=(
  libc6-dev libstdc++-12-dev
  libeigen3-dev libceres-dev libpcl-dev
  libspdlog-dev libfmt-dev libyaml-cpp-dev
  libgpiod-dev libsystemd-dev
  libbz2-dev liblz4-dev libzstd-dev zlib1g-dev
  libboost-dev
  libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
)
suite=bookworm
mirror=http://deb.debian.org/debian

apt_install() {
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  local sudo_cmd=()
  [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  echo "arm64.sh: installing ${missing[*]}"
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

make_sysroot() {
  local stamp=$sysroot/.liod-sysroot
  local want="$suite ${sysroot_packages[*]}"
  if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
    echo "== sysroot $sysroot (made before)"
    return 0
  fi
  echo "== sysroot $sysroot: arm64 $suite with ${sysroot_packages[*]}"
  rm -rf "$sysroot"
  local list
  list=$(IFS=,; echo "${sysroot_packages[*]}")
  mmdebstrap --quiet --variant=extract --architectures=arm64 --include="$list" "$suite" "$sysroot" \
    "deb $mirror $suite main" "deb $mirror $suite-updates main" \
    "deb ${mirror%/debian}/debian-security $suite-security main"
  # Absolute symlinks (libz.so -> /lib/...) would point into the host.
  find "$sysroot" -type l -lname '/*' -print0 | while IFS= read -r -d '' link; do
    ln -sfn --relative "$sysroot$(readlink "$link")" "$link"
  done
  # The links update-alternatives makes in libblas3's and liblapack3's postinst, which an extract
  # does not run.
  local lib=$sysroot/usr/lib/aarch64-linux-gnu
  for f in libblas.so libblas.so.3 liblapack.so liblapack.so.3; do
    [ -e "$lib/$f" ] && continue
    for provider in atlas openblas-pthread blas lapack; do
      if [ -e "$lib/$provider/$f" ]; then ln -sfn "$provider/$f" "$lib/$f"; break; fi
    done
  done
  # Imported targets that name libraries by absolute path (Ceres: liblapack.so, ...): into the sysroot.
  grep -rlE 'INTERFACE_(LINK_LIBRARIES|INCLUDE_DIRECTORIES).*[";]/usr/' "$lib/cmake" | xargs -r sed -i -E \
    '/INTERFACE_(LINK_LIBRARIES|INCLUDE_DIRECTORIES)/ s#([";])/usr/#\1${CMAKE_SYSROOT}/usr/#g'
  echo "$want" >"$stamp"
}

# Every library the arm64 liod links (NEEDED) is in a package its Depends names. The sysroot has no
# dpkg database (nothing was configured), so the owner is looked up among the host's packages of the
# same library (Debian names a library's package alike on every architecture).
check_depends() {
  local deb=$1 names needed lib owner missing=0
  names=$(dpkg-deb -f "$deb" Depends | tr ',|' '\n\n' | sed 's/(.*//; s/ //g')
  needed=$(aarch64-linux-gnu-readelf -d "$build/bin/liod" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
  for lib in $needed; do
    # dpkg -S fails when one of the paths is not registered (Debian 12 registers either); the
    # resolved path finds a library behind an alternative (liblapack.so.3); the loader is libc6's.
    owner=$({ dpkg -S "/lib/x86_64-linux-gnu/$lib" "/usr/lib/x86_64-linux-gnu/$lib" \
      "$(readlink -f "/usr/lib/x86_64-linux-gnu/$lib")" 2>/dev/null || true; } | head -1 | cut -d: -f1)
    case $lib in ld-linux-*) owner=libc6 ;; esac
    if [ -z "$owner" ]; then echo "  $lib: owner unknown (not installed on the host)"; continue; fi
    if grep -Fxq "$owner" <<<"$names"; then
      echo "  $lib: $owner"
    else
      echo "  $lib: $owner, NOT in Depends"; missing=1
    fi
  done
  [ $missing -eq 0 ] || fail "the package's Depends lacks a library liod links"
}

run_unit_tests() {
  local labels
  labels="^($(IFS='|'; echo "${test_programs[*]}"))\$"
  echo "== unit tests (${test_programs[*]}; left out: $slow_tests)"
  local start=$SECONDS log=$build/unit-tests.log
  if ! ctest --test-dir "$build" -L "$labels" -E "$slow_tests" -j"$jobs" --output-on-failure >"$log" 2>&1; then
    tail -n 60 "$log"
    fail "unit tests (log: $log)"
  fi
  grep -E 'tests passed|Total Test time' "$log"
  echo "unit tests took $((SECONDS - start)) s (log: $log)"
}

# The 10 s replay on both architectures. Tolerance 1 mm and 0.01 deg: the arm64 code differs from
# the x86-64 code in rounding only. GCC contracts a*b+c into fused multiply-adds on aarch64 (C++'s
# default -ffp-contract=fast; the arm64 liod has ~30 000 of them, the baseline x86-64 build none),
# glibc's libm differs in the last bit on some functions, and Eigen's NEON and SSE kernels may
# order sums differently. Those are ~1e-16 relative per operation; the filter's iterations and the
# registration's nearest neighbours carry them on from scan to scan (0.2 mm after 10 s), but a real
# fault in the arm64 build (a misparsed packet, an endianness or alignment bug) shows at once as
# centimetres and tenths of a degree. 1 mm is also a quarter of the estimate's own ATE on the drive.
replay_compare() {
  local host_build=build emu=("$@") out=$build/replay
  echo "== replay: a 10 s liod-sim drive, x86-64 and arm64 liod"
  cmake -S . -B "$host_build" -DCMAKE_BUILD_TYPE=Release "${gen[@]}" >/dev/null
  cmake --build "$host_build" -j"$jobs" --target liod liod-sim liod-eval
  rm -rf "$out" && mkdir -p "$out/drive"
  "$host_build/bin/liod-sim" --route urban --seed 1 --duration 10 --max-speed 12 --quiet --out "$out/drive"
  local configs=(--config config/liod.yaml --config config/vehicles/liod-sim-car.yaml --config "$out/drive/extrinsics.yaml")
  local start=$SECONDS
  "$host_build/bin/liod" replay "${configs[@]}" --pcap "$out/drive/lidar.pcap" --imu "$out/drive/imu.csv" \
    --trajectory "$out/x86_64.tum" 2>"$out/x86_64.log"
  echo "x86-64 replay: $((SECONDS - start)) s"
  start=$SECONDS
  "${emu[@]}" "$build/bin/liod" replay "${configs[@]}" --pcap "$out/drive/lidar.pcap" --imu "$out/drive/imu.csv" \
    --trajectory "$out/arm64.tum" 2>"$out/arm64.log"
  echo "arm64 replay under qemu: $((SECONDS - start)) s"
  local eval=("$host_build/bin/liod-eval" --json)
  "${eval[@]}" --gt "$out/x86_64.tum" --est "$out/arm64.tum" --align none --max-dt 0.001 >"$out/difference.json"
  "${eval[@]}" --gt "$out/drive/groundtruth.tum" --est "$out/x86_64.tum" >"$out/x86_64.json"
  "${eval[@]}" --gt "$out/drive/groundtruth.tum" --est "$out/arm64.tum" >"$out/arm64.json"
  python3 - "$out" <<'EOF' || fail "the arm64 replay's trajectory differs from the x86-64 one beyond the tolerance"
import json, sys
out = sys.argv[1]
d, x86, arm = (json.load(open(f"{out}/{n}.json")) for n in ("difference", "x86_64", "arm64"))
n = [sum(1 for line in open(f"{out}/{a}.tum") if line.strip() and not line.startswith("#")) for a in ("x86_64", "arm64")]
pos, rot = d["ate"]["max_m"], d["ate"]["rot_max_deg"]
print(f"poses: x86-64 {n[0]}, arm64 {n[1]}, paired {d['poses_associated']}")
print(f"largest difference: position {pos:.2e} m, rotation {rot:.2e} deg (tolerance 1e-3 m, 1e-2 deg)")
print(f"ATE RMSE against the ground truth: x86-64 {x86['ate']['rmse_m']:.5f} m, arm64 {arm['ate']['rmse_m']:.5f} m")
sys.exit(0 if n[0] == n[1] == d["poses_associated"] and pos <= 1e-3 and rot <= 1e-2 else 1)
EOF
}

if [ "$(uname -m)" = aarch64 ]; then
  echo "== native arm64 build in $build"
  bash scripts/install-deps.sh
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release "${gen[@]}" >/dev/null
  cmake --build "$build" -j"$jobs" --target liod "${test_programs[@]}"
  bash scripts/check-package.sh "$build"
  if [ $tests -eq 1 ]; then run_unit_tests; fi
  exit 0
fi

echo "== host tools"
bash scripts/install-deps.sh
apt_install crossbuild-essential-arm64 qemu-user-static mmdebstrap
make_sysroot
emulator=(qemu-aarch64-static -L "$sysroot")

echo "== cross build in $build"
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release "${gen[@]}" \
  -DCMAKE_TOOLCHAIN_FILE="$src/cmake/aarch64-linux-gnu.cmake" -DLIOD_ARM64_SYSROOT="$sysroot" >/dev/null
start=$SECONDS
cmake --build "$build" -j"$jobs" --target liod "${test_programs[@]}"
echo "cross build took $((SECONDS - start)) s"
file -b "$build/bin/liod" | grep -q 'ARM aarch64' || fail "$build/bin/liod is not an aarch64 executable"

LIOD_EMULATOR="${emulator[*]}" bash scripts/check-package.sh "$build"
deb=$(ls "$build"/package/liod_*_arm64.deb) || fail "no liod_*_arm64.deb in $build/package"
echo "== Depends against the libraries liod links"
check_depends "$deb"

if [ $tests -eq 1 ]; then run_unit_tests; fi
if [ $replay -eq 1 ]; then replay_compare "${emulator[@]}"; fi
echo "arm64.sh: OK ($deb)"
