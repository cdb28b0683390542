"""Training on several datasets at once: ``--data PATH[@WEIGHT]`` given more than once
(each value a ``sources.DataSource``).

Each dataset keeps its own split (a procedural corpus its random split by seed, Bandai its
take numbers), so a mixed run's test motions are those each dataset alone would test on.
Records of all datasets share one vocabulary and one feature set (fitted on all training
motions: ``seq2seq_pairs.build_pairs``). Weights set each dataset's share of a training
epoch (:func:`mix_items`); without weights every training pair goes in once, so larger
datasets dominate.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

# the ``--data`` value as an object, importable here too for the callers of before
from motionlang.datasets.sources import DataSource, parse_source  # noqa: F401
from motionlang.errors import DatasetError, MotionlangError


def source_weights(sources: Sequence[DataSource]) -> list[float] | None:
    """The sources' weights, or None when none has one.

    Raises:
        MotionlangError: some have a weight and others not.
    """
    given = [s.weight is not None for s in sources]
    if not any(given):
        return None
    if not all(given):
        bare = ", ".join(s.path for s, g in zip(sources, given) if not g)
        raise MotionlangError(f"--data: give a weight (PATH@W) to every dataset or to none; "
                              f"{bare} has none")
    return [float(s.weight) for s in sources if s.weight is not None]


def check_distinct_ids(ids_by_source: Mapping[str, Sequence[str]]) -> None:
    """Record ids must not repeat across datasets (the split files list ids only).

    Raises:
        DatasetError: naming an id and both datasets.
    """
    seen: dict[str, str] = {}
    for name, ids in ids_by_source.items():
        for i in ids:
            if i in seen:
                raise DatasetError(f"motion id {i!r} is in both {seen[i]} and {name}: these "
                                   f"datasets cannot be mixed (their split files would clash)")
            seen[i] = name


def mix_items(items: Sequence[dict], source_of: dict[str, int], weights: Sequence[float],
              seed: int = 0) -> list[dict]:
    """Training pairs resampled so that dataset k fills ``weights[k] / sum(weights)`` of an
    epoch of ``len(items)`` pairs.

    A dataset with fewer pairs than its share has every pair repeated ``q`` times plus a
    seeded choice of ``r`` more (``share = q * n + r``); one with more has a seeded subset
    of its pairs (the same for the whole run: a run does not see the rest). Deterministic
    given ``seed``. ``source_of`` maps an item's ``"id"`` to its dataset's index.

    Raises:
        DatasetError: a weighted dataset has no training pairs.
    """
    by_source: list[list[int]] = [[] for _ in weights]
    for n, it in enumerate(items):
        by_source[source_of[it["id"]]].append(n)
    total, wsum = len(items), float(sum(weights))
    out: list[dict] = []
    for k, (idx, w) in enumerate(zip(by_source, weights)):
        if not idx:
            raise DatasetError(f"dataset {k + 1} of --data has no training pairs to weight")
        want = int(round(total * w / wsum))
        q, r = divmod(want, len(idx))
        rng = np.random.default_rng([seed, k])
        extra = sorted(rng.choice(len(idx), size=r, replace=False).tolist())
        out += [items[n] for n in idx for _ in range(q)] + [items[idx[j]] for j in extra]
    return out


def source_counts(items: Sequence[dict], source_of: dict[str, int], n: int) -> list[int]:
    """How many of ``items`` come from each of the ``n`` datasets."""
    counts = [0] * n
    for it in items:
        counts[source_of[it["id"]]] += 1
    return counts


def mix_training(sources: Sequence, train_items: list[dict], source_of: dict[str, int],
                 seed: int) -> list[dict]:
    """Several sources: the training items weighted by their ``@W`` (``mixing.mix_items``;
    unchanged without weights), with a line per dataset of its share of an epoch."""
    if len(sources) < 2:
        return train_items
    n, weights = len(sources), source_weights(sources)
    before = source_counts(train_items, source_of, n)
    if weights:
        train_items = mix_items(train_items, source_of, weights, seed=seed)
    after = source_counts(train_items, source_of, n)
    for s, b, a in zip(sources, before, after, strict=True):
        print(f"{s}: {a} training pairs per epoch ({a / len(train_items):.0%}; "
              f"{b} before weighting)")
    return train_items
