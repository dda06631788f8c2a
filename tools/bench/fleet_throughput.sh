#!/bin/sh
# Throughput of `driftlab fleet` (issue 24): units per minute for 1 h, 100 Hz whole-IMU logs
# (devices/imu3.yaml: 2 instances x gyro + accel, 12 channels), per model kind; the cost of one
# unit by stage (--timings: read, gate, fit, figures, discrepancy, exports; the report once); and
# the MPI engine with 1, 2 and 4 worker ranks (mpirun -np 2, 3, 5; rank 0 deals the units).
#
#   tools/bench/fleet_throughput.sh build/tools/driftlab/driftlab /tmp/fleet_bench [UNITS]
#
# Prints one line per run: what, units, wall s, CPU s (user + sys of the whole run), units/min
# (wall), and the per-unit stage times of the runs with --timings. Writes ~165 MB per unit.
set -eu
DRIFTLAB=$1
OUT=$2
UNITS=${3:-4}
mkdir -p "$OUT"
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); load before: $(cut -d' ' -f1-3 /proc/loadavg)"

run() {  # run WHAT CMD...: the wall and CPU of one command
  what=$1
  shift
  /usr/bin/time -f "%e %U %S" -o "$OUT/time.txt" "$@" >"$OUT/$what.log" 2>&1 || true
  set -- $(cat "$OUT/time.txt")
  awk -v w="$what" -v n="$UNITS" -v e="$1" -v u="$2" -v s="$3" \
    'BEGIN { printf "%-28s %3d units  wall %7.1f s  CPU %7.1f s  %6.2f units/min\n", w, n, e, u + s, 60 * n / e }'
  grep -o '\[read.*\]' "$OUT/$what.log" | sed 's/^/    /' || true
  grep '^report:' "$OUT/$what.log" | sed 's/^/    /' || true
}

run simulate "$DRIFTLAB" simulate --fleet "$UNITS" --device imu3 --fs 100 --duration 3600 --seed 1 \
  --outliers none --out "$OUT/sim"
for model in poly physical rbf; do
  rm -rf "$OUT/fleet_$model"
  run "fleet --model $model" "$DRIFTLAB" fleet --manifest "$OUT/sim/manifest.csv" --out "$OUT/fleet_$model" \
    --model "$model" --workers 2 --timings
done
rm -rf "$OUT/fleet_discrepancy"
run "fleet physical discrepancy" "$DRIFTLAB" fleet --manifest "$OUT/sim/manifest.csv" --out "$OUT/fleet_discrepancy" \
  --workers 2 --timings --discrepancy
if command -v mpirun >/dev/null; then
  for np in 2 3 5; do
    rm -rf "$OUT/mpi_$np"
    run "mpirun -np $np (physical)" env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
      mpirun --oversubscribe -np "$np" "$DRIFTLAB" fleet --manifest "$OUT/sim/manifest.csv" --out "$OUT/mpi_$np"
  done
fi
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
