#!/usr/bin/env bash
# Installs everything stipple needs to build and test on Debian 12, from
# Debian's packages. Runs apt-get directly as root, through sudo otherwise.
set -euo pipefail
packages=(cmake ninja-build g++ pkg-config libeigen3-dev libgtest-dev libgmock-dev libbenchmark-dev libpng-dev clang
  liblzf-dev  # PCD's binary_compressed
  g++-arm-linux-gnueabi g++-arm-linux-gnueabihf g++-aarch64-linux-gnu qemu-user  # cross builds, their emulator
  socat  # a linked pseudo-terminal pair: the serial line in the CLI tests; a TLS client end in the balancer test
  haproxy openssl  # the load balancer in front of several servers (tests/cli_balancer.sh), its TLS certificate
  help2man dpkg-dev  # man pages from --help; the .deb's library dependencies (dpkg-shlibdeps)
  libsdl2-dev libepoxy-dev libegl-dev libgl-dev libgl1-mesa-dri libegl-mesa0  # the emulator, the GL client (llvmpipe)
  xvfb xauth  # their windows in the tests
  draco python3-minimal  # Draco's rate against distortion beside ours (tools/draco_rd.sh); tools/bench/*.py
  python3-distributed)  # the encoder's jobs on a Dask cluster (tools/cluster/dask_encode.py and its test)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
