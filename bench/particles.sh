#!/bin/sh
# Whole-process time and peak memory of `nhdyn simulate` on N free particles under gravity
# (`nhdyn example particles --bodies N`, n = 3N coordinates, no constraint, 1 s simulated at the
# file's settings), from /usr/bin/time -v. Also the part of it spent in the time integration,
# from simulate's own summary line. Docs: docs/performance.md, "Many free particles".
#
#     bench/particles.sh [BUILD_DIR] [N ...]
#
# Defaults: build, N = 100 1000 10000. Target (issue 12): N = 10 000 in 10 s or less.
set -eu
# A first run's figures: the derivation made at every load (the cache of derived models off).
export NHDYN_DERIVATION_CACHE=off
build=${1:-build}
[ $# -ge 1 ] && shift
sizes=${*:-100 1000 10000}
nhdyn=$(cd "$build" && pwd)/apps/nhdyn/nhdyn
[ -x "$nhdyn" ] || { echo "no nhdyn at $nhdyn: build the target nhdyn_cli first" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

printf '%7s %7s | %8s %8s %8s | %13s | %s\n' N n "wall [s]" "cpu [s]" "RSS [MB]" "integration" "load average"
for N in $sizes; do
  "$nhdyn" example particles --bodies "$N" -o "$work/p.toml"
  /usr/bin/time -v "$nhdyn" simulate "$work/p.toml" -o "$work/p.csv" > "$work/out.txt" 2> "$work/time.txt" ||
    { cat "$work/time.txt" >&2; exit 1; }
  wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$work/time.txt" |
         awk -F: '{ if (NF == 3) print $1 * 3600 + $2 * 60 + $3; else print $1 * 60 + $2 }')
  cpu=$(sed -n 's/.*\(User\|System\) time (seconds): //p' "$work/time.txt" | awk '{ t += $1 } END { print t }')
  rss=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$work/time.txt")
  run=$(sed -n 's/.*wall time \([^ ]*\) ms.*/\1 ms/p' "$work/out.txt")
  printf '%7s %7s | %8.2f %8.2f %8.0f | %13s | %s\n' "$N" $((3 * N)) "$wall" "$cpu" "$(echo "$rss / 1024" | bc -l)" \
    "$run" "$(cut -d' ' -f1-3 /proc/loadavg)"
done
