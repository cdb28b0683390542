"""Which items an evaluation with ``--limit N`` scores: a seeded random sample, stratified
by label where the items have labels.

The first N items in file order are no sample: a dataset sorted by id is often sorted by
action too (the Bandai takes: one action after another), so the first 20 are all one
action, and every measure (recognition, FID, diversity) describes that action only.
"""
from __future__ import annotations

from collections.abc import Hashable, Sequence

import numpy as np

from motionlang.errors import MotionlangError


def stratified_sample(n: int, limit: int | None, labels: Sequence[Hashable] | None = None,
                      seed: int = 0) -> list[int]:
    """Indices (sorted, so the items keep their order) of ``limit`` of ``n`` items.

    Without ``labels`` a uniform random sample. With ``labels`` (one per item) each label
    gets its share of ``limit`` in proportion to its count (largest remainders, ties by
    label order), at least one while ``limit`` allows one per label, and its items are
    drawn at random within it. ``limit`` of 0 / None or >= ``n``: every index. The draw is
    a function of ``seed``, ``n``, ``limit`` and the labels only.

    Raises:
        MotionlangError: a negative limit, or labels of another length than ``n``.
    """
    if limit is not None and limit < 0:
        raise MotionlangError(f"limit must be >= 0, got {limit}")
    if not limit or limit >= n:
        return list(range(n))
    rng = np.random.default_rng(seed)
    if labels is None:
        return sorted(int(i) for i in rng.choice(n, size=limit, replace=False))
    if len(labels) != n:
        raise MotionlangError(f"{len(labels)} labels for {n} items")
    groups: dict[Hashable, list[int]] = {}
    for i, lab in enumerate(labels):
        groups.setdefault(lab, []).append(i)
    names = list(groups)
    counts = np.array([len(groups[k]) for k in names], dtype=float)
    share = counts * limit / n
    take = np.floor(share).astype(int)
    if limit >= len(names):   # every label seen at least once
        take = np.maximum(take, 1)
    while take.sum() > limit:   # the minimum of one overshot: trim the largest shares
        j = int(np.argmax(take - share + (take <= 1) * -1e9))
        take[j] -= 1
    order = np.argsort(-(share - take), kind="stable")   # largest remainders first
    k = 0
    while take.sum() < limit:
        j = int(order[k % len(order)])
        if take[j] < counts[j]:
            take[j] += 1
        k += 1
    chosen: list[int] = []
    for name, t in zip(names, take, strict=True):
        members = groups[name]
        chosen += [members[int(i)] for i in rng.choice(len(members), size=int(t),
                                                       replace=False)]
    return sorted(chosen)
