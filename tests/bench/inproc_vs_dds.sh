#!/usr/bin/env bash
# In-process against over DDS: the same scenario and seeds run by `sage run` (the mission core and
# agent objects in lockstep) and by `sage launch` (the same objects as processes on Cyclone DDS),
# compared sample for sample (the trajectory, and how many server cycles kept lockstep) and on
# what an inspection engineer reads: corr(visits, weight), the dominant valve's
# revisit interval, the fewest visits of any valve and the final ergodic metric. Prints and
# writes BUILD_DIR/inproc_vs_dds.md. Usage: tests/bench/inproc_vs_dds.sh [BUILD_DIR] [SCENARIO] [SEEDS...]
# (default: build scenarios/fleet_field.yaml 1 2 3; launches run at 4x real time).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
scenario=${2:-scenarios/fleet_field.yaml}
shift 2 || true
seeds=("${@:-1 2 3}")
out="$build/inproc_vs_dds.md"   # beside the build, never in the source tree
work=$(mktemp -d)
summary() {  # metrics.json -> "corr interval fewest metric"
  python3 - "$1" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
v = m["valves"]
top = max(v, key=lambda x: x["weight"])
print(m["visit_weight_correlation"], top["mean_interval_s"], min(x["visits"] for x in v), m["ergodic_metric"])
PY
}
same_path() {  # two trajectory.csv -> "identical" or "K of N samples differ" (t = 0 is written only in-process)
  python3 - "$1" "$2" <<'PY'
import sys
def rows(path):
    with open(path) as f:
        return sorted(l for l in f if not l.startswith("t,") and not l.startswith("0,"))
a, b = rows(sys.argv[1]), rows(sys.argv[2])
differ = sum(x != y for x, y in zip(a, b)) + abs(len(a) - len(b))
print("identical" if differ == 0 else f"{differ} of {max(len(a), len(b))} samples differ")
PY
}
{
  echo "| seed | transport | corr(visits, weight) | dominant valve interval | fewest visits | ergodic metric | trajectory vs in-process | server cycles in lockstep |"
  echo "|---|---|---|---|---|---|---|---|"
} | tee "$out"
for seed in ${seeds[@]}; do
  echo "inproc_vs_dds: seed $seed" >&2
  "$build/bin/sage" run "$scenario" --seed "$seed" --out "$work/run$seed" >/dev/null 2>&1
  "$build/bin/sage" launch "$scenario" --seed "$seed" --time-scale 4 --no-latest --out "$work/launch$seed" >"$work/launch$seed.log" 2>&1
  path=$(same_path "$work/run$seed/trajectory.csv" "$work/launch$seed/trajectory.csv")
  lockstep=$(grep -o "[0-9]* of [0-9]* cycles in lockstep" "$work/launch$seed.log" | tail -1 | sed 's/ cycles in lockstep//')
  for kind in run launch; do
    read -r corr interval fewest metric <<<"$(summary "$work/$kind$seed/metrics.json")"
    if [ "$kind" = run ]; then transport=in-process; same=-; step=-; else transport=DDS; same=$path; step=$lockstep; fi
    printf "| %s | %s | %+.3f | %.1f s | %s | %.2e | %s | %s |\n" "$seed" "$transport" "$corr" "$interval" "$fewest" "$metric" "$same" "$step" | tee -a "$out"
  done
done
rm -rf "$work"
