#!/usr/bin/env bash
# The paper's ablations on real motion (issue #42, item 4): the two-stream model and its
# variants without the hierarchy (one stream), without the discriminator (adversarial
# weight 0) and without the manifold loss, each trained on the Bandai Namco takes alone
# (mirrored copies too) with the recipe's losses and inputs, EPOCHS epochs at the constant
# rate, the epoch kept by validation R-precision under the Bandai evaluator (256 validation
# pairs each epoch: --select-evaluator); then all of them on the 556 test takes under that
# evaluator (Guo et al. 2022 protocol) and the judge. Tables: docs/results/twostream.md,
# "The ablations on real motion".
#
# Usage: experiments/twostream_ablations_bandai.sh [OUT]   (default runs/ts_ablations_bandai)
# Environment: EVALUATOR (default runs/evaluator_bandai: `motionlang train evaluator --data
# bandai:DIR --out runs/evaluator_bandai --epochs 10`), EPOCHS (default 6), ONLY (one
# variant's name: train that one and stop, e.g. to run two at once), THREADS.
# Time: an epoch of the Bandai takes is 366 steps, 3.5-4 minutes on one core, and scoring
# the validation pairs about one more; six epochs of four variants, 1.5-2 hours on one
# core. Runs are resumable: rerun after an interruption (a finished variant is kept as it
# is: remove its folder to train it to another EPOCHS). Non-commercial (CC BY-NC 4.0).
set -euo pipefail
source "$(dirname "$0")/common.sh"
need_data bandai
OUT=${1:-runs/ts_ablations_bandai}
EVALUATOR=${EVALUATOR:-runs/evaluator_bandai}
EPOCHS=${EPOCHS:-6}
BANDAI="bandai:$DATA/bandai"
mkdir -p "$OUT"
RECIPE=(--data "$BANDAI" --mirror --h 128 --batch-size 32 --length-buckets 20
        --z-every-step --progress-input --threads "$THREADS" --checkpoint-every 100
        --select-evaluator "$EVALUATOR" --epochs "$EPOCHS")

VARIANTS=" full one_stream no_discriminator no_manifold "
if [ -n "${ONLY:-}" ] && [[ "$VARIANTS" != *" $ONLY "* ]]; then
  echo "ONLY=$ONLY: not one of$VARIANTS" >&2
  exit 2
fi
train() {   # train NAME [options]
  local name=$1; shift
  [ -n "${ONLY:-}" ] && [ "$ONLY" != "$name" ] && return 0
  [ -f "$OUT/$name/model.pt" ] && return 0       # finished before (at its EPOCHS)
  local resume=()
  if [ -f "$OUT/$name/last.pt" ]; then
    resume=(--resume)
  elif [ -n "$(ls -A "$OUT/$name" 2>/dev/null)" ]; then
    resume=(--overwrite)                         # stopped before its first checkpoint
  fi
  "$ML" train twostream "${RECIPE[@]}" --out "$OUT/$name" "$@" ${resume[@]+"${resume[@]}"}
}
train full --weight energy=10
train one_stream --ablation one-stream --weight energy=10
train no_discriminator --weight energy=10 --weight adversarial=0
train no_manifold --weight energy=10 --weight manifold=0
[ -n "${ONLY:-}" ] && exit 0

MODELS=(--model full="$OUT/full/model.pt" --model one-stream="$OUT/one_stream/model.pt"
        --model no-discriminator="$OUT/no_discriminator/model.pt"
        --model no-manifold="$OUT/no_manifold/model.pt")
"$ML" evaluate-t2m --protocol guo --evaluator "$EVALUATOR" --data "$BANDAI" --split test \
    --fid-reference val --m2l none --threads "$THREADS" "${MODELS[@]}" -o "$OUT/guo_test"
"$ML" evaluate-judge --judge judge --data "$BANDAI" "${MODELS[@]}" --threads "$THREADS" \
    -o "$OUT/judge"
echo "tables: $OUT/guo_test/t2m_guo.md and $OUT/judge/"
