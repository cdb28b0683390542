#!/usr/bin/env bash
# Plappert et al. 2018's setting on the real KIT Motion-Language Dataset: download the release,
# train the M2L (paper size, attention) and the L2M on MMM joint angles, and score them
# (BLEU/ROUGE/CIDEr, the round trip). No figure of this is in docs/results/ yet: the machines
# the results were measured on cannot download KIT-ML. Compare with the paper's tables.
# Needs network access to KIT's server. Training takes hours on one core (for scale: the
# packaged M2L's 12 epochs on 4,800 procedural motions took ~30 min; KIT-ML has 3,911 motions,
# those up to 30 s kept).
# Usage: experiments/seq2seq_kitml.sh [OUT]   (default runs/seq2seq_kitml; KITML=DIR reuses an
# extracted release)
set -euo pipefail
source "$(dirname "$0")/common.sh"
OUT=${1:-runs/seq2seq_kitml}
KITML=${KITML:-$OUT/kitml}
mkdir -p "$OUT"
[ -d "$KITML" ] || "$ML" data download kitml --dest "$KITML"
"$ML" data info "$KITML" | tee "$OUT/kitml_info.txt"

"$ML" train m2l --data "$KITML" --out "$OUT/m2l" --attention --epochs 12 --batch-size 64 \
    --threads "$THREADS"
"$ML" train l2m --data "$KITML" --out "$OUT/l2m" --batch-size 64 --threads "$THREADS"
"$ML" evaluate --m2l "$OUT/m2l" --data "$KITML" -o "$OUT/m2l.json"
"$ML" evaluate --m2l "$OUT/m2l" --t2m "$OUT/l2m:method=sample" --data "$KITML" \
    --splits "$OUT/m2l/splits" -o "$OUT/round_trip.json"
echo "reports in $OUT"
