#!/usr/bin/env bash
# Rebuild every model shipped in src/motionlang/data/models/ from scratch.
# Usage: scripts/train_shipped_models.sh [WORKDIR]   (default /tmp/motionlang_shipped)
#   MODELS=all (default)   m2l, l2m, judge and twostream (procedural corpus + Bandai Namco:
#                          CC BY-NC 4.0, non-commercial), then m2l-procedural and
#                          l2m-procedural (MIT)
#   MODELS=bandai          only the first four;   MODELS=procedural   only the MIT ones:
#                          the recipe for models free of the Bandai licence
#   BANDAI=DIR             the Bandai Namco datasets (default ../shared/data/bandai)
#   RESUME=--resume        continue interrupted runs from their last checkpoint
# Needs ~6 GB of disk in WORKDIR. Times on this project's 2-core machine, one core per model,
# two models side by side: corpus ~2 min; procedural + Bandai: data preparation ~25 min per
# run (fitting and encoding 6,750 training motions and their mirror images; cached by
# MOTIONLANG_CACHE), M2L ~7-10 min an epoch (8 epochs), L2M ~28 min a teacher-forced epoch and
# ~35 min an epoch on its own frames (1 + 1 + 1 + 1), judge ~10 min, Bandai evaluator ~10 min,
# two-stream ~11-13 min an epoch and ~2 min to score it (12 epochs, after the M2L);
# procedural alone: M2L ~30 min (12 epochs), L2M ~90 min (3 + 3 + 1 + 1).
# Every --out is a run folder: the final model is its model.pt (beside best.pt, last.pt,
# history.json, loss_curve.png, splits/ and commands.jsonl; LICENSE.txt for Bandai runs).
# OMP_NUM_THREADS=1: one thread per model as the two run side by side.
set -euo pipefail
WORK=${1:-/tmp/motionlang_shipped}
RESUME=${RESUME:-}
MODELS=${MODELS:-all}
HERE=$(cd "$(dirname "$0")/.." && pwd)
ML="${ML:-$HERE/.venv/bin/motionlang}"
PY="${PY:-$HERE/.venv/bin/python}"
BANDAI=${BANDAI:-$HERE/../shared/data/bandai}
SHIP="$HERE/src/motionlang/data/models"
export OMP_NUM_THREADS=1 MOTIONLANG_CACHE="$WORK/cache"
mkdir -p "$WORK" "$SHIP"
# 1. the procedural corpus (deterministic for a given seed): 6,000 motions (4,800 train),
#    the same split for every model
# (each finished step leaves a mark, so that RESUME=--resume does not run it again; `if`
#  blocks, not `[ ] || { a && touch; }`, so that set -e stops the script when a step fails)
if [ ! -f "$WORK/corpus6000/.done" ]; then
  "$ML" data synth --out "$WORK/corpus6000" --n 6000 --seed 0 --workers 1
  touch "$WORK/corpus6000/.done"
fi
C="$WORK/corpus6000"

# 2. both seq2seq models on the 21-joint position features (rig-independent: any motion that
#    maps onto the 21-joint body can be described; generated motions retarget onto any such
#    rig). M2L: paper size with additive attention (test BLEU 0.403 vs 0.386 without). L2M:
#    a 2 x 256 decoder, 5 components, a clock, the fraction of the motion done and a plan of
#    8 parts (its planner predicts it from the sentence), first teacher-forced epochs with
#    noisy inputs, then epochs with scheduled sampling (90 % own frames after 225 steps),
#    the last with the learning rate decayed; then a third stage, one epoch fed
#    its own *expected* frames (--rollout-input mean, learning rate 3e-4 decayed), so that
#    generation continues from the frames it was trained on (docs/results/real-motion.md,
#    seventh session: less skating, better recognised), and a fourth, one more such epoch with
#    a squared error on the expected frames (--mean-frames 10), without which the decoder
#    leaves gestures that start partway through a motion to a broad mixture component and
#    never starts them (eighth session: procedural waves and jumps); each model.pt is the
#    epoch with the best validation loss; then the planner alone 20 epochs more (minutes).
L2M_COMMON=(--batch-size 64 --offsets 1 --features positions --checkpoint-every 200
            --dec-hidden 256 --dec-layers 2 --components 5 --end-weight 10 --time-input
            --progress-input --plan-parts 8 --plan-noise 0.1)
