"""What the motion judge is trained and scored on: labelled 21-joint motions, a fresh judge
for them, their batches, accuracy.

:func:`bandai_items` reads the Bandai Namco takes of a split as :class:`JudgeItem`
(positions at the positions features' rate, cached by file identity); any other labelled
motions can join them, ``style=None`` where there is none: :func:`primitive_items` cuts a
procedural corpus' primitives that show a Bandai action (walks, runs, waves, raised arms,
bows, kicks, punches); :func:`mirror_item` swaps left and right. :func:`new_judge` makes a
judge for some items (labels, normaliser) and :func:`examples` / :func:`collate` turn items
into the batches of its ``loss`` (random crops of ``config.window`` frames); the training
itself is the shared trainer's (``recipes.judge``). :func:`accuracy` scores whole
motions.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from motionlang.datasets.bandai import load_bandai, load_bandai_text
from motionlang.datasets.bandai_text import MIRROR_CONTENT  # a lower layer
from motionlang.datasets.cache import cached, file_identity
from motionlang.datasets.kitml import load_kitml
from motionlang.datasets.synth import ground_truth
from motionlang.errors import MotionlangError
from motionlang.features.body21 import median_bones21
from motionlang.features.joint_map import KIT21_MIRROR
from motionlang.features.normalizer import Normalizer
from motionlang.features.positions import DEFAULT_FPS, PositionFeatures, PositionsConfig
from motionlang.models.judge.config import JudgeConfig
from motionlang.models.judge.model import MotionJudge, judge_rows

CACHE_VERSION = "judge-items-1"


@dataclass
class JudgeItem:
    """One labelled motion: ``positions`` (T, 21, 3) metres, Y up, at ``fps`` Hz; ``style``
    None where unknown (its head is then not trained on it)."""

    id: str
    positions: np.ndarray
    fps: float
    content: str
    style: str | None = None


def mirror_item(item: JudgeItem) -> JudgeItem:
    """Left and right swapped: positions reflected (x -> -x) with partner joints exchanged,
    the content label mirrored (``bandai_text.MIRROR_CONTENT``); id prefixed with ``M``."""
    return replace(item, id=f"M{item.id}",
                   positions=item.positions[:, list(KIT21_MIRROR)] * np.array([-1.0, 1, 1]),
                   content=MIRROR_CONTENT.get(item.content, item.content))


def bandai_items(source: str | Path, split: str | None = None, fps: float = DEFAULT_FPS
                 ) -> list[JudgeItem]:
    """The Bandai Namco takes of ``split`` (``datasets.bandai.load_bandai``) as items: each
    take's 21-joint body (``PositionFeatures.body``: on the floor) at ``fps`` Hz. Cached
    (``datasets.cache``) by the takes' file identities."""
    records = load_bandai(source, split)
    body = PositionFeatures(PositionsConfig(fps=fps)).body

    def compute():
        return {str(i): body(r.load_motion()).astype(np.float32) for i, r in enumerate(records)}
    key = {"v": CACHE_VERSION, "fps": fps, "files": [file_identity(r.path) for r in records]}
    arrays = cached(key, compute, name="judge-bandai")
    return [JudgeItem(r.id, arrays[str(i)].astype(float), fps, r.content, r.style)
            for i, r in enumerate(records)]


def primitive_content(action: str, side: str | None = None, direction: str | None = None
                      ) -> str | None:
    """The Bandai content a procedural primitive (``datasets.synth.spec``) shows, or None
    where Bandai has no such action (turns, squats, jumps, sidesteps ...)."""
    if action in ("walk", "run"):
        gaits: dict[tuple[str, str | None], str] = {
            ("walk", "forward"): "walk", ("walk", "backward"): "walk-back",
            ("run", "forward"): "run"}
        return gaits.get((action, direction))
    if action in ("wave", "raise_arms"):
        stem = "wave" if action == "wave" else "raise-up"
        return f"{stem}-both-hands" if side == "both" else f"{stem}-{side}-hand"
    return action if action in ("bow", "kick", "punch") else None


def primitive_items(corpus: str | Path, fps: float = DEFAULT_FPS, min_seconds: float = 0.5
                    ) -> list[JudgeItem]:
    """The primitives of a procedural corpus (``motionlang data synth``) that show a Bandai
    content, as items without a style: each body primitive with nothing layered on it, and
    each upper-body one layered on standing still; cut at their frame ranges, at least
    ``min_seconds`` long."""
    body = PositionFeatures(PositionsConfig(fps=fps)).body
    out = []
    for rec in load_kitml(corpus, max_seconds=None):
        prims, motion = ground_truth(rec.meta), None
        for k, p in enumerate(prims):
            under = next((q for q in reversed(prims[:k]) if q.layer == "body"), None)
            layered = k + 1 < len(prims) and prims[k + 1].layer == "upper"
            if p.layer == "upper":
                ok = under is not None and under.action == "stand"
            else:
                ok = not layered
            content = primitive_content(p.action, p.side, p.direction) if ok else None
            if content is None or p.end - p.start < min_seconds * rec.fps:
                continue
            if motion is None:
                motion = rec.load_motion()
            out.append(JudgeItem(f"{rec.id}@{k}", body(motion[p.start:p.end]), fps, content))
    return out


