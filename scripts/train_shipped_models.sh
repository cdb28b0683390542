#!/usr/bin/env bash
# Rebuild the small M2L and L2M models shipped in src/motionlang/data/models/.
# Usage: scripts/train_shipped_models.sh [WORKDIR]   (default /tmp/motionlang_shipped)
# Needs ~2 GB of disk in WORKDIR; about 20 min per model on 2 shared CPU cores.
# (The shipped M2L was trained 8 epochs, then continued to 14 with --resume in a copy of the
# run folder; the trainer's tests check that resume equals an uninterrupted run.)
set -euo pipefail
WORK=${1:-/tmp/motionlang_shipped}
HERE=$(cd "$(dirname "$0")/.." && pwd)
ML="${ML:-$HERE/.venv/bin/motionlang}"
export OMP_NUM_THREADS=1 MOTIONLANG_CACHE="$WORK/cache"
mkdir -p "$WORK"
# 1. procedural corpus (deterministic for a given seed)
[ -f "$WORK/corpus/.done" ] || { "$ML" data synth --out "$WORK/corpus" --n 3000 --seed 0 --workers 1 \
    && touch "$WORK/corpus/.done"; }
# 2. the two models (paper-size M2L, shrunk L2M decoder); both runs may go in parallel
"$ML" train m2l --data "$WORK/corpus" --out "$WORK/m2l" --epochs 14 --batch-size 64 --offsets 1 &
"$ML" train l2m --data "$WORK/corpus" --out "$WORK/l2m" --epochs 8 --batch-size 64 --offsets 1 \
    --dec-hidden 128 --dec-layers 2 --components 5 --end-weight 10 &
wait
# 3. ship the best checkpoints (self-describing: config, vocabulary, normaliser, weights)
mkdir -p "$HERE/src/motionlang/data/models"
cp "$WORK/m2l/model.pt" "$HERE/src/motionlang/data/models/m2l.pt"
cp "$WORK/l2m/model.pt" "$HERE/src/motionlang/data/models/l2m.pt"
