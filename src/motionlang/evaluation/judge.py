"""Judging generated motion against real motion with a trained judge
(``models.judge.MotionJudge``), for any text-to-motion model.

Given motions generated for asked (content, style) labels, :func:`judge_motions` reports:

* ``content_acc`` / ``style_acc``: how often the judge recognises the asked content /
  style (over the motions whose asked label the judge knows; ``n_content`` / ``n_style``
  say how many);
* ``fid``: Frechet distance between the judge's penultimate features of the motions and
  of a real reference set (``metrics.t2m.fid``);
* ``diversity``: mean distance between random pairs of those features
  (``metrics.t2m.diversity``, at most 300 pairs);
* physical plausibility (``metrics.physics``): ``skating`` (m/s, mean over the motions with
  any foot contact), ``penetration`` (m, mean), ``penetration_max``, ``root_jump`` and
  ``root_kick`` (m, max over motions; ``root_jump_mean`` the mean of ``root_jump``).

:func:`judge_report` scores generated motions and the ground truth the same way; the
ground truth's ``fid`` is between two random halves of the real set, the value FID takes
for two real samples of that size (its floor), since the real set against itself gives 0.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics.physics import physics
from motionlang.evaluation.metrics.t2m import diversity, fid


def _recognised(probs: np.ndarray, names: Sequence[str], asked: Sequence[str | None]
                ) -> tuple[float, int]:
    """Fraction of the motions with a known asked label whose top class is that label."""
    known = [(i, names.index(a)) for i, a in enumerate(asked) if a in names]
    if not known:
        return float("nan"), 0
    hits = [int(np.argmax(probs[i]) == j) for i, j in known]
    return float(np.mean(hits)), len(known)


def judge_motions(judge, motions: Sequence[np.ndarray], fps: float,
                  asked: Sequence[tuple[str | None, str | None]],
                  reference: np.ndarray | None = None, *, rng: int = 0,
                  skating: dict | None = None) -> dict[str, float]:
    """Measures of ``motions`` (each (T, 21, 3) metres, Y up, floor y = 0, at ``fps``) asked
    as ``asked`` (content, style) pairs (None: not asked). ``reference``: (M, E) judge
    embeddings of real motions (``judge.judge(...)["embedding"]``) for ``fid``, else no
    FID. ``skating``: options of ``metrics.physics.foot_skating``.
    """
    if len(motions) != len(asked):
        raise MotionlangError(f"{len(motions)} motions but {len(asked)} asked labels")
    if not len(motions):
        raise MotionlangError("judge_motions: no motions")
    got = judge.judge(motions, fps)
    out: dict[str, float] = {"n": len(motions)}
    out["content_acc"], out["n_content"] = _recognised(got["content"], judge.config.contents,
                                                       [a[0] for a in asked])
    out["style_acc"], out["n_style"] = _recognised(got["style"], judge.config.styles,
                                                   [a[1] for a in asked])
    emb = got["embedding"]
    out["fid"] = fid(reference, emb) if reference is not None and len(emb) > 1 else float("nan")
    out["diversity"] = (diversity(emb, times=min(300, len(emb) - 1), rng=rng)
                        if len(emb) > 1 else float("nan"))
    phys = [physics(p, fps, **(skating or {})) for p in motions]
    skate = [m["skating"] for m in phys if np.isfinite(m["skating"])]
    out["skating"] = float(np.mean(skate)) if skate else float("nan")
    out["penetration"] = float(np.mean([m["penetration"] for m in phys]))
    out["penetration_max"] = float(np.max([m["penetration_max"] for m in phys]))
    out["root_jump"] = float(np.max([m["root_jump"] for m in phys]))
    out["root_jump_mean"] = float(np.mean([m["root_jump"] for m in phys]))
    out["root_kick"] = float(np.max([m["root_kick"] for m in phys]))
    return out


def judge_report(judge, generated: Sequence[np.ndarray], asked, fps: float,
                 real: Sequence[np.ndarray], real_labels, real_fps: float, *,
                 rng: int = 0) -> dict[str, dict[str, float]]:
    """``{"generated": ..., "ground_truth": ...}``: :func:`judge_motions` of the generated
    motions (FID against ``real``) and of ``real`` with its own ``real_labels`` (FID
    between two random halves of ``real``; NaN with fewer than 4 real motions)."""
    ref = judge.judge(real, real_fps)["embedding"]
    gen = judge_motions(judge, generated, fps, asked, ref, rng=rng)
    truth = judge_motions(judge, real, real_fps, real_labels, None, rng=rng)
    if len(ref) >= 4:
        order = np.random.default_rng(rng).permutation(len(ref))
        half = len(ref) // 2
        truth["fid"] = fid(ref[order[:half]], ref[order[half:]])
    return {"generated": gen, "ground_truth": truth}


# -- the table of ``motionlang evaluate-judge`` ---------------------------------------------
#: the columns of :func:`markdown_judge_table`: measure -> (header, scale)
JUDGE_COLUMNS = {"content_acc": ("content %", 100), "style_acc": ("style %", 100),
                 # the grounded analysis: any action it reads, not the judge's classes
                 "check": ("open-world check %", 100),
                 "fid": ("FID", 1), "diversity": ("diversity", 1),
                 "skating": ("skating m/s", 1), "penetration": ("penetration cm", 100),
                 "penetration_max": ("max penetration cm", 100),
                 # the control for skating: a model that moves less also slides less
                 "root_jump_mean": ("mean max root jump cm", 100),
                 "root_jump": ("max root jump cm", 100),
                 "root_kick": ("max root kick cm", 100)}


def asked_labels(sentences: Sequence) -> list[tuple[str, str | None]]:
    """(content, style) a sentence asks for (``bandai_text.Sentence``); the style None where
    its words do not state it (some "normal" sentences)."""
    return [(s.content, s.style if getattr(s, "states_style", True) else None)
            for s in sentences]


def judge_table(judge, real: Sequence[np.ndarray], real_labels, real_fps: float,
                generated: dict[str, Sequence[np.ndarray]], asked, fps: float, *,
                rng: int = 0) -> dict[str, dict[str, float]]:
    """``{"ground truth": ..., name: ...}``: :func:`judge_report` of each model's motions
    (``generated[name]``, asked ``asked``) beside the real motions with their own labels
    (whose recognition rates are the judge's own accuracy)."""
    ref = judge.judge(list(real), real_fps)["embedding"]
    truth = judge_motions(judge, list(real), real_fps, real_labels, None, rng=rng)
    if len(ref) >= 4:
        order = np.random.default_rng(rng).permutation(len(ref))
        half = len(ref) // 2
        truth["fid"] = fid(ref[order[:half]], ref[order[half:]])
    table = {"ground truth": truth}
    for name, motions in generated.items():
        table[name] = judge_motions(judge, list(motions), fps, asked, ref, rng=rng)
    return table


def markdown_judge_table(table: dict[str, dict[str, float]], title: str = "") -> str:
    """:func:`judge_table` as a Markdown table (:data:`JUDGE_COLUMNS`; "–" for NaN)."""
    head = "| | " + " | ".join(h for h, _ in JUDGE_COLUMNS.values()) + " |"
    lines = ([title, ""] if title else []) + [head, "|---" * (len(JUDGE_COLUMNS) + 1) + "|"]
    for name, row in table.items():
        cells = []
        for key, (_, scale) in JUDGE_COLUMNS.items():
            v = row.get(key, float("nan"))
            cells.append("–" if not np.isfinite(v) else f"{v * scale:.{1 if scale == 100 else 3}f}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
