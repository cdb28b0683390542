#!/usr/bin/env bash
# An M2L trained on the procedural corpus and the Bandai Namco takes, half of each epoch each
# (issue #24): BLEU-4 and the share of top descriptions naming the action and style on the
# Bandai test takes, BLEU on the procedural test set (docs/results/real-motion.md).
# Usage: experiments/m2l_procedural_bandai.sh [OUT] (default runs/m2l_procedural_bandai);
# EPOCHS (default 8). Resumable: run it again and it continues from OUT/m2l/last.pt.
# Time on one shared core: data preparation ~23 min the first time (cached after), then
# ~6.5 min an epoch. The model is trained on CC BY-NC 4.0 data: non-commercial use only.
set -euo pipefail
source "$(dirname "$0")/common.sh"
OUT=${1:-runs/m2l_procedural_bandai}
EPOCHS=${EPOCHS:-8}
need_data bandai
mkdir -p "$OUT"
export MOTIONLANG_CACHE="${MOTIONLANG_CACHE:-$OUT/cache}"
corpus "${CORPUS:-$OUT/corpus6000}"
C="${CORPUS:-$OUT/corpus6000}"
RESUME=""
[ -f "$OUT/m2l/last.pt" ] && RESUME=--resume
"$ML" train m2l --data "$C@1" --data "bandai:$DATA/bandai@1" --features positions --attention \
    --offsets 1 --batch-size 64 --mirror --checkpoint-every 200 --out "$OUT/m2l" \
    --epochs "$EPOCHS" --threads "$THREADS" $RESUME
"$ML" evaluate --m2l "$OUT/m2l" --splits "$OUT/m2l/splits" --data "bandai:$DATA/bandai" \
    --threads "$THREADS" -o "$OUT/eval_bandai.json"
"$ML" evaluate --m2l "$OUT/m2l" --splits "$OUT/m2l/splits" --data "$C" \
    --threads "$THREADS" -o "$OUT/eval_procedural.json"
