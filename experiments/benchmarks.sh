#!/usr/bin/env bash
# The README's benchmark table: reading speed of a 10-minute BVH (3.1 s; bar 5 s), every
# command on 103 real takes (0 failures), 10,000 mutated inputs per format (0 crashes, hangs
# or uncaught errors), 118 bad command lines (exit 2, one line, nothing left behind), the MIT
# .mat reader (22 ms).
# Needs the shared real data for the real-take sweep and the MIT file.
# Time: the fuzzing dominates (10,000 inputs for each of six formats, each in a child process:
# hours); the rest takes minutes. FUZZ=0 skips it.
# Usage: experiments/benchmarks.sh [OUT]   (default runs/benchmarks)
set -euo pipefail
source "$(dirname "$0")/common.sh"
OUT=${1:-runs/benchmarks}
mkdir -p "$OUT"
B="$HERE/benchmarks"
OMP_NUM_THREADS=1 "$PY" "$B/bench_bvh_read.py" | tee "$OUT/bvh_read.txt"
"$PY" "$B/real_rigs_commands.py" --n 100 --seed 0 | tee "$OUT/real_rigs.txt"
"$PY" "$B/cli_bad_inputs.py" | tee "$OUT/cli_bad_inputs.txt"
"$PY" "$B/bench_mit_read.py" | tee "$OUT/mit_read.txt"
if [ "${FUZZ:-1}" != 0 ]; then
  "$PY" "$B/fuzz_readers.py" | tee "$OUT/fuzz_readers.txt"
fi
echo "outputs in $OUT"
