"""Training the motion judge: labelled 21-joint motions in, a fitted :class:`MotionJudge` out.

:func:`bandai_items` reads the Bandai Namco takes of a split as :class:`JudgeItem`
(positions at the positions features' rate, cached by file identity); any other labelled motions can join them,
``style=None`` where there is none: :func:`primitive_items` cuts a procedural corpus'
primitives that show a Bandai action (walks, runs, waves, raised arms, bows, kicks,
punches). :func:`fit_judge` is a plain torch loop: AdamW, random crops of ``config.window`` frames, optional mirrored
copies (left/right swapped in positions and label), the epoch with the best validation
accuracy kept. :func:`accuracy` scores whole motions.
"""
from __future__ import annotations

import copy
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import torch
from torch import nn

from motionlang.errors import MotionlangError
from motionlang.features.body21 import median_bones21
from motionlang.features.joint_map import KIT21_MIRROR
from motionlang.features.normalizer import Normalizer
from motionlang.features.positions import DEFAULT_FPS
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
    from motionlang.datasets.bandai_text import MIRROR_CONTENT  # a lower layer
    return replace(item, id=f"M{item.id}",
                   positions=item.positions[:, list(KIT21_MIRROR)] * np.array([-1.0, 1, 1]),
                   content=MIRROR_CONTENT.get(item.content, item.content))


def bandai_items(source: str | Path, split: str | None = None, fps: float = DEFAULT_FPS
                 ) -> list[JudgeItem]:
    """The Bandai Namco takes of ``split`` (``datasets.bandai.load_bandai``) as items: each
    take's 21-joint body (``PositionFeatures.body``: on the floor) at ``fps`` Hz. Cached
    (``datasets.cache``) by the takes' file identities."""
    from motionlang.datasets.bandai import load_bandai
    from motionlang.datasets.cache import cached, file_identity
    from motionlang.features.positions import PositionFeatures, PositionsConfig
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
    from motionlang.datasets.kitml import load_kitml
    from motionlang.datasets.synth import ground_truth
    from motionlang.features.positions import PositionFeatures, PositionsConfig
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


def _crop(rows: np.ndarray, window: int, rng: np.random.Generator) -> np.ndarray:
    if len(rows) <= window:
        return rows
    s = int(rng.integers(len(rows) - window + 1))
    return rows[s:s + window]


def _batch(rows: Sequence[np.ndarray], ids: dict[str, np.ndarray]) -> dict:
    x = nn.utils.rnn.pad_sequence([torch.from_numpy(r) for r in rows], batch_first=True)
    return {"x": x, "lengths": torch.tensor([len(r) for r in rows]),
            **{k: torch.as_tensor(v) for k, v in ids.items()}}


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


def fit_judge(train: Sequence[JudgeItem], val: Sequence[JudgeItem] = (), *,
              epochs: int = 30, batch_size: int = 32, lr: float = 1e-3,
              weight_decay: float = 1e-4, mirror: bool = True, seed: int = 0,
              uniform: bool = True, log: Callable[[str], None] | None = None, **config
              ) -> tuple[MotionJudge, list]:
    """Train a judge on ``train`` (labels: every content, every known style there); keep the
    epoch whose ``val`` accuracy (mean of content and style) is best, else the last.

    uniform: read every motion on one body, the training motions' median bone lengths
    (``JudgeConfig.bones``), unless ``config`` gives ``bones``.
    config: :class:`JudgeConfig` fields (sizes, window). Returns the judge (eval mode) and
    one dict per epoch (``loss``, ``content_acc``, ``style_acc`` on the training crops,
    ``val_content``, ``val_style``, ``seconds``).
    """
    if not train:
        raise MotionlangError("fit_judge: no training items")
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    items = list(train) + ([mirror_item(it) for it in train] if mirror else [])
    if uniform and config.get("bones") is None:
        config["bones"] = median_bones(train)
    cfg = JudgeConfig(contents=sorted({it.content for it in items}),
                      styles=sorted({it.style for it in items if it.style is not None}),
                      **config)
    raw = [judge_rows(it.positions, it.fps, cfg) for it in items]
    norm = Normalizer().fit(raw)
    rows = [norm.transform(r).astype(np.float32) for r in raw]
    c_id = np.array([cfg.contents.index(it.content) for it in items])
    s_id = np.array([-1 if it.style is None else cfg.styles.index(it.style) for it in items])
    judge = MotionJudge(cfg, norm)
    opt = torch.optim.AdamW(judge.parameters(), lr=lr, weight_decay=weight_decay)
    history, best, best_score = [], None, -1.0
    for epoch in range(epochs):
        t0 = time.time()
        judge.train()
        sums: dict[str, float] = {}
        order = rng.permutation(len(items))
        for s in range(0, len(order), batch_size):
            idx = order[s:s + batch_size]
            batch = _batch([_crop(rows[i], cfg.window, rng) for i in idx],
                           {"content": c_id[idx], "style": s_id[idx]})
            terms = judge.loss(batch)
            opt.zero_grad()
            terms["loss"].backward()
            opt.step()
            for k, v in terms.items():
                sums[k] = sums.get(k, 0.0) + float(v.detach()) * len(idx)
        rec = {k: v / len(items) for k, v in sums.items() if not k.endswith("_loss")}
        if val:
            acc = accuracy(judge, val)
            rec.update(val_content=acc["content"], val_style=acc["style"])
            score = float(np.nanmean([acc["content"], acc["style"]]))
            if score > best_score:
                best_score, best = score, copy.deepcopy(judge.state_dict())
        rec.update(epoch=epoch + 1, seconds=time.time() - t0)
        history.append(rec)
        if log:
            log(" ".join(f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
                         for k, v in rec.items()))
    if best is not None:
        judge.load_state_dict(best)
    return judge.eval(), history


def bandai_sentences(source: str | Path, split: str | None = "test", seed: int = 0) -> list:
    """One English sentence per Bandai take of ``split`` (``bandai_text.Sentence``: ``text``,
    ``content``, ``style``, ``states_style``), in :func:`bandai_items`' order (by id): what a
    text-to-motion model is asked for to be judged beside that take."""
    from motionlang.datasets.bandai import load_bandai_text
    return [r.sentences[0] for r in load_bandai_text(source, split, per_take=1, seed=seed)]
