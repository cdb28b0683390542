#!/usr/bin/env bash
# The angle-feature M2L and L2M packaged from 2026-11-22 to 2026-11-24 (MMM joint angles at
# 10 Hz; replaced by the 21-joint models): regenerates their headline figures in
# docs/results/seq2seq.md:
#   - M2L (attention): BLEU 0.403 on the 600 test motions (nearest neighbour 0.277), actions
#     exactly right 87 %; ranked per token (--length-penalty 1): 0.434;
#   - L2M with a plan, one ancestral sample per sentence, all 600: round trip 66.5 % (paper
#     65.5 %), 70.4 % at temperature 1.2;
#   - the same L2M judged without an M2L (evaluate-t2m): APE 109.7 mm from one sample, 98.3 mm
#     with mean decoding;
#   - directions, 9 samples each: backwards 9/9, left 9/9, right 6/9, forward 9/9.
# The two model files are taken from git (commit cd6ad22), so this runs in a clone of the
# repository. Time: the corpus (a few minutes), then five evaluations over the 600 test
# motions (tens of minutes each on one core; not timed end to end).
# Usage: experiments/seq2seq_angle_models.sh [OUT]   (default runs/seq2seq_angle_models;
# CORPUS=DIR reuses a corpus)
set -euo pipefail
source "$(dirname "$0")/common.sh"
OUT=${1:-runs/seq2seq_angle_models}
CORPUS=${CORPUS:-$OUT/corpus}
mkdir -p "$OUT/models"
for m in m2l l2m; do
  git -C "$HERE" show "cd6ad22:src/motionlang/data/models/$m.pt" > "$OUT/models/$m.pt"
done
M2L="$OUT/models/m2l.pt" L2M="$OUT/models/l2m.pt"
corpus "$CORPUS"
"$ML" data split "$CORPUS" --seed 0 --out "$OUT/splits"

"$ML" evaluate --m2l "$M2L" --data "$CORPUS" --splits "$OUT/splits" -o "$OUT/m2l.json"
"$ML" evaluate --m2l "$M2L" --data "$CORPUS" --splits "$OUT/splits" --length-penalty 1 \
    -o "$OUT/m2l_per_token.json"
"$ML" evaluate --m2l "$M2L" --t2m "$L2M:method=sample" --data "$CORPUS" --splits "$OUT/splits" \
    -o "$OUT/round_trip.json"
"$ML" evaluate --m2l "$M2L" --t2m "$L2M:method=sample,temperature=1.2" --data "$CORPUS" \
    --splits "$OUT/splits" -o "$OUT/round_trip_t1.2.json"
"$ML" evaluate-t2m --data "$CORPUS" --model "l2m=$L2M:method=sample" -o "$OUT/t2m_sample"
"$ML" evaluate-t2m --data "$CORPUS" --model l2m="$L2M" -o "$OUT/t2m_mean"
"$PY" "$HERE/experiments/probes/l2m_directions.py" --data "$CORPUS" --model "$L2M" \
    | tee "$OUT/directions.txt"
echo "reports in $OUT"
