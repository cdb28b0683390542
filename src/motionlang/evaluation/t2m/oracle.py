"""How low can APE go on the procedural corpus? Oracles that know each test motion's full
ground-truth parameters.

A corpus motion is drawn from its parameters (actions, sides, counts, directions, speeds,
angles) *and* from unstated ones: the subject's height, tempo, stride, posture and the
primitives' timing. A sentence carries at most the first set, so no model can predict the
second, and APE, a frame-by-frame distance, charges for it. Two rows measure this on the
test motions whose exact parameters occur at least ``min_group`` times in training:

* **mean of the same-parameter training motions**: each re-timed to the test length
  (``models.t2m.stretch``) and averaged frame by frame: a reference point for a
  deterministic model told *every* parameter (the frame-wise mean minimises a squared
  error; APE is a plain distance and the re-timing is a guess, so this is not a strict
  floor);
* **one same-parameter training motion** (the first in the split): what a real motion that
  fits the description exactly scores.

Every model row of the main table is re-scored on the same subset beside them.
"""
from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence

import numpy as np

from motionlang.datasets.synth import ground_truth
from motionlang.errors import MotionlangError
from motionlang.evaluation.t2m.scoring import markdown_table, score_generated
from motionlang.models.t2m import stretch

MEAN_ROW = "oracle: mean of the same-parameter training motions"
ONE_ROW = "oracle: one same-parameter training motion"


def parameter_key(record) -> tuple | None:
    """The motion's full ground-truth parameters (``Primitive.key()`` and layer of each
    primitive, in order), hashable; None without corpus meta."""
    meta = getattr(record, "meta", None) or {}
    if not meta.get("primitives"):
        return None
    return tuple((p.key(), p.layer) for p in ground_truth(meta))


def same_parameter_groups(data, split: str = "train") -> dict[tuple, list[str]]:
    """{parameter key: ids of the ``split`` motions with exactly those parameters}."""
    groups: dict[tuple, list[str]] = defaultdict(list)
    for rid in data.splits[split]:
        key = parameter_key(data.records[rid])
        if key is not None:
            groups[key].append(rid)
    return dict(groups)


def oracle_generations(data, items: Sequence, min_group: int = 3
                       ) -> tuple[list, dict[str, dict[str, np.ndarray]]]:
    """(the items with >= ``min_group`` same-parameter training motions, {row name: {item
    id: (T, 21, 3) metres}}) for :data:`MEAN_ROW` and :data:`ONE_ROW`.

    Raises:
        MotionlangError: ``min_group`` < 1, or no item has an oracle.
    """
    if min_group < 1:
        raise MotionlangError(f"the oracle needs groups of at least 1 motion, got {min_group}")
    groups = same_parameter_groups(data)
    kept, mean, one = [], {}, {}
    for it in items:
        ids = groups.get(parameter_key(data.records[it.id]), [])
        ids = [i for i in ids if i != it.id]   # evaluated on training motions: not itself
        if len(ids) < min_group:
            continue
        T = len(it.target)
        motions = [stretch(data.features.decode(data.sequences[i]), T) for i in ids]
        kept.append(it)
        mean[it.id] = np.mean(motions, axis=0)
        one[it.id] = motions[0]
    if not kept:
        raise MotionlangError(f"no test motion has {min_group} training motions with its "
                              "exact parameters (a procedural corpus is needed)")
    return kept, {MEAN_ROW: mean, ONE_ROW: one}


def oracle_table(results: dict[str, dict], data, kept: Sequence, gens: dict, n_items: int,
                 prototypes) -> tuple[dict[str, dict], str]:
    """Every row of ``results`` (``compare.compare``'s, with ``generated``) re-scored on
    ``kept``, and the oracle rows ``gens`` (both from :func:`oracle_generations` over
    ``n_items`` test items). Returns (rows, markdown)."""
    rows = {name: score_generated({it.id: r["generated"][it.id] for it in kept}, kept,
                                  data.features, prototypes) for name, r in results.items()}
    rows.update({name: score_generated(g, kept, data.features, prototypes)
                 for name, g in gens.items()})
    table = markdown_table(rows).rstrip("\n") + (
        f" Only the {len(kept)} of {n_items} test motions with enough training motions of "
        "exactly their parameters.\n")
    return rows, table
