"""Text -> motion retrieval on the Bandai Namco test takes: a retrieval model
(``train retrieval``) against a text-motion evaluator's encoders (``train evaluator``) on
the same pairs, and search queries in words the training captions do not use.

    OMP_NUM_THREADS=2 .venv/bin/python experiments/retrieval_bandai.py \
        --retrieval RUN/model.pt --evaluator EVAL_RUN [--data bandai:../shared/data/bandai] \
        [--corpus CORPUS] [--queries FILE] [--reading written|verbs|canonical] [--json out.json]

Pairs: one caption per test take (dataset 2, take numbers 0 mod 5), drawn as the yardstick
draws them (``evaluation.t2m.yardstick.test_pairs``, seed 0). Each caption ranks every test
take, each take every caption (``metrics.t2m.retrieval_scores``), with three ideas of a hit:
the pair's own take only; any take of the same label (action and style: Bandai's captions
are written from the labels, so these captions cannot tell such takes apart); any take of
the same action. The evaluator is scored by cosine (as the yardstick's TMR columns) and by
its own Euclidean distance. Queries: one sentence per action of the test takes, its action
named in other words; precision@5 is the share of the five best-ranked takes that show the
action. ``--corpus``: the procedural corpus trained on too, so that the query words found in
any training caption are listed. A few minutes; CC BY-NC data.
"""
from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import numpy as np

import motionlang as ml
from motionlang.datasets.canonical import READINGS
from motionlang.datasets.evaluator_items import build_evaluator_data
from motionlang.evaluation.metrics.t2m import euclidean_distance_matrix, retrieval_scores
from motionlang.evaluation.t2m.guo import load_evaluator
from motionlang.evaluation.t2m.yardstick import evaluator_body, test_pairs

#: one query per action of the test takes, the action in words the captions do not use
QUERIES = {
    "walk": "somebody strolls along at an easy pace",
    "walk-turn-left": "somebody strolls and veers round leftward",
    "walk-turn-right": "somebody strolls and veers round rightward",
    "run": "somebody hurries along at a trot",
    "wave-both-hands": "somebody greets using both palms",
    "wave-left-hand": "somebody greets using the left palm",
    "wave-right-hand": "somebody greets using the right palm",
    "raise-up-both-hands": "somebody reaches skyward using both palms",
    "raise-up-left-hand": "somebody reaches skyward using the left palm",
    "raise-up-right-hand": "somebody reaches skyward using the right palm",
}
WORD = re.compile(r"[a-z]+")


def hit_sets(labels: list[tuple[str, str]]) -> dict[str, np.ndarray]:
    """(content, style) of each pair -> {name: (N, N) bool hits}."""
    content = np.array([c for c, _ in labels])
    label = np.array([f"{c}/{s}" for c, s in labels])
    return {"pair": np.eye(len(labels), dtype=bool),
            "label": label[:, None] == label[None],
            "action": content[:, None] == content[None]}


def precision_at(sims: np.ndarray, content: list[str], actions: list[str],
                 k: int = 5) -> list[float]:
    """(queries, takes) similarities and each query's action -> precision@k per query."""
    out = []
    for action, row in zip(actions, sims):
        top = np.argsort(-row, kind="stable")[:k]
        out.append(float(np.mean([content[j] == action for j in top])))
    return out


def read_queries(path: str | None) -> list[tuple[str, str]]:
    """``(action, query)`` pairs: :data:`QUERIES`, or a file of ``action<TAB>query`` lines
    (several queries an action allowed; ``#`` starts a comment)."""
    if path is None:
        return list(QUERIES.items())
    out = []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        if line.strip() and not line.startswith("#"):
            action, query = line.split("\t", 1)
            out.append((action.strip(), query.strip()))
    return out


