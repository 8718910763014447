#!/bin/sh
# nhdyn against a SciPy sparse solve_ivp pipeline (bench/peers/chain_scipy.py) on the N-trailer
# chain, whole process: `nhdyn simulate c.toml --t-end T` at the file's tolerances (rtol 1e-10,
# atol 1e-12, dopri5) against the same model in NumPy/SciPy (RK45, one sparse KKT solve per
# right-hand side). Prints wall time and peak memory of each (from /usr/bin/time -v), their ratio,
# and the largest difference of the two final states. Docs: docs/performance.md.
#
#     bench/peers/chain_vs_scipy.sh [BUILD_DIR] [T_END] [N ...]
#
# Defaults: build, 1, N = 10 30 100 300 1000. Uses /usr/bin/python3 (python3-scipy, python3-numpy).
set -eu
# A first run's figures: the derivation made at every load (the cache of derived models off).
export NHDYN_DERIVATION_CACHE=off
build=${1:-build}
t_end=${2:-1}
[ $# -ge 2 ] && shift 2 || shift $#
sizes=${*:-10 30 100 300 1000}
here=$(cd "$(dirname "$0")" && pwd)
nhdyn=$(cd "$build" && pwd)/apps/nhdyn/nhdyn
[ -x "$nhdyn" ] || { echo "no nhdyn at $nhdyn: build the target nhdyn_cli first" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# seconds and peak kB of a command, from GNU time's verbose report.
measure() {
  /usr/bin/time -v "$@" > "$work/out.txt" 2> "$work/time.txt" || { cat "$work/time.txt" >&2; exit 1; }
  wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$work/time.txt" |
         awk -F: '{ if (NF == 3) print $1 * 3600 + $2 * 60 + $3; else print $1 * 60 + $2 }')
  rss=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$work/time.txt")
  cpu=$(sed -n 's/.*\(User\|System\) time (seconds): //p' "$work/time.txt" | awk '{ t += $1 } END { print t }')
  echo "$wall $rss $cpu"
}

printf '%6s %6s | %9s %8s %7s | %9s %8s %7s | %6s %6s | %s\n' N n "nhdyn [s]" "cpu [s]" "[MB]" "scipy [s]" "cpu [s]" "[MB]" "ratio" "cpu" "max |q_nhdyn - q_scipy| at t_end"
for N in $sizes; do
  "$nhdyn" example chain --bodies "$N" -o "$work/c.toml" > /dev/null
  set -- $(measure "$nhdyn" simulate "$work/c.toml" --t-end "$t_end" -q -o "$work/nhdyn.csv")
  t_nhdyn=$1 m_nhdyn=$2 c_nhdyn=$3
  set -- $(measure /usr/bin/python3 "$here/chain_scipy.py" "$work/c.toml" "$work/scipy.csv" --t-end "$t_end")
  t_scipy=$1 m_scipy=$2 c_scipy=$3
  diff=$(/usr/bin/python3 - "$work/nhdyn.csv" "$work/scipy.csv" "$N" <<'PY'
import sys, numpy as np
a = np.loadtxt([l for l in open(sys.argv[1]) if not l.startswith("#")][1:], delimiter=",")  # after the provenance and the names
b = np.loadtxt(sys.argv[2], delimiter=",")
n = 3 * int(sys.argv[3])
print(f"{np.abs(a[-1, 1:1 + n] - b[-1, 1:1 + n]).max():.2e}")
PY
)
  printf '%6s %6s | %9.2f %8.2f %7.0f | %9.2f %8.2f %7.0f | %6.2f %6.2f | %s\n' "$N" $((3 * N)) \
    "$t_nhdyn" "$c_nhdyn" "$(echo "$m_nhdyn / 1024" | bc -l)" "$t_scipy" "$c_scipy" "$(echo "$m_scipy / 1024" | bc -l)" \
    "$(echo "$t_scipy / $t_nhdyn" | bc -l)" "$(echo "$c_scipy / $c_nhdyn" | bc -l)" "$diff"
done
echo "ratio: SciPy's wall time over nhdyn's, cpu: the same for user + system CPU time (above 1: nhdyn is faster)"
