#!/usr/bin/env bash
# Load-independent share of the location-change observer (docs/performance.md, "Location-change
# observer"): callgrind instruction counts of `wetgran-bench observer:POINT` at two scales; the
# difference between them removes the start-up and the unobserved warm-up. Per extra sample:
#   observer = instructions in observe_counter (the counter, triangulating every sample),
#   run = all instructions - observer (engine, frame copy, other observers),
#   share = observer / (run + observer).
# Usage: scripts/observer_share.sh [BINARY] [POINTS] [SCALE_LOW] [SCALE_HIGH]
set -euo pipefail
bin=${1:-./target/release/wetgran-bench}
points=${2:-gas fluid coexistence}
lo=${3:-0.05}
hi=${4:-0.15}
out=$(mktemp -d)
printf "%-12s %12s %12s %8s\n" point "run/sample" "obs/sample" share
for p in $points; do
  declare -A tot obs
  for s in $lo $hi; do
    nice -n 19 valgrind --tool=callgrind --callgrind-out-file="$out/$p-$s.out" \
      "$bin" "observer:$p" --scale "$s" > "$out/$p-$s.txt" 2>/dev/null
    ann=$(callgrind_annotate --inclusive=yes "$out/$p-$s.out" 2>/dev/null)
    tot[$s]=$(echo "$ann" | grep "PROGRAM TOTALS" | awk '{gsub(",","",$1); print $1}')
    obs[$s]=$(echo "$ann" | grep "observer::observe_counter \[" | awk '{gsub(",","",$1); print $1}')
  done
  n=$(python3 -c "print(max(10, round(400*$hi)) - max(10, round(400*$lo)))")
  python3 - "$p" "$n" "${tot[$lo]}" "${tot[$hi]}" "${obs[$lo]}" "${obs[$hi]}" <<'PY'
import sys
p, n = sys.argv[1], int(sys.argv[2])
t0, t1, o0, o1 = map(int, sys.argv[3:])
obs = (o1 - o0) / n
run = (t1 - t0) / n - obs
print(f"{p:<12} {run:12.0f} {obs:12.0f} {100*obs/(run+obs):7.1f}%")
PY
done
rm -rf "$out"
