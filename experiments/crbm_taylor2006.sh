#!/usr/bin/env bash
# Taylor, Hinton & Roweis 2006 on CMU subject 35: regenerates the figures of
# docs/results/crbm.md:
#   - the missing-data table (walking trial 35_29, leg / upper body): nearest neighbour 11.68 /
#     22.20, CRBM 9.43 / 10.36 (sampled hiddens 9.68 / 11.37), AR(3) 12.62 / 9.21; jogging
#     trial 35_18 beside it;
#   - the same CRBM trained without noise on its past frames (the paper's training): 7.99 / 19.94;
#   - generation: 1,000 frames from the walking test frames stay walking at 1.2 m/s (seeds
#     0-3), from the jogging ones jogging at 3.1 m/s; noise on the hidden biases (std 1, 3)
#     brings walk/jog transitions back (7 label changes in 1,000 frames at std 1).
# Time: three CRBM trainings of 4,000 passes (benchmarks/bench_crbm_train.py times one; its
# target is under 10 minutes on one core) plus the fill-ins: about an hour.
# Usage: experiments/crbm_taylor2006.sh [OUT]   (default runs/crbm_taylor2006)
set -euo pipefail
source "$(dirname "$0")/common.sh"
OUT=${1:-runs/crbm_taylor2006}
need_data cmu35/cmu35WalkJog.mat
CMU="$DATA/cmu35"
mkdir -p "$OUT"

# 1. the table, with the selected settings (trains a CRBM and the AR(3) baseline)
"$ML" crbm reproduce --data "$CMU" --json --plots "$OUT/plots" > "$OUT/table.json"
# 2. the paper's training: no noise on the past frames
"$ML" crbm reproduce --data "$CMU" --history-noise 0 --json > "$OUT/table_no_history_noise.json"
# 3. generation from the test trials' first frames
"$ML" train crbm --data "$CMU" --out "$OUT/crbm"
for seed in 0 1 2 3; do
  "$ML" crbm generate "$OUT/crbm" "$OUT/walk_$seed.gif" --data "$CMU" --start walk --seed $seed \
      --json > "$OUT/walk_$seed.json"
done
"$ML" crbm generate "$OUT/crbm" "$OUT/jog.gif" --data "$CMU" --start jog --json > "$OUT/jog.json"
for noise in 1 3; do
  "$ML" crbm generate "$OUT/crbm" "$OUT/transitions_$noise.gif" --data "$CMU" --start walk \
      --noise $noise --json > "$OUT/transitions_$noise.json"
done
echo "tables and generation reports in $OUT"
