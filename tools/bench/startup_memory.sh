#!/bin/sh
# Start-up and peak memory of the commands a user feels: wall time and peak resident set size
# (/usr/bin/time %e, %M) of `driftlab --version`, `entropy` on a 1e3-sample record, `decompose` at
# 1e6 samples, `allan` at 1e6 and 1e7 samples and the li2023 `run` at 1e6 samples (2 threads), on
# the benchmark records of tools/bench/gen_signals.py (generated into DIR when missing; the 1e7
# record is written as a 3-column CSV from gyro_N10000000.f64, about 480 MB; numpy, $PYTHON or python3).
#
#   tools/bench/startup_memory.sh build/tools/driftlab/driftlab DIR [RUNS]
#
# Prints one line per command: the median wall time and the largest peak RSS over RUNS runs
# (default 3). Outputs go to DIR/out and are removed after each run.
set -eu
DRIFTLAB=$1
DIR=$2
RUNS=${3:-3}
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$DIR/out"
[ -f "$DIR/gyro_N1000000.csv" ] || "${PYTHON:-python3}" "$HERE/gen_signals.py" --out "$DIR" >/dev/null
if [ ! -f "$DIR/gyro_N10000000.csv" ]; then
  "${PYTHON:-python3}" - "$DIR" <<'PY'
import sys, numpy as np
d = sys.argv[1]
rate = np.fromfile(f"{d}/gyro_N10000000.f64", dtype="<f8")
t = np.arange(rate.size) / 100.0
with open(f"{d}/gyro_N10000000.csv.tmp", "w") as f:
    f.write("t_s,rate_dps,temp_c\n")
    for k in range(0, rate.size, 1000000):
        block = np.column_stack([t[k:k + 1000000], rate[k:k + 1000000], np.full(min(1000000, rate.size - k), 25.0)])
        np.savetxt(f, block, fmt=["%.2f", "%.17g", "%.1f"], delimiter=",")
PY
  mv "$DIR/gyro_N10000000.csv.tmp" "$DIR/gyro_N10000000.csv"
fi
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); load before: $(cut -d' ' -f1-3 /proc/loadavg)"

measure() {  # measure WHAT CMD...: median wall and largest peak RSS over RUNS runs
  what=$1
  shift
  : >"$DIR/out/times.txt"
  i=0
  while [ "$i" -lt "$RUNS" ]; do
    /usr/bin/time -f "%e %M" -a -o "$DIR/out/times.txt" "$@" >/dev/null 2>"$DIR/out/stderr.txt" ||
      { echo "$what: failed"; cat "$DIR/out/stderr.txt"; exit 1; }
    rm -rf "$DIR/out/run" "$DIR/out/decompose.csv" "$DIR/out/allan.csv"
    i=$((i + 1))
  done
  sort -n "$DIR/out/times.txt" | awk -v w="$what" '{ t[NR] = $1; if ($2 > m) m = $2 }
    END { printf "%-34s wall %8.3f s   peak RSS %7.1f MiB\n", w, t[int((NR + 1) / 2)], m / 1024 }'
}

head -n 1001 "$DIR/gyro_N1000000.csv" >"$DIR/out/small.csv"
measure "driftlab --version" "$DRIFTLAB" --version
measure "entropy, 1e3 samples" "$DRIFTLAB" entropy --data "$DIR/out/small.csv"
measure "decompose, 1e6 samples" "$DRIFTLAB" -q decompose --data "$DIR/gyro_N1000000.csv" --out "$DIR/out/decompose.csv"
measure "allan, 1e6 samples" "$DRIFTLAB" -q allan --data "$DIR/gyro_N1000000.csv" --out "$DIR/out/allan.csv"
measure "allan, 1e7 samples" "$DRIFTLAB" -q allan --data "$DIR/gyro_N10000000.csv" --out "$DIR/out/allan.csv"
measure "run li2023, 1e6 samples, 2 threads" "$DRIFTLAB" -q --threads 2 run --pipeline "$HERE/../../models/pipelines/li2023.yaml" \
  --data "$DIR/gyro_N1000000.csv" --out "$DIR/out/run"
