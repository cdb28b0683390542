"""What the masked model's tokens allow: the packaged judge on the Bandai takes passed through
the tokenizer and back, beside the model's own motions (docs/results/masked.md, fifth stage).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/masked_token_ceiling.py --model masked \
        [--data ../shared/data/bandai] [--split val] [--limit 0] [--evaluator E] \
        [--no-generated]

Rows: the real takes (the judge's own accuracy; FID between two halves), each take
tokenized and decoded with all codebooks and with the base codebook alone (placed where the
take starts), and the model's motions for one sentence per take (as ``evaluate-judge``
draws them, feet locked). If the reconstructions vary as much as the real takes under the
judge, the model's lower diversity comes from the generator, not from the tokens.

``--evaluator E`` (a text-motion evaluator, e.g. ``runs/evaluator_bandai``): instead, the
Guo-protocol table of ``evaluate-t2m --protocol guo`` (the same pairs, options and rows:
ground truth, nearest neighbour, standing still) with the test motions through the tokens
and back as rows, so that R-precision and FID show what a generator that drew the true
tokens would score. A few minutes on one core. Non-commercial: Bandai data (CC BY-NC 4.0).
"""
from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def guo_ceiling(args: argparse.Namespace) -> None:
    """The Guo-protocol rows of the test motions through the tokens and back."""
    import numpy as np
    import torch
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.evaluation.t2m.guo import GuoRun, load_evaluator
    from motionlang.evaluation.t2m.yardstick import guo_table, markdown_table, positions_rows
    from motionlang.features.h3d_vectors import H3D_BODIES, vectors_to_joints
    from motionlang.features.positions import positions_to_rows

    model = ml.load_model(args.model, kind="masked")
    evaluator = load_evaluator(args.evaluator)
    run = GuoRun.prepare(evaluator, f"bandai:{args.data}", evaluator_name=args.evaluator,
                         split=args.split, seed=args.seed, limit=args.limit)
    spec, feats = H3D_BODIES[run.body], model.features
    rows: dict[str, list] = {f"tokens and back, {model.config.quantizers} codebooks": [],
                             "tokens and back, base codebook": []}
    for pair in run.pairs:
        p21 = vectors_to_joints(np.asarray(pair["motion"]), spec) / 1000.0   # mm -> m
        enc = feats.encode_positions(p21)
        for out, n_q in zip(rows.values(), (None, 1), strict=True):
            back = feats.decode(model.reconstruct(enc, n_q), positions_to_rows(p21[:1])[1],
                                pin_root=True)
            out.append(positions_rows(back, run.data.bones))
    table = guo_table(evaluator, run.pairs, run.data.items.get("train") or [], rows,
                      reference_items=run.reference, repeats=run.options.repeats,
                      seed=run.seed, batch_size=run.options.rp_batch)
    print(markdown_table(table, f"{len(run.pairs)} {args.split} pairs, evaluator "
                                f"{args.evaluator}, the model {args.model}'s tokenizer"))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--model", default="masked")
    p.add_argument("--judge", default="judge")
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    p.add_argument("--split", default="val")
    p.add_argument("--limit", type=int, default=0, help="takes (0: all)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--evaluator", default=None)
    p.add_argument("--no-generated", action="store_true",
                   help="leave out the model's own motions (a run with a tokenizer only)")
    args = p.parse_args()
    if args.evaluator:
        return guo_ceiling(args)

    import torch
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.evaluation.judge import asked_labels, judge_table
    from motionlang.evaluation.sampling import stratified_sample
    from motionlang.features.foot_lock import lock_feet
    from motionlang.features.positions import positions_to_rows
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.t2m import FPS

    model = ml.load_model(args.model, kind="masked")
    judge = ml.load_model(args.judge, kind="judge")
    t2m = ml.text_to_motion(model)
    if abs(model.fps - FPS) > 1e-6:
        raise SystemExit(f"the model runs at {model.fps} Hz, the judge's takes at {FPS}")
    real = bandai_items(args.data, args.split, fps=FPS)
    sentences = bandai_sentences(args.data, args.split, seed=args.seed)
    keep = stratified_sample(len(real), args.limit, [s.content for s in sentences],
                             seed=args.seed)
    real, sentences = [real[i] for i in keep], [sentences[i] for i in keep]
    feats = model.features

    def through_tokens(p21, n_q):
        rows = feats.encode_positions(p21)
        return feats.decode(model.reconstruct(rows, n_q), positions_to_rows(p21[:1])[1],
                            pin_root=True)

    generated = {
        f"tokens and back, {model.config.quantizers} codebooks":
            [through_tokens(it.positions, None) for it in real],
        "tokens and back, base codebook": [through_tokens(it.positions, 1) for it in real],
    }
    if not args.no_generated:
        generated[f"{args.model} (generated)"] = [
            lock_feet(t2m.positions21(s.text, max(2, len(it.positions)), seed=args.seed), FPS)
            for s, it in zip(sentences, real, strict=True)]
    rows = judge_table(judge, [it.positions for it in real],
                       [(it.content, it.style) for it in real], FPS, generated,
                       asked_labels(sentences), FPS, rng=args.seed)
    print(f"{len(real)} Bandai {args.split} takes; the judge {args.judge}\n")
    print("| | content % | style % | FID | diversity | skating m/s |")
    print("|---|---|---|---|---|---|")
    for name, r in rows.items():
        print(f"| {name} | {100 * r['content_acc']:.1f} | {100 * r['style_acc']:.1f} | "
              f"{r.get('fid', float('nan')):.1f} | {r['diversity']:.1f} | {r['skating']:.3f} |")


if __name__ == "__main__":
    main()
