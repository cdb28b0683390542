"""The report of ``motionlang evaluate``: an M2L model on one split of its data, beside the
nearest-neighbour baseline, and optionally a text-to-motion model's round trip.

:func:`evaluate_seq2seq` takes the loaded models, records and splits and returns the report
(a JSON-friendly dict); :func:`report_text` is its printed form (markdown). Beyond BLEU the
report checks what the data makes checkable: on labelled takes (Bandai) whether the action
and style are named, on a procedural corpus the parameters each description states against
the generator's ground truth (:mod:`.seq2seq` holds the scores themselves).
"""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from motionlang.datasets.synth import ground_truth
from motionlang.errors import MotionlangError
from motionlang.evaluation import seq2seq as ev
from motionlang.evaluation.context_tsne import l2m_contexts, m2l_contexts, plot_context_tsne
from motionlang.evaluation.retrieval import SentenceIndex
from motionlang.evaluation.sampling import stratified_sample
from motionlang.features.frames import motion_frames
from motionlang.utils.progress import progress


def evaluate_seq2seq(m2l, records: Mapping[str, Any], splits: Mapping[str, Sequence[str]], *,
                     split: str = "test", width: int = 5, limit: int = 0,
                     length_penalty: float = 0.0, rank: str = "logp", t2m=None,
                     t2m_name: str | None = None, tsne: str | Path | None = None) -> dict:
    """The M2L's scores on the motions of ``splits[split]`` found in ``records``.

    Args:
        m2l: a loaded M2L. records: ``{id: Record}`` (``datasets.sources.Record``) of the
            data it was trained on. splits: ``{name: [id, ...]}``, with "train" (the
            baseline's search space and the round trip's sentences) and ``split``.
        width: beam width, hypotheses per motion (ordered by ``rank``, "logp" or "mbr";
            ``length_penalty`` as in ``models.seq2seq.decode.search.describe_features``).
        limit: evaluate at most this many motions of the split (0: all), a random sample
            (seed 0, ``evaluation.sampling``); the baseline
            searches the whole training split.
        t2m: a text-to-motion model (``models.t2m.TextToMotion``, one that gives ranked
            hypotheses in the M2L's features) whose round trip is also scored, named
            ``t2m_name`` in the report. tsne: also draw the context vectors' t-SNE map to
            this PNG.

    Returns:
        ``{"split", "length_penalty", "rank", "m2l", "nearest_neighbour"}`` (scores of
        :mod:`.seq2seq`), with a round trip ``"l2m_round_trip"`` and ``"nn_round_trip"``;
        on labelled takes ``"m2l_labels"`` / ``"nn_labels"``; on a procedural corpus
        ``"m2l_parameters"``, ``"m2l_actions_by_rank"`` and each round trip's parameters;
        with ``tsne`` its path.

    Raises:
        MotionlangError: a split missing, or fewer than 4 motions for the t-SNE map.
    """

    for name in ("train", split):
        if name not in splits:
            raise MotionlangError(f"no {name!r} split (have {sorted(splits)})")

    def frames(ids, n=None):
        ids = [i for i in ids if i in records][:n]
        return {i: motion_frames(m2l.features, records[i].load_motion(), 1)[0]
                for i in progress(ids, desc="encode", unit="motion")}
    present = [i for i in splits[split] if i in records]
    chosen = [present[k] for k in stratified_sample(len(present), limit)]   # seed 0
    n_eval = len(chosen)
    if tsne and n_eval < 4:
        raise MotionlangError(f"--tsne needs at least 4 motions in the {split!r} split, "
                              f"it has {n_eval}")
    test, train = frames(chosen), frames(splits["train"])
    refs = {i: records[i].annotations for i in {**test, **train}}
    report: dict = {"split": split, "length_penalty": length_penalty, "rank": rank,
                    "m2l": ev.evaluate_m2l(m2l, test, refs, width, length_penalty, rank=rank),
                    "nearest_neighbour": ev.evaluate_nn_baseline(train, refs, test, refs)}
    if t2m is not None:
        test_refs = {i: refs[i] for i in test}
        report["l2m_round_trip"] = ev.round_trip_of(t2m, m2l, test_refs, report["m2l"]["bleu"])
        report["l2m_round_trip"].update(model=t2m_name, **dataclasses.asdict(t2m.options))
        index = SentenceIndex((i, s) for i in sorted(train) for s in refs[i])
        report["nn_round_trip"] = ev.evaluate_round_trip_nn(index, train, m2l, test_refs,
                                                            report["m2l"]["bleu"])
    _add_checks(report, records, test, train, refs, width)
    if tsne:
        _context_tsne(Path(tsne), m2l, None if t2m is None else t2m.model, test, records)
        report["tsne"] = str(tsne)
    return report


