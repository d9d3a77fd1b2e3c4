#!/usr/bin/env bash
# Fuzzes the project's parsers with libFuzzer (clang from Debian) for a bounded time.
#   scripts/fuzz.sh [SECONDS] [TARGET|all]   (default: 60 s, rtde)
# Targets (fuzz/CMakeLists.txt): rtde (RTDE packets), recording (CSV + column map), scenario
# (YAML), twin_model (twin JSON), description_json, description_urdf, monitor_config,
# friction_block; "all" runs each of them for SECONDS in turn.
# Findings are written to fuzz/regressions/<target>/ — commit them: ctest replays that folder
# (fuzz.<target>_replay), so every finding becomes a regression test once fixed.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
which=${2:-rtde}
all_targets=(rtde recording scenario twin_model description_json description_urdf monitor_config friction_block)
if [ "$which" = all ]; then
  targets=("${all_targets[@]}")
elif [[ " ${all_targets[*]} " == *" $which "* ]]; then
  targets=("$which")
else
  echo "unknown fuzz target '$which', expected one of: ${all_targets[*]} all" >&2
  exit 2
fi
if ! command -v clang++ >/dev/null; then
  SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
  $SUDO apt-get update && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends clang
fi
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DTWINWATCH_FUZZ=ON -DBUILD_TESTING=OFF >/dev/null
cmake --build build-fuzz --target "${targets[@]/%/_fuzz}" -j"$(nproc)"
# a UBSan report is a finding (not just a warning); leaks inside urdfdom are suppressed
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan_suppressions.txt}
failed=()
for t in "${targets[@]}"; do
  work=$(mktemp -d)
  cp fuzz/corpus/"$t"/* "$work/"
  mkdir -p fuzz/regressions/"$t"
  # a hang: an input running > 10 s; scenarios get 30 s, as a Cartesian trajectory (figure_eight,
  # triangle) takes ~6 s to build under the sanitizers (50 ms in a Release build)
  timeout=10 extra=()
  [ "$t" = scenario ] && timeout=30
  [ "$t" = description_urdf ] && extra=(-close_fd_mask=2)  # urdfdom prints every XML error to stderr
  echo "== fuzzing $t for ${seconds} s"
  if ./build-fuzz/fuzz/"$t"_fuzz "$work" fuzz/corpus/"$t" -max_total_time="$seconds" -max_len=4096 -timeout="$timeout" \
       -artifact_prefix=fuzz/regressions/"$t"/ -print_final_stats=1 ${extra[@]+"${extra[@]}"}; then
    echo "$t: no findings in ${seconds} s; corpus grown to $(ls "$work" | wc -l) inputs in $work"
  else
    echo "$t: FINDING, reproducer in fuzz/regressions/$t/ (replay: build-fuzz/fuzz/${t}_fuzz <file>)"
    failed+=("$t")
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "findings in: ${failed[*]}" >&2
  exit 1
fi
