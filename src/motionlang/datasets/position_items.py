"""From a dataset folder to training items of 12.5 Hz position features: the two-stream
model's (Ghosh et al. 2021), the masked and retrieval families' and the text-to-motion
evaluations'.

Reads a KIT-ML-format folder (the release or a procedural corpus) or a custom folder
(``datasets.seq2seq_pairs.load_records``), drops motions without descriptions, splits by
motion (the records' own split where they name one, else ``datasets.splits.random_split``),
fits the *positions* features (21 joints + root
trajectory, 12.5 Hz, ``features.positions.PositionFeatures``) on the training motions only
and encodes every motion once through the on-disk feature cache
(``datasets.feature_cache.dataset_features``). Each motion is paired with each of its
descriptions: items ``{"motion": (T, 66) float32 normalised, "sentence": str, "id": str}``,
the input of ``TwoStreamModel.collate``. With ``mirror`` the training items also hold
every training motion mirrored left/right with its sentences' sides swapped. With
``by_source`` each source's motions are normalised by that source's own training motions
(:func:`normalise_by_source`).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from motionlang.datasets.feature_cache import dataset_features
from motionlang.datasets.seq2seq_pairs import load_sources
from motionlang.datasets.synth.augment import mirror_text
from motionlang.errors import DatasetError
from motionlang.features.normalizer import Normalizer
from motionlang.features.positions import DEFAULT_FPS

#: frame rate of the positions features (the features' own default)
FPS = DEFAULT_FPS


@dataclass
class TwoStreamData:
    """Everything a two-stream training or evaluation run needs.

    Attributes:
        features: the fitted ``PositionFeatures`` (its normaliser included).
        splits: ``{"train"|"val"|"test": [record ids]}``.
        records: ``{id: record}`` (``annotations``, ``meta``, ``n_frames`` at 100 Hz).
        sequences: ``{id: (T, 66) float32}`` normalised features at 12.5 Hz.
        items: per split, ``[{"motion", "sentence", "id"}]`` (one per description; with
            ``mirror`` the mirrored training items also carry ``"mirrored": True``).
        sources: ``{id: index of its dataset}`` (several datasets: ``datasets.mixing``).
        normalizers: normalised by source, each source's normaliser in source order
            (:func:`normalise_by_source`); else empty.
    """

    features: Any
    splits: dict[str, list[str]]
    records: dict[str, Any]
    sequences: dict[str, np.ndarray]
    items: dict[str, list[dict]]
    sources: dict[str, int] = field(default_factory=dict)
    normalizers: list = field(default_factory=list)

    def first_frames(self, split: str = "train") -> np.ndarray:
        """(N, 66) first frames of the split's motions (for ``TwoStreamModel.set_rest_pose``)."""
        return np.stack([self.sequences[i][0] for i in self.splits[split]])


def build_twostream_data(data: str | Path | Sequence[str | Path], *, fractions: Sequence[float] = (0.8, 0.1, 0.1),
                         seed: int = 0, max_seconds: float | None = 30.0,
                         max_frames: int | None = None, cache_dir: str | Path | None = None,
                         mirror: bool = False, by_source: int | None = None) -> TwoStreamData:
    """Read ``data``, split by motion, fit + encode positions features (cached), make items.

    Args:
        data: one dataset or several (``seq2seq_pairs.load_sources``: one feature set,
            each dataset's own split).
        fractions, seed: the split (``random_split``), unless every record names its own
            (``seq2seq_pairs.record_splits``: the Bandai takes).
        max_seconds: drop motions this long or longer.
        max_frames: crop every training/validation/test sequence to its first
            ``max_frames`` frames (12.5 Hz) to bound the unrolled decoder's cost; None keeps all.
        cache_dir: feature cache folder (default ``$MOTIONLANG_CACHE`` or ~/.cache/motionlang).
        mirror: add each training motion mirrored (``mirror_motion``) with each of its
            sentences' sides swapped (``datasets.synth.augment.mirror_text``) to the training
            items (marked ``"mirrored": True``, same ``id``): twice the items, both sides
            equally often. Features are fitted on the unmirrored motions; ``sequences`` and
            the other splits stay unmirrored.
        by_source: several datasets: normalise each by its own training motions, and give
            ``features`` the normaliser of dataset ``by_source`` (an index into ``data``;
            negative from the end): :func:`normalise_by_source`. None: one normaliser
            fitted on all training motions.
    """

    records, splits, sources = load_sources(data, max_seconds, fractions=fractions, seed=seed)
    by_id = {str(r.id): r for r in records}
    train = [by_id[i] for i in splits["train"]]
    if not train:
        raise DatasetError(f"{data}: the training split is empty")
    df = dataset_features(records, "positions", {"fps": FPS}, fit_records=train,
                          directory=cache_dir)
    seqs = _first_sequences(df, max_frames)
    items = {name: [{"motion": seqs[i], "sentence": s, "id": i}
                    for i in ids for s in by_id[i].annotations]
             for name, ids in splits.items()}
    if mirror:
        flipped = _first_sequences(dataset_features(
            train, "positions", {"fps": FPS}, fit_records=train, directory=cache_dir,
            mirror=True), max_frames)
        items["train"] += [{"motion": flipped[i], "sentence": mirror_text(s), "id": i,
                            "mirrored": True}
                           for i in splits["train"] for s in by_id[i].annotations]
    data = TwoStreamData(df.features, splits, by_id, seqs, items, sources)
    if by_source is None:
        return data
    # fitted on the whole motions, as the shared normaliser is, not on their crops
    return normalise_by_source(data, by_source, whole=_first_sequences(df, None))


