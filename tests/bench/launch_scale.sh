#!/usr/bin/env bash
# Fleet missions over Cyclone DDS at scale: `sage launch` on scenarios/fleet_large.yaml with N
# vehicles (agent hosts of up to 10,000 vehicles each, sage launch's default), at real time. Prints and appends to
# BUILD_DIR/launch_scale.md: the real-time factor the server kept, its cycle time, and the DDS message
# rate it saw. Usage: tests/bench/launch_scale.sh [BUILD_DIR] [N ...]   (default: build 100 1000)
# Missions are secured (DDS Security, sage launch's default); LAUNCH_FLAGS=--insecure runs them plain.
set -euo pipefail
cd "$(dirname "$0")/../.."   # the repository root: scenarios/ and build/ are relative to it
build=${1:-build}
shift || true
counts=("${@:-100 1000}")
out="$build/launch_scale.md"   # beside the build, never in the source tree
echo "| vehicles | agent hosts | mission | wall | real-time factor | server cycle | DDS messages/s at the server |" | tee -a "$out"
echo "|---|---|---|---|---|---|---|" | tee -a "$out"
for n in ${counts[@]}; do
  dir=$(mktemp -d)
  log="$dir/launch.log"
  if ! "$build/bin/sage" launch scenarios/fleet_large.yaml --vehicles "$n" --duration 30 --no-latest --out "$dir" ${LAUNCH_FLAGS:-} >"$log" 2>&1; then
    echo "launch_scale: the $n-vehicle mission failed; its log: $log" >&2
    exit 1
  fi
  summary=$(grep "server: .* of mission in" "$log" | tail -1)
  hosts=$(grep -o "[0-9]* agent host(s)" "$log" | head -1 | cut -d' ' -f1)
  # "... 30 s of mission in 30.0 s wall (1.00x real time); 310149 messages in, 1364 out (10380/s); 31.020 MB in, 1.204 MB
  # out at 1.074 MB/s; server cycle 9.79 ms mean, 21.40 ms p99, 49.30 ms max; peak RSS 80.1 MB; ..."
  mission=$(sed -E 's/.*server: ([0-9.]+) s of mission.*/\1/' <<<"$summary")
  wall=$(sed -E 's/.* in ([0-9.]+) s wall.*/\1/' <<<"$summary")
  rtf=$(sed -E 's/.*\(([0-9.]+)x real time\).*/\1/' <<<"$summary")
  rate=$(sed -E 's/.*out \(([0-9]+)\/s\).*/\1/' <<<"$summary")
  cycle=$(sed -E 's/.*server cycle ([0-9.]+ ms mean, [0-9.]+ ms p99, [0-9.]+ ms max).*/\1/' <<<"$summary")
  echo "| $n | $hosts | $mission s | $wall s | ${rtf}x | $cycle | $rate |" | tee -a "$out"
  rm -rf "$dir"
done
