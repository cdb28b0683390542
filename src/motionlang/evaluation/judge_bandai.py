"""Text-to-motion models judged on the Bandai Namco takes (``motionlang evaluate-judge``).

One sentence per take of a split (``bandai_text``), each model's motion for it as long as
the take, judged by a trained judge beside the real takes (:func:`.judge.judge_table`):
recognition of the asked content and style, FID and diversity on the judge's features,
foot skating, floor penetration and root jumps, and the open-world check (the share of
motions that show their sentence's actions by the grounded analysis,
``evaluation.open_world``). The data and the judge are CC BY-NC 4.0
(``datasets.sources``): every figure made here is for non-commercial use only.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from motionlang.datasets.sources import DataSource, licence_text, parse_source
from motionlang.errors import MotionlangError
from motionlang.evaluation.judge import asked_labels, judge_table, markdown_judge_table
from motionlang.evaluation.open_world import check_share
from motionlang.evaluation.sampling import stratified_sample
from motionlang.features.foot_lock import lock_feet
from motionlang.models.registry import load_model
from motionlang.models.t2m import FPS
from motionlang.utils.progress import progress

#: the values of ``foot_lock``: rows with feet held (on), as decoded (off), or both
FOOT_LOCK = ("on", "off", "both")


@dataclass
class JudgeEvaluation:
    """What :func:`evaluate_on_bandai` found.

    Attributes:
        rows: ``{"ground truth": measures, model row: measures}`` (``judge_table``).
        title: the line above the table (data, judge, how the models were asked, licence).
        report: everything as plain values, for ``judge_report.json``: ``data``, ``split``,
            ``judge``, ``takes``, ``licence``, ``rows``, ``sentences``.
    """

    rows: dict[str, dict[str, float]]
    title: str
    report: dict[str, Any]

    def markdown(self) -> str:
        """The table in Markdown under its title (``markdown_judge_table``)."""
        return markdown_judge_table(self.rows, self.title)


def evaluate_on_bandai(judge: Any, models: Mapping[str, Any], data: str | Path | DataSource,
                       split: str = "test", *, limit: int = 0, seed: int = 0,
                       foot_lock: str = "on", judge_name: str = "") -> JudgeEvaluation:
    """Judge ``models`` (row label -> text-to-motion model, ``models.t2m``; none: the
    judge and the real takes only) on the takes of ``split`` of the Bandai folder ``data``
    (``bandai:DIR``, or a bare folder read as one).

    judge: a ``MotionJudge``, or a judge file, run folder or packaged name.
    limit: at most this many takes (0: all), a sample stratified by the sentences'
        asked content (``evaluation.sampling``) drawn with ``seed``. seed: the sentences, the sampling models'
        draws and the FID halves. foot_lock: :data:`FOOT_LOCK`; ``both`` gives each model
        a row ``NAME`` (locked) and ``NAME (raw)`` from one decoding.
    judge_name: how the title and report name the judge (default: ``judge``'s text).

    Raises:
        MotionlangError: not a Bandai source, no takes in the split, a bad ``foot_lock``,
            a judge file that is not a judge.
    """
    from motionlang.models.judge.fit import bandai_items, bandai_sentences

    if foot_lock not in FOOT_LOCK:
        raise MotionlangError(f"foot_lock must be one of {', '.join(FOOT_LOCK)}, got "
                              f"{foot_lock!r}")
    source = parse_source(data, kind="bandai")
    if isinstance(judge, (str, Path)):
        judge_name = judge_name or str(judge)
        judge = load_model(judge, kind="judge")
    real = bandai_items(source.root, split, fps=FPS)
    if not real:
        raise MotionlangError(f"{source.root}: no Bandai takes in the {split} split")
    sentences = bandai_sentences(source.root, split, seed=seed)
    # a sample stratified by the asked action, never the first takes (sorted by action)
    keep = stratified_sample(len(real), limit, [s.content for s in sentences], seed=seed)
    real, sentences = [real[i] for i in keep], [sentences[i] for i in keep]
    generated = {}
    for name, t2m in models.items():
        kw = {} if t2m.deterministic else {"seed": seed}   # its options: how it decodes
        raw = [t2m.positions21(s.text, max(2, len(it.positions)), **kw)
               for s, it in progress(list(zip(sentences, real)), desc=name, unit="motions")]
        # the lock is a post-process of the decoded frames: both rows from one decoding
        if foot_lock in ("off", "both"):
            generated[name + (" (raw)" if foot_lock == "both" else "")] = raw
        if foot_lock in ("on", "both"):
            generated[name] = [lock_feet(p, FPS) for p in raw]
    rows = judge_table(judge, [it.positions for it in real],
                       [(it.content, it.style) for it in real], FPS, generated,
                       asked_labels(sentences), FPS, rng=seed)
    texts = [s.text for s in sentences]
    rows["ground truth"]["check"] = check_share(texts, [it.positions for it in real], FPS)
    for name, motions in generated.items():
        rows[name]["check"] = check_share(texts, motions, FPS)
    terms = (licence_text(source, "judge") or "").splitlines()[0]
    name = judge_name or "judge"
    c = judge.config
    title = (f"{len(real)} Bandai {split} takes of {source.root}, judge {name} "
             f"({len(c.contents)} contents, {len(c.styles)} styles, "
             f"motions read {'on one body' if c.bones else 'on their own bones'}); "
             "models asked one sentence per take. Ground truth: the judge's own accuracy, "
             f"FID between two halves of the takes. {terms}")
    report = {"data": source.root, "split": split, "judge": name, "takes": len(real),
              "licence": terms, "rows": rows, "sentences": [s.text for s in sentences]}
    return JudgeEvaluation(rows, title, report)
