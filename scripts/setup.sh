#!/usr/bin/env bash
# Installs every Debian package twinwatch needs (idempotent, apt-get only) and builds it.
#   scripts/setup.sh            set up and build (Release) into build/
#   BUILD_DIR=... scripts/setup.sh   build elsewhere
# Environment: CI=true turns warnings into errors. SKIP_APT=1 skips the package step.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake ninja-build pkg-config git ccache
  libeigen3-dev liborocos-kdl-dev liburdfdom-dev liburdfdom-headers-dev libconsole-bridge-dev
  libcli11-dev nlohmann-json3-dev libfmt-dev libspdlog-dev libyaml-cpp-dev libsqlite3-dev
  libboost-dev libceres-dev libnlopt-cxx-dev libnlopt-dev libglpk-dev coinor-libclp-dev
  libgtest-dev libgmock-dev googletest libbenchmark-dev sqlite3 curl
  libmosquitto-dev mosquitto mosquitto-clients openssl
)

if [[ "${SKIP_APT:-0}" != "1" ]]; then
  missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
    SUDO=""
    [[ $(id -u) -ne 0 ]] && SUDO="sudo"
    $SUDO apt-get update
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
  else
    echo "setup: all ${#PACKAGES[@]} Debian packages present"
  fi
fi

BUILD_DIR=${BUILD_DIR:-build}
WERROR=OFF
[[ "${CI:-}" == "true" ]] && WERROR=ON
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTWINWATCH_WERROR=$WERROR ${CMAKE_EXTRA:-}
cmake --build "$BUILD_DIR" --parallel "$(nproc)"
echo "setup: built $BUILD_DIR/twinwatch"
