"""Where a two-stream model loses its sentences: R-precision of the motions it decodes from
the sentence embedding (what ``generate`` does) beside those it decodes from each motion's
own pose embedding (its autoencoder), under a text-motion evaluator, on one caption per
motion of a split.

    .venv/bin/python experiments/probes/twostream_paths.py MODEL [MODEL ...] \
        --evaluator runs/evaluator_bandai --data bandai:../shared/data/bandai \
        [--split val] [--limit 160] [--repeats 5]

If the own-embedding motions keep their R-precision while the sentence's fall, the decoder
still tells motions apart and the sentence embeddings are what no longer reach the motions
that match them. Also printed: the spread of the evaluator's embeddings of the generated
motions (root mean square distance to their mean; the real motions' beside them), which
falls as the motions made from different sentences grow alike.
"""
from __future__ import annotations

import argparse
import sys


def spread(x) -> float:
    """Root mean square distance of rows (N, D) to their mean."""
    import numpy as np
    a = np.asarray(x, dtype=np.float64)
    return float(np.sqrt(((a - a.mean(0)) ** 2).sum(1).mean()))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("models", nargs="+", help="two-stream model files")
    ap.add_argument("--evaluator", required=True)
    ap.add_argument("--data", required=True, help="e.g. bandai:../shared/data/bandai")
    ap.add_argument("--split", default="val", choices=("train", "val", "test"))
    ap.add_argument("--limit", type=int, default=160, help="pairs (0: all)")
    ap.add_argument("--repeats", type=int, default=5, help="shuffles into batches of 32")
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args(argv)
    import torch

    from motionlang.api import body21, load_model
    from motionlang.errors import MotionlangError
    from motionlang.evaluation.t2m.guo import GuoRun, load_evaluator
    from motionlang.evaluation.t2m.yardstick import generated_rows, guo_metrics, positions_rows
    from motionlang.features.base import downsample
    from motionlang.models.t2m import text_to_motion
    torch.set_num_threads(a.threads)
    try:
        ev = load_evaluator(a.evaluator)
        run = GuoRun.prepare(ev, a.data, split=a.split, limit=a.limit)
        captions = [p["caption"] for p in run.pairs]
        frames = [len(p["motion"]) + 1 for p in run.pairs]
        text = ev.embed_texts(captions, [p.get("tokens") for p in run.pairs])
        real = ev.embed_motions([p["motion"] for p in run.pairs])
        # each motion on the 21-joint body at the models' 12.5 Hz, for its own embedding
        p21 = [body21(downsample(run.data.records[p["id"]].load_motion(), 12.5))
               for p in run.pairs]

        def top3(rows) -> tuple[float, float]:
            emb = ev.embed_motions(rows)
            m = guo_metrics(text, emb, real, repeats=a.repeats)
            return float(m["R-precision top-3"][0]), spread(emb)

        print(f"{len(run.pairs)} {a.split} pairs; real motions: top-3 "
              f"{top3([p['motion'] for p in run.pairs])[0]:.3f}, spread {spread(real):.2f}")
        for path in a.models:
            t2m = text_to_motion(load_model(path))
            if not t2m.autoencodes:
                raise MotionlangError(f"{path}: a {t2m.model.kind} model has no pose "
                                      "embedding to decode")
            with torch.no_grad():
                own = [positions_rows(t2m.reconstruct21(p), run.data.bones) for p in p21]
            said = generated_rows(t2m.model, captions, frames, bones=run.data.bones,
                                  desc=str(path))
            (s3, ss), (o3, os_) = top3(said), top3(own)
            print(f"{path}: from the sentence top-3 {s3:.3f} (spread {ss:.2f}); from the "
                  f"motion's own embedding top-3 {o3:.3f} (spread {os_:.2f})", flush=True)
    except MotionlangError as exc:
        print(f"twostream_paths.py: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