def training_words(data: str, corpus: str | None) -> set[str]:
    """Every word of every training caption of ``data`` (and ``corpus``)."""
    from motionlang.datasets.seq2seq_pairs import load_records
    words: set[str] = set()
    for source in [data] + ([corpus] if corpus else []):
        for r in load_records(source, 30.0):
            if getattr(r, "split", "train") in ("train", None):
                for a in r.annotations:
                    words |= set(WORD.findall(a.lower()))
    return words


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--retrieval", required=True, help="retrieval model (file or run folder)")
    ap.add_argument("--evaluator", help="text-motion evaluator (file or run); without one, "
                                        "only the retrieval model's columns")
    ap.add_argument("--data", default="bandai:../shared/data/bandai", help="Bandai source")
    ap.add_argument("--corpus", help="the procedural corpus the model was also trained on")
    ap.add_argument("--json", help="also write the figures here")
    ap.add_argument("--queries", help="a file of action<TAB>query lines instead of the ten "
                                      "fixed queries (each action's P@5: its queries' mean)")
    ap.add_argument("--reading", choices=READINGS,
                    help="read captions and queries so (datasets.canonical.read_as) instead "
                         "of as the model does (its config's use_reading)")
    args = ap.parse_args(argv)

    model = ml.load_model(args.retrieval, kind="retrieval")
    if args.reading:
        model.text.reading = args.reading
    print(f"sentences read: {model.text.reading}")
    evaluator = load_evaluator(args.evaluator) if args.evaluator else None
    from motionlang.datasets.seq2seq_pairs import load_records
    tests = [r for r in load_records(args.data, 30.0) if r.split == "test"]
    built = build_evaluator_data(tests, evaluator_body(evaluator) if evaluator else "kit",
                                 seed=0, bones=evaluator.config.bones if evaluator else None)
    pairs = test_pairs(built.items["test"], 0)
    records = [built.records[p["id"]] for p in pairs]
    labels = [(r.labels["content"], r.labels["style"]) for r in records]
    captions = [p["caption"] for p in pairs]
    print(f"{len(pairs)} test takes, {len({c for c, _ in labels})} actions, "
          f"{len(set(labels))} labels, {len(set(captions))} distinct captions")

    emb = {"retrieval": (model.embed_texts(captions),
                         model.embed_motions([model.motion_rows(r.load_motion())
                                              for r in records]))}
    sims = {"retrieval": emb["retrieval"][0] @ emb["retrieval"][1].T}
    if evaluator is not None:
        ev_t = evaluator.embed_texts(captions, [p.get("tokens") for p in pairs])
        ev_m = evaluator.embed_motions([p["motion"] for p in pairs])
        unit = [x / np.linalg.norm(x, axis=1, keepdims=True) for x in (ev_t, ev_m)]
        sims["evaluator (cosine)"] = unit[0] @ unit[1].T
        sims["evaluator (distance)"] = -euclidean_distance_matrix(ev_t, ev_m)
    hits = hit_sets(labels)
    report: dict = {"pairs": len(pairs), "retrieval": {}, "queries": {}}
    print("\n| encoders | hit | t2m R@1 | R@2 | R@3 | R@5 | R@10 | MedR | m2t R@1 | R@5 | MedR |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, s in sims.items():
        for hit, h in hits.items():
            r = retrieval_scores(s, h)
            report["retrieval"][f"{name}/{hit}"] = r
            print(f"| {name} | {hit} | " + " | ".join(
                f"{r[k]:.1f}" if "MedR" not in k else f"{r[k]:g}" for k in (
                    "t2m/R01", "t2m/R02", "t2m/R03", "t2m/R05", "t2m/R10", "t2m/MedR",
                    "m2t/R01", "m2t/R05", "m2t/MedR")) + " |")

    content = [c for c, _ in labels]
    asked = read_queries(args.queries)
    actions = [a for a, _ in asked]
    queries = [q for _, q in asked]
    q_sims = {"retrieval": model.embed_texts(queries) @ emb["retrieval"][1].T}
    if evaluator is not None:
        q_sims["evaluator (distance)"] = -euclidean_distance_matrix(
            evaluator.embed_texts(queries), ev_m)
    known = training_words(args.data, args.corpus)
    print("\n| action | query | words in training captions | retrieval P@5 | evaluator P@5 |")
    print("|---|---|---|---|---|")
    precision = {name: precision_at(s, content, actions) for name, s in q_sims.items()}
    for i, (action, query) in enumerate(asked):
        used = sorted(set(WORD.findall(query)) & known)
        report["queries"].setdefault(action, []).append(
            {"query": query, "known_words": used, **{n: p[i] for n, p in precision.items()}})
        ev = precision["evaluator (distance)"][i] if evaluator is not None else float("nan")
        print(f"| {action} | {query} | {', '.join(used)} | "
              f"{precision['retrieval'][i]:.1f} | {ev:.1f} |")
    per_action = {a: float(np.mean([p for b, p in zip(actions, precision["retrieval"])
                                    if b == a])) for a in dict.fromkeys(actions)}
    report["per_action"] = per_action
    print(f"mean P@5 over the {len(queries)} queries: {np.mean(precision['retrieval']):.3f}")
    for bar in (0.9, 0.8):
        print(f"actions at P@5 >= {bar}: {sum(p >= bar for p in per_action.values())} "
              f"of {len(per_action)}")
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
