#!/usr/bin/env bash
# Installs liod's build and test dependencies from Debian/Ubuntu packages. (PCL is for a test:
# the maps liod writes are read back with PCL's reader, as a user's tools would read them; pcap
# captures and PCD files are liod's own small code, so neither libpcap nor PCL ships with liod.)
# Idempotent: packages already present are skipped; safe to run again.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libceres-dev libpcl-dev
  libspdlog-dev libfmt-dev libyaml-cpp-dev
  libgpiod-dev libsystemd-dev
  libcli11-dev nlohmann-json3-dev
  libbz2-dev liblz4-dev libzstd-dev zlib1g-dev   # ROS 1 bag and MCAP chunks
  libboost-dev   # Boost.Beast/Asio: the live view's WebSocket server
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-matplotlib   # liod-eval's plots (tools/eval/liod-eval-plot, run by /usr/bin/python3)
  clang
  dpkg-dev file systemd   # the Debian package and its check: dpkg-shlibdeps, file (CPack finds the ELF
                          # files with it), systemd-analyze, -sysusers, -tmpfiles (scripts/check-package.sh)
)
# libFuzzer and the sanitizer runtimes for clang (scripts/fuzz.sh): their own package on Debian 12,
# part of clang's packages on Ubuntu 22.04.
if grep -qx 'ID=debian' /etc/os-release 2>/dev/null; then packages+=(libclang-rt-dev); fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
