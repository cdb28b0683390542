#!/usr/bin/env bash
# The two-stream model against its four ablations at equal budget (8 epochs, then 2 with the
# learning rate decayed; no joint training: 3 + 3 epochs), the recipe's losses and inputs:
# regenerates these rows of docs/results/twostream.md (600 test sentences, APE local / order):
#   full 85.0 mm / 55 %, one stream 84.8 / 59 %, no extra losses 84.8 / 58 %, word vectors
#   84.9 / 64 %; no joint training (3 + 3, not decayed) 89.5 / 39 %.
# Time: four 10-epoch runs and one of 3 + 3 epochs at h = 128 on one core: a day or more
# (not timed end to end). Runs are resumable: rerun the script after an interruption.
# Usage: experiments/twostream_ablations.sh [OUT]   (default runs/twostream_ablations;
# CORPUS=DIR reuses a corpus)
set -euo pipefail
source "$(dirname "$0")/common.sh"
OUT=${1:-runs/twostream_ablations}
CORPUS=${CORPUS:-$OUT/corpus}
mkdir -p "$OUT"
corpus "$CORPUS"
RECIPE=(--data "$CORPUS" --h 128 --batch-size 32 --length-buckets 20 --z-every-step
        --progress-input --weight energy=10 --threads "$THREADS")

train() {   # train NAME ABLATION EPOCHS [more options]
  local name=$1 ablation=$2 epochs=$3; shift 3
  [ -f "$OUT/$name/model.pt" ] && return 0       # finished before
  local resume=()
  [ -f "$OUT/$name/last.pt" ] && resume=(--resume)
  "$ML" train twostream "${RECIPE[@]}" --ablation "$ablation" --out "$OUT/$name" \
      --epochs "$epochs" "$@" ${resume[@]+"${resume[@]}"}
}
train full full 10 --decay-epochs 2
train one_stream one-stream 10 --decay-epochs 2
train no_extra_losses no-extra-losses 10 --decay-epochs 2
train word_vectors word-vectors 10 --decay-epochs 2
train no_joint_training no-joint-training 3

"$ML" evaluate-t2m --data "$CORPUS" --autoencode -o "$OUT/t2m" \
    --model full="$OUT/full/model.pt" \
    --model one-stream="$OUT/one_stream/model.pt" \
    --model no-extra-losses="$OUT/no_extra_losses/model.pt" \
    --model word-vectors="$OUT/word_vectors/model.pt" \
    --model no-joint-training="$OUT/no_joint_training/model.pt"
echo "table in $OUT/t2m/t2m_table.md"
