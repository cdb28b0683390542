"""Does an L2M model use a word? On the validation and test pairs whose sentence holds
``--word`` (default "backwards"), compare the model under the true sentence and under the
same sentence with the word replaced by ``--instead`` (default "forward"):

* the frame NLL (nats per frame, exact mixture density) of the true motion, fed the true
  previous frames (teacher forcing) and, as the model was trained, 90 % its own;
* the mean of one feature (``--feature``, default ``root_vz``: the root's forward speed in
  the heading frame, printed in m/s) over the motion: the truth, the model's expected
  frames (sum_k pi_k mu_k) under teacher forcing, and its own ancestral samples (of the
  first 12 sentences, at most as long as the true motions).

A model fed a plan (``--plan-parts``) follows the plan it predicts from the sentence here,
as when it generates, not the true motion's.

A model that reads the word assigns the true sentence the lower NLL and moves its expected
feature the truth's way; one that generates it also samples that way.

    .venv/bin/python experiments/probes/l2m_word_use.py --data corpus [--model M] [--limit 48]
"""
from __future__ import annotations

import argparse
import re

import numpy as np
import torch


def select(data, word: str, limit: int) -> list[dict]:
    """Validation then test pairs whose sentence holds ``word`` (whole word), each with its
    ``sentence`` decoded (``data.vocab``)."""
    pattern = re.compile(rf"\b{re.escape(word)}\b")
    items = [{**it, "sentence": data.vocab.decode(it["tokens"])}
             for split in ("val", "test") for it in data.items.get(split, [])]
    return [it for it in items if pattern.search(it["sentence"])][:limit]


def with_sentences(items: list[dict], vocab, sentences: list[str]) -> list[dict]:
    """The items with their tokens in the model's vocabulary."""
    from motionlang.models.seq2seq.decode.search import encode_sentence
    return [{**it, "tokens": encode_sentence(vocab, s)} for it, s in zip(items, sentences)]


def evaluate(model, items: list[dict], column: int, p_own: float) -> tuple[float, float]:
    """(exact NLL per valid frame, mean expected feature value in normalised units)."""
    from motionlang.models.seq2seq import mdn
    from motionlang.training.collate import collate_pairs
    b = collate_pairs(items)
    B, T, F = b["motion"].shape
    with torch.no_grad():
        params = model.rollout_forward(b["tokens"], b["token_lengths"], b["motion"], p_own,
                                       seed=0, motion_lengths=b["motion_lengths"],
                                       # a planning model: the plan it reads from the sentence
                                       sentence_plan=True).flatten()
    valid = (torch.arange(T)[None] < b["motion_lengths"][:, None]).reshape(-1)
    nll = -mdn.mixture_log_prob(params, b["motion"].reshape(B * T, F))[valid].mean()
    expected = mdn.mixture_mean(params)[valid][:, column].mean()
    return float(nll), float(expected)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", required=True, help="the corpus the model was trained on")
    ap.add_argument("--model", default=None, help="L2M model file (default: packaged)")
    ap.add_argument("--word", default="backwards")
    ap.add_argument("--instead", default="forward")
    ap.add_argument("--feature", default="root_vz")
    ap.add_argument("--limit", type=int, default=48, help="at most N pairs")
    ap.add_argument("--samples", type=int, default=3, help="ancestral samples per sentence")
    args = ap.parse_args(argv)
    torch.set_num_threads(1)

    import motionlang as ml
    from motionlang.datasets.seq2seq_pairs import build_pairs
    from motionlang.features.frames import model_dim
    from motionlang.models.registry import resolve
    from motionlang.models.seq2seq.decode.search import _normalize, generate_features
    path = resolve(args.model or "l2m")
    model = ml.load_model(path, kind="l2m")
    fs, vocab = model.features, model.vocab
    if args.feature not in fs.names[:model_dim(fs)]:
        raise SystemExit(f"{path}: no feature {args.feature!r} among the model's features")
    column = fs.names.index(args.feature)
    data = build_pairs(args.data, features=fs.kind, offsets=1, seed=0)
    items = select(data, args.word, args.limit)
    if not items:
        raise SystemExit(f"{args.data}: no validation or test sentence holds {args.word!r}")
    speed = args.feature.startswith("root_v")   # metres per frame: shown per second
    scale, unit = (float(fs.fps), "m/s") if speed else (1.0, "(feature units)")

    def shown(value: float) -> str:
        """A normalised value of the feature -> its own unit."""
        row = np.zeros((1, fs.n_normalised), dtype=np.float32)
        row[0, column] = value
        return f"{float(fs.normalizer.inverse(row)[0, column]) * scale:+.3f} {unit}"

    truth = float(np.mean(np.concatenate([it["motion"][:, column] for it in items])))
    print(f"{len(items)} validation/test pairs with {args.word!r}; "
          f"{args.feature} of the true motions: {shown(truth)}")
    pattern = re.compile(rf"\b{re.escape(args.word)}\b")
    for name, sentences in (("true sentence", [it["sentence"] for it in items]),
                            (f"{args.word!r} -> {args.instead!r}",
                             [pattern.sub(args.instead, it["sentence"]) for it in items])):
        sents = with_sentences(items, vocab, sentences)
        tf = evaluate(model, sents, column, 0.0)
        own = evaluate(model, sents, column, 0.9)
        drawn = []
        for it, sentence in zip(sents[:12], sentences):
            # as long as the true motion at most (a model told its length: exactly)
            for h, _ in generate_features(model, sentence, width=args.samples,
                                          method="sample", n_frames=len(it["motion"])):
                # frames come back in the model's units: normalised unless it has its own
                x = h if model.normalizer is None else _normalize(model.normalizer, h)
                drawn.append(x[:, column])
        print(f"  {name:28s} NLL/frame teacher-forced {tf[0]:7.3f}, 90 % own frames "
              f"{own[0]:7.3f}; expected {args.feature} {shown(tf[1])} (teacher-forced); "
              f"samples {shown(float(np.mean(np.concatenate(drawn))))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