def new_judge(items: Sequence[JudgeItem], window: int | None = None, **config: Any
              ) -> tuple[MotionJudge, list[dict]]:
    """A fresh judge for ``items`` and the items as its examples (:func:`examples`).

    The judge's labels are every content and every known style of ``items`` (sorted), its
    normaliser is fitted on their rows; ``config``: the other :class:`JudgeConfig` fields
    (sizes, ``bones``). ``window``: the examples' crop (default ``config.window``).
    """
    if not items:
        raise MotionlangError("no training items for the judge")
    cfg = JudgeConfig(contents=sorted({it.content for it in items}),
                      styles=sorted({it.style for it in items if it.style is not None}),
                      **config)
    raw = [judge_rows(it.positions, it.fps, cfg) for it in items]
    judge = MotionJudge(cfg, Normalizer().fit(raw))
    return judge, _examples(judge, items, raw, cfg.window if window is None else window)


def examples(judge: MotionJudge, items: Sequence[JudgeItem], window: int | None = None
             ) -> list[dict]:
    """``items`` as what :func:`collate` batches for ``judge``: ``rows`` (T, F) float32
    normalised (``MotionJudge.rows``), ``content`` / ``style`` label ids (-1: unknown, or
    not one of the judge's labels; not trained or scored on), ``window``: frames of the
    random crop a batch takes of the rows (None: the whole motion, as judged)."""
    return _examples(judge, items, [judge_rows(it.positions, it.fps, judge.config)
                                    for it in items], window)


def _examples(judge: MotionJudge, items: Sequence[JudgeItem], raw: Sequence[np.ndarray],
              window: int | None) -> list[dict]:
    norm = judge.normalizer
    if norm is None:
        raise MotionlangError("the judge has no normaliser: make it with new_judge")
    content = {c: i for i, c in enumerate(judge.config.contents)}
    style: dict[str | None, int] = {s: i for i, s in enumerate(judge.config.styles)}
    return [{"rows": norm.transform(r).astype(np.float32),
             "content": content.get(it.content, -1), "style": style.get(it.style, -1),
             "window": window} for it, r in zip(items, raw)]


def collate(batch: Sequence[dict]) -> dict[str, torch.Tensor]:
    """Examples (:func:`examples`) -> the batch ``MotionJudge.loss`` takes: ``x`` (B, T, F)
    zero-padded, ``lengths`` (B,), ``content`` and ``style`` (B,) long. An example with a
    ``window`` shorter than its rows gives a crop at a random start (torch's global
    generator, whose state the trainer's checkpoints keep)."""
    rows = []
    for ex in batch:
        r, window = torch.from_numpy(ex["rows"]), ex["window"]
        if window is not None and len(r) > window:
            s = int(torch.randint(len(r) - window + 1, ()))
            r = r[s:s + window]
        rows.append(r)
    return {"x": nn.utils.rnn.pad_sequence(rows, batch_first=True),
            "lengths": torch.tensor([len(r) for r in rows]),
            "content": torch.tensor([ex["content"] for ex in batch]),
            "style": torch.tensor([ex["style"] for ex in batch])}


def accuracy(judge: MotionJudge, items: Sequence[JudgeItem]) -> dict[str, float]:
    """Fractions of ``items`` (whole motions) whose content / style the judge names; style
    over the items with a known style only."""
    if not items:
        raise MotionlangError("accuracy: no items")
    got = []
    for fps in sorted({it.fps for it in items}):
        part = [it for it in items if it.fps == fps]
        got += list(zip(part, judge.predict([it.positions for it in part], fps)))
    styled = [(it, s) for it, (_, s) in got if it.style is not None]
    return {"content": float(np.mean([c == it.content for it, (c, _) in got])),
            "style": float(np.mean([s == it.style for it, s in styled])) if styled
            else float("nan"), "n": len(got)}


def median_bones(items: Sequence[JudgeItem]) -> list[float]:
    """The 20 median bone lengths (m) over every frame of ``items``: the body a judge
    reads motions on (``JudgeConfig.bones``)."""
    return median_bones21([it.positions for it in items])


def bandai_sentences(source: str | Path, split: str | None = "test", seed: int = 0) -> list:
    """One English sentence per Bandai take of ``split`` (``bandai_text.Sentence``: ``text``,
    ``content``, ``style``, ``states_style``), in :func:`bandai_items`' order (by id): what a
    text-to-motion model is asked for to be judged beside that take."""
    return [r.sentences[0] for r in load_bandai_text(source, split, per_take=1, seed=seed)]
