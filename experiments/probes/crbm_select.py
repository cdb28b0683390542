"""Hyper-parameter selection for `motionlang crbm reproduce` on held-out TRAINING trials.

    python experiments/probes/crbm_select.py --data ../shared/data/cmu35 --out select.json \
        --weight-decays 2e-4 2e-3 2e-2 --epochs 500 1000 2000 4000 --n-gibbs 5 30 --mean-field both

Prints one JSON line per (setting, snapshot) and writes the whole grid to --out.
"""
import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # experiments.lab

from experiments.lab.crbm_select import SelectionConfig, select  # noqa: E402

from motionlang.utils.atomic import atomic_write  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--weight-decays", type=float, nargs="+", default=[0.0, 2e-4, 2e-3])
    ap.add_argument("--learning-rates", type=float, nargs="+", default=[1e-3])
    ap.add_argument("--epochs", type=int, nargs="+", default=[1000, 2000])
    ap.add_argument("--n-gibbs", type=int, nargs="+", default=[5, 30])
    ap.add_argument("--ar-decays", type=lambda v: None if v == "same" else float(v), nargs="+",
                    default=None,
                    help="weight decays of the autoregressive weights A (\"same\": W's; default same)")
    ap.add_argument("--history-noises", type=float, nargs="+", default=[0.0],
                    help="noise on the past frames while training (CRBMConfig.history_noise)")
    ap.add_argument("--mean-field", choices=["no", "yes", "both"], default="no")
    ap.add_argument("--repeats", type=int, default=20)
    a = ap.parse_args()
    mf = {"no": (False,), "yes": (True,), "both": (False, True)}[a.mean_field]
    cfg = SelectionConfig(weight_decays=tuple(a.weight_decays), learning_rates=tuple(a.learning_rates),
                          epochs=tuple(a.epochs), n_gibbs=tuple(a.n_gibbs), mean_fields=mf,
                          n_repeats=a.repeats,
                          ar_decays=tuple(a.ar_decays) if a.ar_decays else (None,),
                          history_noises=tuple(a.history_noises))
    res = select(a.data, cfg, log=lambda s: print(s, flush=True))
    with atomic_write(a.out) as f:
        json.dump(res, f, indent=1)
    print("best:", json.dumps(res["best"]))


if __name__ == "__main__":
    main()
