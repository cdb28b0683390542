#!/usr/bin/env bash
# The procedural-only M2L and L2M (m2l-procedural, l2m-procedural; the packaged m2l and l2m
# until 2026-11-24; 21-joint body, position features): regenerates the first section
# of docs/results/seq2seq.md and the real-motion figures of docs/results/real-rigs.md:
#   - M2L on the 600 procedural test motions: BLEU 0.404 (nearest neighbour 0.293), actions
#     exactly right 86.2 %, side and direction 100 %, count 95.4 %;
#   - L2M round trip through the M2L, expected frames, 200 test sentences: 86.5 %
#     (the l2m-procedural of before the ninth session: 60.8 %);
#   - what the M2L says about real takes (describe -w 3), and every command on 103 real files.
# It evaluates the models in src/motionlang/data/models as they are; to rebuild them first,
# run MODELS=procedural scripts/train_shipped_models.sh (~1 h 45 min, ~4 GB).
# Time: the corpus (a few minutes), then each evaluate encodes it (tens of minutes on one core;
# not timed end to end); the real-file sweep a few minutes.
# Usage: experiments/seq2seq_packaged.sh [OUT]   (default runs/seq2seq_packaged; CORPUS=DIR
# reuses a corpus)
set -euo pipefail
source "$(dirname "$0")/common.sh"
OUT=${1:-runs/seq2seq_packaged}
CORPUS=${CORPUS:-$OUT/corpus}
M="$HERE/src/motionlang/data/models"
mkdir -p "$OUT"
corpus "$CORPUS"
# the split both packaged models were trained with (seed 0, 80/10/10 by motion)
"$ML" data split "$CORPUS" --seed 0 --out "$OUT/splits"

"$ML" evaluate --m2l "$M/m2l-procedural.pt" --data "$CORPUS" --splits "$OUT/splits" -o "$OUT/m2l.json"
"$ML" evaluate --m2l "$M/m2l-procedural.pt" --t2m "$M/l2m-procedural.pt:method=mean" --data "$CORPUS" \
    --splits "$OUT/splits" --limit 200 -o "$OUT/round_trip.json"

if [ -e "$DATA/cmu35/35_01.amc" ]; then
  for f in cmu35/35_01.amc kitml/00001_mmm.xml cmu49/49_20.amc; do
    echo "== $f"
    "$ML" describe "$DATA/$f" -w 3 --model m2l-procedural
  done | tee "$OUT/real_takes.txt"
  "$PY" "$HERE/benchmarks/real_rigs_commands.py" --n 100 --seed 0 | tee "$OUT/real_rigs.txt"
else
  echo "no shared data at $DATA: real takes skipped" >&2
fi
echo "reports in $OUT"
