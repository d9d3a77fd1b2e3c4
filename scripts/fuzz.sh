#!/usr/bin/env bash
# Fuzzes the RTDE packet parser with libFuzzer (clang from Debian) for a bounded time.
#   scripts/fuzz.sh [SECONDS]   (default 60)
# Findings are written to fuzz/regressions/rtde/ — commit them: ctest replays that folder
# (fuzz.rtde_replay), so every finding becomes a regression test once fixed.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
if ! command -v clang++ >/dev/null; then
  SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
  $SUDO apt-get update && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends clang
fi
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DTWINWATCH_FUZZ=ON -DBUILD_TESTING=OFF >/dev/null
cmake --build build-fuzz --target rtde_fuzz -j"$(nproc)"
work=$(mktemp -d)
cp fuzz/corpus/rtde/* "$work/"
./build-fuzz/fuzz/rtde_fuzz "$work" fuzz/corpus/rtde -max_total_time="$seconds" -max_len=4096 \
  -artifact_prefix=fuzz/regressions/rtde/ -print_final_stats=1
echo "no findings in ${seconds} s; corpus grown to $(ls "$work" | wc -l) inputs in $work"
