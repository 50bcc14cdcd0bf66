#!/usr/bin/env bash
# The cost of whole shipped diagrams, two builds on the same jobs in one window
# (docs/performance.md, "The cost of a whole diagram"). For each sweep file, each build runs
# `sweep run FILE --jobs WORKERS` on a fresh database of its own (the builds alternate: A, B on
# the first file, B, A on the next, ...); a sweep with a continuation axis runs both branches in
# that one command. Printed per sweep and build: the wall time of `sweep run`, the job time
# (the jobs' own wall seconds, summed), the jobs, and the CPU seconds of the process (user +
# system, from /usr/bin/time); then B against A. The databases stay in OUT (default: a new
# temporary folder) for `wetgran sweep status` or `export`.
#
# Usage: scripts/diagram_cost.sh A_WETGRAN B_WETGRAN [WORKERS] [OUT] -- SWEEP.toml [SWEEP.toml ...]
# e.g.   scripts/diagram_cost.sh baseline/wetgran target/release/wetgran 2 -- \
#            sweeps/quickstart.toml sweeps/shaken_2d_elastic.toml
set -euo pipefail
a=$1
b=$2
shift 2
workers=2
out=""
while [ "$#" -gt 0 ] && [ "$1" != "--" ]; do
  if [ -z "${set_workers:-}" ]; then workers=$1; set_workers=1; else out=$1; fi
  shift
done
[ "${1:-}" = "--" ] && shift
[ "$#" -gt 0 ] || { echo "usage: $0 A B [WORKERS] [OUT] -- SWEEP.toml ..." >&2; exit 2; }
out=${out:-$(mktemp -d)}
mkdir -p "$out"
a=$(realpath "$a")
b=$(realpath "$b")
printf "%-28s %-2s %9s %10s %5s %9s\n" sweep bin "wall s" "job s" jobs "cpu s"
first=a
for sweep in "$@"; do
  name=$(basename "$sweep" .toml)
  order="a b"
  [ "$first" = b ] && order="b a"
  for who in $order; do
    bin=$a
    [ "$who" = b ] && bin=$b
    db="$out/$name-$who.sqlite"
    rm -f "$db" "$db-wal" "$db-shm"
    start=$(date +%s.%N)
    /usr/bin/time -f "%U %S" -o "$out/$name-$who.time" \
      "$bin" sweep run "$sweep" --db "$db" --jobs "$workers" > "$out/$name-$who.log" 2>&1 ||
      echo "  ($name, $who: sweep run exited $?; see $out/$name-$who.log)"
    end=$(date +%s.%N)
    "$bin" export --json --db "$db" > "$out/$name-$who.json" 2>/dev/null
    python3 - "$name" "$who" "$start" "$end" "$out/$name-$who.json" "$out/$name-$who.time" <<'PY'
import json, sys
name, who, start, end, export, timing = sys.argv[1:]
rows = json.load(open(export))
job = sum(r.get("wall_seconds") or 0.0 for r in rows)
user, system = map(float, open(timing).read().split()[-2:])
print(f"{name:<28} {who:<2} {float(end) - float(start):9.1f} {job:10.1f} {len(rows):5d} {user + system:9.1f}")
PY
  done
  python3 - "$name" "$out/$name-a.json" "$out/$name-b.json" <<'PY'
import json, sys
name, fa, fb = sys.argv[1:]
ja, jb = json.load(open(fa)), json.load(open(fb))
key = lambda r: r["job_id"]
ta = sum(r.get("wall_seconds") or 0.0 for r in ja)
tb = sum(r.get("wall_seconds") or 0.0 for r in jb)
same = {key(r): r.get("phase") for r in ja} == {key(r): r.get("phase") for r in jb}
print(f"{name:<28} B/A job time {tb / ta:.3f} ({ta / tb:.2f}x faster); same jobs and labels: {same}")
PY
  [ "$first" = a ] && first=b || first=a
done
echo "databases and logs in $out"