# l2m_run OUT EPOCHS1 EPOCHS_TOTAL DECAY MEAN_EPOCHS MEAN_FRAMES_EPOCHS DATA_ARGS... : the
# stages and the planner
l2m_run() {
  local out=$1 e1=$2 e2=$3 decay=$4 e3=$5 e4=$6; shift 6
  local data=("$@") plan_mirror=()
  [[ " ${data[*]} " == *" --mirror "* ]] && plan_mirror=(--mirror)
  local plan_data=()
  for ((i = 0; i < ${#data[@]}; i++)); do
    [ "${data[$i]}" = --data ] && plan_data+=(--data "${data[$((i + 1))]}")
  done
  if [ ! -f "$out/.stage1" ]; then
    "$ML" train l2m "${data[@]}" --out "$out" "${L2M_COMMON[@]}" --epochs "$e1" \
        --input-noise 0.5 $RESUME
    touch "$out/.stage1"
  fi
  if [ ! -f "$out/.stage2" ]; then
    "$ML" train l2m "${data[@]}" --out "$out" "${L2M_COMMON[@]}" --epochs "$e2" \
        --decay-epochs "$decay" --rollout 0.9 --rollout-warmup 225 --resume
    touch "$out/.stage2"
  fi
  if [ "$e3" -gt 0 ] && [ ! -f "$out/.stage3" ]; then
    "$ML" train l2m "${data[@]}" --out "$out" "${L2M_COMMON[@]}" --epochs $((e2 + e3)) \
        --decay-epochs "$e3" --lr 0.0003 --rollout 0.9 --rollout-warmup 225 \
        --rollout-input mean --resume
    touch "$out/.stage3"
  fi
  if [ "$e4" -gt 0 ] && [ ! -f "$out/.stage4" ]; then
    "$ML" train l2m "${data[@]}" --out "$out" "${L2M_COMMON[@]}" --epochs $((e2 + e3 + e4)) \
        --decay-epochs "$e4" --lr 0.0003 --rollout 0.9 --rollout-warmup 225 \
        --rollout-input mean --mean-frames 10 --resume
    touch "$out/.stage4"
  fi
  "$PY" "$HERE/scripts/l2m_fit_planner.py" "$out/model.pt" "${plan_data[@]}" "${plan_mirror[@]}" \
      --out "$out/planned.pt" --epochs 20
}

if [ "$MODELS" = all ] || [ "$MODELS" = bandai ]; then
  # procedural corpus and Bandai Namco takes, half of every epoch each, mirrored copies too
  MIX=(--data "$C@1" --data "bandai:$BANDAI@1" --mirror)
  "$ML" train m2l "${MIX[@]}" --out "$WORK/m2l" --epochs 8 --batch-size 64 --offsets 1 \
      --attention --features positions --checkpoint-every 200 $RESUME &
  M2L=$!
  l2m_run "$WORK/l2m" 1 2 1 1 1 "${MIX[@]}" &
  L2M=$!
  wait $M2L
  "$ML" train judge --data "bandai:$BANDAI" --out "$WORK/judge" --epochs 30
  # the two-stream model (Ghosh et al. 2021 with the recipe's additions, docs/results/
  # twostream.md): each source normalised by its own motions, every epoch scored on the
  # Bandai validation pairs by a Bandai evaluator (with its first pose and source fitted)
  # and the best kept; 6 epochs (the last 2 decayed), 6 more at half the rate (the last 3
  # decayed), 6 more at a quarter (the last 3 decayed): epoch 18 was kept; stored in float16
  "$ML" train evaluator --data "bandai:$BANDAI" --out "$WORK/evaluator_bandai" --epochs 10
  TS=(train twostream "${MIX[@]}" --out "$WORK/twostream" --h 128 --batch-size 32
      --length-buckets 20 --z-every-step --progress-input --weight energy=10 --threads 1
      --normalise by-source --select-evaluator "$WORK/evaluator_bandai"
      --select-data "bandai:$BANDAI" --checkpoint-every 100)
  if [ ! -f "$WORK/twostream/.stage1" ]; then
    "$ML" "${TS[@]}" --epochs 6 --decay-epochs 2 $RESUME
    touch "$WORK/twostream/.stage1"
  fi
  if [ ! -f "$WORK/twostream/.stage2" ]; then
    "$ML" "${TS[@]}" --resume --epochs 12 --lr 5e-4 --decay-epochs 3
    touch "$WORK/twostream/.stage2"
  fi
  "$ML" "${TS[@]}" --resume --epochs 18 --lr 2.5e-4 --decay-epochs 3
  wait $L2M   # (set -e) a failed run stops the script before anything is shipped
  cp "$WORK/m2l/model.pt" "$SHIP/m2l.pt"
  cp "$WORK/l2m/planned.pt" "$SHIP/l2m.pt"
  cp "$WORK/judge/model.pt" "$SHIP/judge.pt"
  "$PY" "$HERE/experiments/masked_root_path.py" half "$WORK/twostream/model.pt" \
      "$SHIP/twostream.pt"
fi

if [ "$MODELS" = all ] || [ "$MODELS" = procedural ]; then
  # the procedural corpus alone (MIT): M2L 12 epochs, L2M 3 + 3 + 1 + 1 epochs (the last two
  # since the ninth session: before them it did 13 % of the procedural gestures)
  "$ML" train m2l --data "$C" --out "$WORK/m2l-procedural" --epochs 12 --batch-size 64 \
      --offsets 1 --attention --features positions --checkpoint-every 200 $RESUME &
  M2L=$!
  l2m_run "$WORK/l2m-procedural" 3 6 2 1 1 --data "$C" &
  L2M=$!
  wait $M2L; wait $L2M
  cp "$WORK/m2l-procedural/model.pt" "$SHIP/m2l-procedural.pt"
  cp "$WORK/l2m-procedural/planned.pt" "$SHIP/l2m-procedural.pt"
fi