def normalise_by_source(data: TwoStreamData, output: int,
                        whole: dict[str, np.ndarray] | None = None) -> TwoStreamData:
    """``data`` with every motion z-normalised by the mean and spread of its own source's
    training motions (mirrored copies by their source's too), and ``features`` carrying the
    normaliser of source ``output`` (negative: from the end), so a model trained on it makes
    motions in that source's statistics. ``whole``: the training motions to fit on, where
    ``data.sequences`` holds crops of them (default ``data.sequences``).

    Why: one normaliser over sources of unlike spread squeezes the narrower one. The
    procedural corpus has bodies of many sizes, the Bandai actors one: over both, the joints'
    heights spread several times as much as over the Bandai takes, so the Bandai motions
    fill a small part of the model's input and output range. Normalised by source, each
    fills it as it would alone. (Weighing each source's errors by its own spread in the loss,
    with one normaliser, does not do it: ``docs/results/twostream.md``.) The cost: the
    model's motions come out in one source's statistics, whatever the sentence.

    Raises:
        DatasetError: ``output`` names no source, or a source has no training motion.
    """
    import copy

    ids = sorted(set(data.sources.values()))
    n = (max(ids) + 1) if ids else 1
    if not -n <= output < n:
        raise DatasetError(f"by_source: {output} names none of the {n} data sources")
    shared = data.features.normalizer
    fitted = {}
    for s in range(n):
        rows = [shared.inverse(np.asarray((whole or data.sequences)[i], dtype=np.float64))
                for i in data.splits["train"] if data.sources.get(i, 0) == s]
        if not rows:
            raise DatasetError(f"by_source: data source {s} has no training motion")
        fitted[s] = Normalizer(names=shared.names, min_std=shared.min_std).fit(rows)

    def renorm(rid: str, x: np.ndarray) -> np.ndarray:
        back = shared.inverse(np.asarray(x, dtype=np.float64))
        return fitted[data.sources.get(rid, 0)].transform(back).astype(np.float32)

    data.sequences = {i: renorm(i, x) for i, x in data.sequences.items()}
    for part in data.items.values():
        for it in part:   # an item's motion is its sequence, or its mirrored copy
            it["motion"] = (renorm(it["id"], it["motion"]) if it.get("mirrored")
                            else data.sequences[it["id"]])
    data.features = copy.deepcopy(data.features)
    data.features.normalizer = fitted[output % n]
    data.normalizers = [fitted[s] for s in range(n)]
    return data


def _first_sequences(df, max_frames: int | None) -> dict[str, np.ndarray]:
    """``{id: (T, 66) float32}`` of each record's (only) sequence, cut at ``max_frames``."""
    seqs = {}
    for rid, arrays in df.sequences.items():
        x = np.asarray(arrays[0], dtype=np.float32)
        seqs[rid] = x[:max_frames] if max_frames else x
    return seqs