def report_text(report: dict) -> str:
    """The printed (and ``report.md``) form of :func:`evaluate_seq2seq`'s report: the score
    table, BLEU by rank, parameters and labels named where the data has them."""
    rows = {"M2L (top hypothesis)": report["m2l"],
            "nearest neighbour": report["nearest_neighbour"]}
    if "l2m_round_trip" in report:
        rows[f"L2M round trip ({_decoding(report['l2m_round_trip'])})"] = \
            report["l2m_round_trip"]
        rows["nearest training sentence, round trip"] = report["nn_round_trip"]
    width = report["m2l"]["width"]
    table = ev.markdown_table(rows)
    by_rank = " ".join(f"{b:.3f}" for b in report["m2l"]["bleu_by_rank"])
    table += (f"\nM2L BLEU of hypotheses 1..{width} (ordered by --rank {report['rank']}): "
              f"{by_rank}\n")
    if "m2l_actions_by_rank" in report:
        table += (f"M2L hypotheses 1..{width} naming exactly the true actions: " +
                  " ".join(f"{a:.1%}" for a in report["m2l_actions_by_rank"]) + "\n")
    for key, name in (("m2l_parameters", "M2L top description"),
                      ("l2m_parameters", "L2M round trip"),
                      ("nn_parameters", "Nearest training sentence, round trip")):
        if key in report:
            acc = report[key]
            table += (f"{name}, parameters right (procedural ground truth): " + ", ".join(
                f"{f} {acc[f]:.1%} of {acc[f + '_stated']}" for f in
                ("side", "count", "direction", "speed")) +
                f"; actions exactly right {acc['actions_match']:.1%}\n")
            if "named" in acc:
                table += f"{name}, true actions named: " + ev.named_line(acc["named"]) + "\n"
    for key, name in (("m2l_labels", "M2L top description"),
                      ("nn_labels", "Nearest neighbour")):
        if key in report:
            acc = report[key]
            table += (f"{name}, labelled takes ({acc['n']}): action named {acc['content']:.1%}, "
                      f"style named {acc['style']:.1%}, both {acc['both']:.1%}\n")
    return table


def _decoding(trip: dict) -> str:
    """How the round trip's motions were made, for its row: "mean", "sample", "sample, best
    of 5 by reranker"."""
    text = str(trip.get("method") or "mean")
    if trip.get("rerank"):
        text += f", best of {trip.get('width')} by reranker"
    return text


def _add_checks(report: dict, records: Mapping[str, Any], test: dict, train: dict,
                refs: dict, width: int) -> None:
    """Beyond BLEU, into ``report``: on labelled takes (Bandai) whether the action and
    style are named (M2L and nearest neighbour); on a procedural corpus the parameters
    each description states, checked against the generator's ground truth."""
    labelled = _labels(records, test)
    if labelled:
        top = {e["id"]: e["hypotheses"][0] for e in report["m2l"]["all"] if e["id"] in labelled}
        nn = ev.nearest_neighbour_descriptions(train, refs, {i: test[i] for i in labelled})
        report["m2l_labels"] = ev.label_accuracy(top, labelled)
        report["nn_labels"] = ev.label_accuracy(nn, labelled)
    ranked = {e["id"]: e["hypotheses"] for e in report["m2l"].pop("all")}
    truths = _ground_truths(records, test)
    if not truths:
        return
    report["m2l_parameters"] = ev.parameter_accuracy({i: h[0] for i, h in ranked.items()},
                                                     truths)
    # BLEU cannot tell a worse description from an equally valid paraphrase; the
    # parameters can: how often the k-th hypothesis names exactly the true actions
    # (evaluate_m2l pads a short beam with its last hypothesis, so all have W)
    report["m2l_actions_by_rank"] = [
        ev.parameter_accuracy({i: h[k] for i, h in ranked.items()}, truths)["actions_match"]
        for k in range(width)]
    for run in ("l2m", "nn"):
        if f"{run}_round_trip" in report:
            descriptions = report[f"{run}_round_trip"]["descriptions"]
            report[f"{run}_parameters"] = ev.round_trip_parameter_accuracy(descriptions, truths)
            report[f"{run}_parameters"]["named"] = ev.actions_named(descriptions, truths)


def _labels(records: Mapping[str, Any], ids) -> dict:
    """{id: {"content", "style"}} of the motions among ``ids`` that carry those labels
    (Bandai takes)."""
    out = {}
    for i in ids:
        lab = getattr(records[i], "labels", None)
        if isinstance(lab, dict) and "content" in lab and "style" in lab:
            out[i] = lab
    return out


def _ground_truths(records: Mapping[str, Any], ids) -> dict:
    """{id: ground-truth primitives} when every record carries them (procedural corpus)."""
    metas = {i: records[i].meta for i in ids}
    if not metas or not all(m.get("primitives") for m in metas.values()):
        return {}
    return {i: ground_truth(m) for i, m in metas.items()}


def _context_tsne(path: Path, m2l, l2m, test: dict, records: Mapping[str, Any]) -> None:
    """The paper's Fig. 9: t-SNE of both encoders' context vectors, coloured by motion type
    (the first action of a procedural sample, else the first word after "a person")."""

    def label(i):
        prims = records[i].meta.get("primitives")
        if prims:
            return prims[0]["action"]
        words = records[i].annotations[0].lower().split()
        return words[2] if len(words) > 2 and words[:2] == ["a", "person"] else words[0]
    ids = sorted(test)
    labels = [label(i) for i in ids]
    panels = {"M2L encoder (motions)": (m2l_contexts(m2l, [test[i] for i in ids]), labels)}
    if l2m is not None:
        panels["L2M encoder (sentences)"] = (
            l2m_contexts(l2m, [records[i].annotations[0] for i in ids]), labels)
    plot_context_tsne(panels, path)
