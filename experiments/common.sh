# Sourced by the experiments/*.sh scripts (not run on its own): where the project, its
# command and its data are, and the procedural corpus every seq2seq and two-stream figure uses.
#
# Environment: ML (the motionlang command; default .venv/bin/motionlang of this project),
# PY (its Python), MOTIONLANG_DATA (the shared real data; default ../shared/data beside the
# project), THREADS (torch threads per command; default 1, what the figures were measured with).

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
ML="${ML:-$HERE/.venv/bin/motionlang}"
PY="${PY:-$HERE/.venv/bin/python}"
DATA="${MOTIONLANG_DATA:-$HERE/../shared/data}"
THREADS="${THREADS:-1}"
export OMP_NUM_THREADS="$THREADS"

# corpus DIR: the procedural corpus of the results pages (6,000 motions, seed 0; 5,000 take
# 2.7 GB and about 3 minutes, 6,000 proportionally more). Kept between runs: a .done marker
# says it is complete, so several experiments can share one (CORPUS=DIR in each script).
corpus() {
  local dir=$1
  if [ ! -f "$dir/.done" ]; then
    "$ML" data synth --out "$dir" --n 6000 --seed 0
    touch "$dir/.done"
  fi
}

# need_data SUBDIR: stop with a clear message when the shared real data is absent.
need_data() {
  if [ ! -e "$DATA/$1" ]; then
    echo "needs $DATA/$1 (set MOTIONLANG_DATA to the shared data folder)" >&2
    exit 2
  fi
}
