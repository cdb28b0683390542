#!/usr/bin/env bash
# Rebuild the M2L and L2M models shipped in src/motionlang/data/models/.
# Usage: scripts/train_shipped_models.sh [WORKDIR]   (default /tmp/motionlang_shipped)
# Needs ~4 GB of disk in WORKDIR. On this project's 2-core machine (one core per model):
# corpus ~2 min, features ~15 min (both runs fit and encode the corpus), M2L ~30 min alone
# (12 epochs at ~110 seq/s), L2M ~60 min (3 teacher-forced epochs at ~40 seq/s, then 3 on
# its own frames at ~25 seq/s, then a few minutes for its planner). On 2026-11-24, with
# other work sharing the two cores, the whole rebuild took about 1 h 45 min.
# RESUME=--resume continues interrupted runs from their last checkpoint (stage 1 of the L2M
# and the M2L); M2L_EPOCHS overrides the M2L's 12 epochs.
# Every --out is a run folder: the final model is its model.pt (beside best.pt, last.pt,
# history.json, loss_curve.png, splits/ and commands.jsonl); OMP_NUM_THREADS=1 below is also
# every command's --threads default, one thread per model as the two run side by side.
set -euo pipefail
WORK=${1:-/tmp/motionlang_shipped}
RESUME=${RESUME:-}
HERE=$(cd "$(dirname "$0")/.." && pwd)
ML="${ML:-$HERE/.venv/bin/motionlang}"
PY="${PY:-$HERE/.venv/bin/python}"
export OMP_NUM_THREADS=1 MOTIONLANG_CACHE="$WORK/cache"
mkdir -p "$WORK"
# 1. the procedural corpus (deterministic for a given seed): 6,000 motions (4,800 train),
#    the same split for both models
for n in 6000; do
  [ -f "$WORK/corpus$n/.done" ] || { "$ML" data synth --out "$WORK/corpus$n" --n $n --seed 0 --workers 1 \
      && touch "$WORK/corpus$n/.done"; }
done
# 2. the two models, in parallel, both on the 21-joint position features (rig-independent:
#    any motion that maps onto the 21-joint body can be described, and generated motions
#    can be retargeted onto any such rig; since 2026-11-24, the angle-feature models before
#    them read MMM motions only). The M2L runs 12 epochs at a constant rate (the shipped one
#    was a 20-epoch run stopped after its 12th, the same thing; its validation loss still
#    fell by ~0.005 an epoch there): paper-size M2L with additive attention (the paper's
#    proposed next step; test BLEU 0.403 vs 0.386 without); L2M with a 2 x 256 decoder,
#    5 components, a clock, the fraction of the motion done and a plan of 8 parts (the
#    planner predicts it from the sentence): 3 teacher-forced epochs with noisy inputs, then
#    3 epochs with scheduled sampling (90 % own frames after the first of them), the last 2
#    with the learning rate decayed; each model.pt is the epoch with the best validation
#    loss (the L2M's: among the epochs of its second stage, on its own frames); then the
#    L2M's planner alone 20 epochs more (minutes; validation MSE ~0.172 -> ~0.158)
"$ML" train m2l --data "$WORK/corpus6000" --out "$WORK/m2l" --epochs ${M2L_EPOCHS:-12} --batch-size 64 \
    --offsets 1 --attention --features positions --checkpoint-every 200 $RESUME &
M2L=$!
L2M_OPTS=(--data "$WORK/corpus6000" --out "$WORK/l2m" --batch-size 64 --offsets 1 --features positions
          --checkpoint-every 200 --dec-hidden 256
          --dec-layers 2 --components 5 --end-weight 10 --time-input --progress-input
          --plan-parts 8 --plan-noise 0.1)
{ "$ML" train l2m "${L2M_OPTS[@]}" --epochs 3 --input-noise 0.5 $RESUME \
  && "$ML" train l2m "${L2M_OPTS[@]}" --epochs 6 --decay-epochs 2 --rollout 0.9 \
         --rollout-warmup 225 --resume \
  && "$PY" "$HERE/scripts/l2m_fit_planner.py" "$WORK/l2m/model.pt" --data "$WORK/corpus6000" \
         --out "$WORK/l2m/planned.pt" --epochs 20; } &
L2M=$!
wait $M2L; wait $L2M   # (set -e) a failed run stops the script before anything is shipped
# 3. ship the final checkpoints (self-describing: config, vocabulary, normaliser, weights)
mkdir -p "$HERE/src/motionlang/data/models"
cp "$WORK/m2l/model.pt" "$HERE/src/motionlang/data/models/m2l.pt"
cp "$WORK/l2m/planned.pt" "$HERE/src/motionlang/data/models/l2m.pt"
