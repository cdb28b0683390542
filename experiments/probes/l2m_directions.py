"""Which way do an L2M model's generated motions go? For each sentence, draw ancestral
samples and print the distance walked along the body's own axes (summed heading-frame steps,
metres), the total turn (degrees), and how many samples go the stated way.

    .venv/bin/python experiments/probes/l2m_directions.py [--model M] [--samples 9] [--method mean]
        [--rerank M2L --candidates 10]

With ``--rerank``, each of the ``--samples`` motions is the best of ``--candidates`` draws by
that M2L's log P(sentence | motion) (``models.seq2seq.decode.rerank``).

The sign of "sideways" is calibrated on a real procedural sample whose sentence says
"leftwards" (``--data`` corpus), so no axis convention is assumed. Default model: packaged.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

SENTENCES = {"a person walks forward": "forward", "a person walks backwards": "backward",
             "a person sidesteps to the left": "left", "a person sidesteps to the right": "right"}


def body_frame_distances(fs, frames: np.ndarray) -> tuple[float, float, float]:
    """Feature-space frames (T, D) -> (sideways m, forward m, turn deg), summed over time."""
    from motionlang.features.frames import frames_to_features
    x = frames_to_features(fs, frames)
    raw = fs.normalizer.inverse(x[:, :fs.n_normalised])
    v = raw[:, fs.names.index("root_vx")], raw[:, fs.names.index("root_vz")]
    return float(v[0].sum()), float(v[1].sum()), float(np.degrees(
        raw[:, fs.names.index("root_dyaw")].sum()))


def left_sign(fs, corpus: Path) -> float:
    """+1 if a positive sideways step is to the left, from a sample described 'leftwards'."""
    import json

    import motionlang as ml
    from motionlang.features.frames import motion_frames
    for ann in sorted(corpus.glob("*_annotations.json")):
        texts = json.loads(ann.read_text())
        if any("sidesteps" in t and "leftwards" in t for t in texts):
            stem = ann.name[:-len("_annotations.json")]
            motion = ml.read_motion(ann.with_name(f"{stem}_mmm.xml"))
            side, _, _ = body_frame_distances(fs, motion_frames(fs, motion, 1)[0])
            return 1.0 if side > 0 else -1.0
    raise SystemExit(f"{corpus}: no sample described as sidestepping leftwards")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=None)
    ap.add_argument("--data", required=True, help="a procedural corpus (for the sign of left)")
    ap.add_argument("--samples", type=int, default=9)
    ap.add_argument("--method", choices=("sample", "mean"), default=None,
                    help="ancestral samples, or the one deterministic motion (default: mean "
                         "for a model trained on its expected frames, else sample)")
    ap.add_argument("--rerank", metavar="M2L", help="keep the best of --candidates draws by "
                    "this M2L's log P(sentence | motion)")
    ap.add_argument("--candidates", type=int, default=10)
    args = ap.parse_args()
    import motionlang as ml
    from motionlang.models.seq2seq.decode.search import generate_features
    model = ml.load_model(args.model or "l2m", kind="l2m")
    fs = model.features
    method = args.method or ("mean" if model.config.rollout_input == "mean" else "sample")
    if args.rerank and (method == "mean" or args.candidates < 2):
        raise SystemExit("--rerank needs --method sample and --candidates 2 or more")
    left = left_sign(fs, Path(args.data))
    reranker = None
    if args.rerank:
        from motionlang.models.seq2seq.decode.rerank import check_same_features, rerank
        reranker = ml.load_model(args.rerank, kind="m2l")
        check_same_features(model, reranker, f"--rerank {args.rerank}")
    for sentence, way in SENTENCES.items():
        if reranker is None:
            hyps = generate_features(model, sentence, width=args.samples, method=method,
                                     min_frames=5)
        else:   # each motion the best of its own draws (seeds 0, 1, ...)
            hyps = [rerank(generate_features(model, sentence, width=args.candidates,
                                             method=method, min_frames=5, seed=k),
                           reranker, sentence)[0][:2] for k in range(args.samples)]
        moves = [body_frame_distances(fs, f) for f, _ in hyps]
        right_way = sum({"forward": fwd > 0.2, "backward": fwd < -0.2,
                         "left": left * side > 0.1, "right": left * side < -0.1}[way]
                        for side, fwd, _ in moves)
        print(f"{sentence!r}: {right_way}/{len(moves)} samples go {way}")
        for side, fwd, turn in moves:
            print(f"    left {left * side:+.2f} m  forward {fwd:+.2f} m  turn {turn:+5.0f} deg")


if __name__ == "__main__":
    main()
