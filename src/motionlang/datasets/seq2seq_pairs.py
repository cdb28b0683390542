"""From a dataset folder to (motion features, sentence) pairs for the seq2seq models.

The same code reads a KIT-ML release, a procedural corpus (written in KIT-ML format) and a
custom folder of motion files with a captions file. Motions without descriptions are
dropped; the split is by motion (``datasets.splits.random_split``), so no motion's
sentences or offsets are shared between train and test. Features are fitted on the
training motions only. Each motion gives up to ``offsets`` down-sampled sequences (the
paper's augmentation: 10 start offsets from 100 Hz to 10 Hz) and each sequence is paired
with every description.

Model frames are the feature set's normalised dimensions only: a trailing binary "active"
flag (AnglesFeatures) is dropped, since L2M predicts its own end-of-motion flag.
"""
from __future__ import annotations

import json
import logging
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from motionlang.datasets.cache import cached, file_identity
from motionlang.datasets.mixing import check_distinct_ids
from motionlang.datasets.sources import DataSource, Record, load
from motionlang.datasets.splits import random_split
from motionlang.datasets.synth import ground_truth
from motionlang.datasets.synth.augment import mirror_text
from motionlang.datasets.text import SPECIALS, Vocabulary
from motionlang.errors import DatasetError, MotionlangError
from motionlang.features.angles import AnglesFeatures
from motionlang.features.base import FeatureSet, features_from_dict
from motionlang.features.frames import motion_frames
from motionlang.features.positions import PositionFeatures
from motionlang.kinematics.from_positions import mirror_motion
from motionlang.utils.progress import progress

CACHE_VERSION = "seq2seq-pairs-1"
#: down-sampling start offsets per motion: a 1000 Hz take down-sampled to 10 Hz has 100
MAX_OFFSETS = 100
log = logging.getLogger(__name__)


def load_records(data: str | Path | DataSource, max_seconds: float | None = 30.0,
                 joint_map: str | Path | dict | None = None) -> list[Record]:
    """The records of one source (``sources.load``; text is parsed by
    ``sources.parse_source``): a KIT-ML-format folder, a custom folder (whose rig maps onto
    the 21-joint body by ``joint_map``, see ``load_custom``), ``humanml3d:DIR`` /
    ``kitml-h3d:DIR`` or ``bandai:DIR`` (non-commercial licence)."""
    return load(data, max_seconds=max_seconds, joint_map=joint_map)


def record_splits(records: Sequence, fractions: Sequence[float] = (0.8, 0.1, 0.1),
                  seed: int = 0) -> dict[str, list[str]]:
    """Ids per split: the records' own (``split`` attribute: the Bandai takes' numbers, a
    HumanML3D folder's split files) when every record names one, else ``random_split``."""
    own = [getattr(r, "split", None) for r in records]
    if records and all(s in ("train", "val", "test") for s in own):
        out: dict[str, list[str]] = {"train": [], "val": [], "test": []}
        for r, s in zip(records, own):
            out[str(s)].append(r.id)
        return {k: sorted(v) for k, v in out.items()}
    return random_split([r.id for r in records], fractions, seed=seed)


def load_sources(data: str | Path | DataSource | Sequence[str | Path | DataSource],
                 max_seconds: float | None = 30.0,
                 joint_map: str | Path | dict | None = None,
                 fractions: Sequence[float] = (0.8, 0.1, 0.1), seed: int = 0
                 ) -> tuple[list, dict[str, list[str]], dict[str, int]]:
    """The described records of one dataset or several (``datasets.mixing``), each split on
    its own (``record_splits``), and ``{id: index of its dataset}``.

    Raises:
        DatasetError: fewer than 2 described motions (one dataset) or none (one of several);
            an id in two datasets.
    """
    sources = [data] if isinstance(data, (str, Path, DataSource)) else list(data)
    records: list = []
    splits: dict[str, list[str]] = {}
    source_of: dict[str, int] = {}
    ids: dict[str, list[str]] = {}
    for k, src in enumerate(sources):
        recs = [r for r in load_records(src, max_seconds, joint_map) if r.annotations]
        if len(recs) < (2 if len(sources) == 1 else 1):
            raise DatasetError(f"{src}: need at least {2 if len(sources) == 1 else 1} "
                               f"described motions, found {len(recs)}")
        ids[f"{src} (--data {k + 1})"] = [r.id for r in recs]
        check_distinct_ids(ids)
        for name, part in record_splits(recs, fractions, seed).items():
            splits.setdefault(name, []).extend(part)
        records += recs
        source_of.update((r.id, k) for r in recs)
    return records, splits, source_of


def record_path(rec: Any) -> Path:
    return Path(getattr(rec, "mmm_path", None) or rec.path)


def make_features(kind: str) -> FeatureSet:
    if kind == "angles":
        return AnglesFeatures()
    if kind == "positions":
        return PositionFeatures()
    raise MotionlangError(f"unknown features {kind!r} (angles or positions)")


@dataclass
class PairData:
    """Everything a seq2seq training run needs.

    Attributes:
        features: the fitted feature set. vocab: built from the training sentences.
        splits: ``{"train"|"val"|"test": [record ids]}``.
        items: per split, dicts ``{"motion" (T, F) float32, "tokens" [SOS .. EOS], "id"}``.
        references: per split, ``{id: [sentences]}`` (all descriptions, for BLEU).
        sequences: per split, ``{id: [(T, F) arrays, one per offset]}``.
        labels: ``{id: ["walk/backward", "wave", ...]}``, the ground-truth primitives of
            every motion whose meta carries them (procedural corpus), else empty.
        sources: ``{id: index of its dataset in build_pairs' data}`` (all 0 for one).
    """

    features: FeatureSet
    vocab: Vocabulary
    splits: dict[str, list[str]]
    items: dict[str, list[dict]]
    references: dict[str, dict[str, list[str]]]
    sequences: dict[str, dict[str, list[np.ndarray]]]
    labels: dict[str, list[str]] = field(default_factory=dict)
    sources: dict[str, int] = field(default_factory=dict)


def _thin(motion, fps: float):
    """Every k-th frame when that lands on ``fps`` exactly: fitting on these instead of the
    100 Hz motions keeps a 5,000-motion corpus in memory; the statistics barely change."""
    step = int(round(motion.fps / fps))
    if step <= 1 or abs(motion.fps / step - fps) > 1e-6 or motion.n_frames < step:
        return motion
    return motion[::step]


def _add_joint_maps(key: dict, records: Sequence) -> None:
    """A user's joint map changes every motion's body: it belongs in the cache key (added
    only when there is one, so that other keys stay those of earlier caches)."""
    maps = [getattr(r, "joint_map", None) for r in records]
    if any(maps):
        key["joint_maps"] = maps


def _fit_features(kind: str, train: Sequence) -> FeatureSet:
    """Fit on the training motions (cached by file identity)."""
    def compute():
        # one line for logs too: the bar below is hidden when stderr is not a terminal
        log.info(f"fitting {kind} features on {len(train)} training motions (cached after)")
        fs = make_features(kind)
        motions = []
        for rec in progress(train, desc="fit features", unit="motion"):
            motions.append(_thin(rec.load_motion(), fs.fps))
        fs.fit(motions)
        blob = json.dumps(fs.to_dict()).encode("utf-8")
        return {"json": np.frombuffer(blob, dtype=np.uint8)}
    key = {"v": CACHE_VERSION, "stage": "fit", "kind": kind,
           "config": asdict(make_features(kind).config),
           "files": [file_identity(record_path(r)) for r in train]}
    _add_joint_maps(key, train)
    out = cached(key, compute, name=f"seq2seq-fit-{kind}")
    return features_from_dict(json.loads(out["json"].tobytes().decode("utf-8")))


def _encode(fs: FeatureSet, records: Sequence, offsets: int, mirror: bool = False
            ) -> dict[str, list[np.ndarray]]:
    """{id: sequences} for ``records`` (cached by files + fitted features + offsets), of
    the mirrored motions (``Motion.mirror``) with ``mirror``."""
    def compute():
        log.info(f"encoding {len(records)} {'mirrored ' * mirror}motions x {offsets} offsets "
                 f"(cached after)")
        arrays: dict[str, np.ndarray] = {}
        for i, rec in enumerate(progress(records, desc="encode", unit="motion")):
            motion = rec.load_motion()
            for k, s in enumerate(motion_frames(fs, mirror_motion(motion) if mirror else motion,
                                                offsets)):
                arrays[f"{i}_{k}"] = s
        return arrays
    key = {"v": CACHE_VERSION, "stage": "encode", "features": fs.to_dict(), "offsets": offsets,
           "files": [file_identity(record_path(r)) for r in records]}
    if mirror:   # keys without it stay those of earlier caches; "mirror_motion": not the
        key["mirror"] = "mirror_motion"   # Motion.mirror of before, wrong on some rigs
    _add_joint_maps(key, records)
    out = cached(key, compute, name="seq2seq-encode")
    seqs: dict[str, list[np.ndarray]] = {r.id: [] for r in records}
    for name in sorted(out, key=lambda n: tuple(map(int, n.split("_")))):
        i, _ = name.split("_")
        seqs[records[int(i)].id].append(out[name])
    return seqs


def build_pairs(data: str | Path | DataSource | Sequence[str | Path | DataSource], *, features: str = "angles",
                offsets: int = 10,
                fractions: Sequence[float] = (0.8, 0.1, 0.1), seed: int = 0,
                min_count: int = 1, max_seconds: float | None = 30.0,
                mirror: bool = False, joint_map: str | Path | dict | None = None) -> PairData:
    """Read ``data``, split by motion, fit features and vocabulary on train, make pairs.

    data: one dataset (``load_records``) or several: their records share the vocabulary
    and the features (fitted on all their training motions), each keeps its own split
    (``load_sources``); ``PairData.sources`` says which dataset a motion is from (for
    ``mixing.mix_items``).

    joint_map: for a custom folder whose rig no built-in map recognises (``load_custom``).

    Splits: the records' own where they all name one (``record_splits``), else random.

    mirror: the training items also hold every training motion mirrored left/right
    (``kinematics.from_positions.mirror_motion``, right on any rig) with
    its sentences' sides swapped (``datasets.synth.augment.mirror_text``; items marked
    ``"mirrored": True``, same ``id``), which doubles them and balances the sides. The
    features are fitted on the unmirrored motions; references, sequences and the other
    splits stay unmirrored.
    """
    if not (isinstance(offsets, int) and 1 <= offsets <= MAX_OFFSETS):
        raise DatasetError(f"--offsets (offsets) must be an integer in 1..{MAX_OFFSETS}, "
                           f"got {offsets!r}")
    records, splits, sources = load_sources(data, max_seconds, joint_map, fractions, seed)
    by_id = {r.id: r for r in records}
    train = [by_id[i] for i in splits["train"]]
    if not train:
        raise DatasetError(f"{data}: the training split is empty")
    vocab = Vocabulary.build([s for r in train for s in r.annotations], min_count=min_count)
    if len(vocab.itos) <= len(SPECIALS):   # before the features are fitted
        raise DatasetError(f"no word of the training sentences is seen {min_count:,} times or "
                           "more: the vocabulary would be empty (lower --min-count)")
    fs = _fit_features(features, train)
    if mirror:
        # words only the mirrored sentences have go last: the ids of the others stay as
        # without --mirror, so a run can be resumed with it, unless new words make the
        # vocabulary larger (the trainer then refuses the checkpoint with a clear error)
        extra = Vocabulary.build([mirror_text(s) for r in train for s in r.annotations],
                                 min_count=min_count)
        for w in extra.itos:
            vocab.add(w)
    items, refs, seqs = {}, {}, {}
    for name, ids in splits.items():
        recs = [by_id[i] for i in ids]
        seqs[name] = _encode(fs, recs, offsets) if recs else {}
        refs[name] = {r.id: list(r.annotations) for r in recs}
        items[name] = [{"motion": s, "tokens": vocab.encode(text), "id": r.id}
                       for r in recs for s in seqs[name][r.id] for text in r.annotations]
    if mirror:
        mirrored = _encode(fs, train, offsets, mirror=True)
        items["train"] += [{"motion": s, "tokens": vocab.encode(mirror_text(text)),
                            "id": r.id, "mirrored": True}
                           for r in train for s in mirrored[r.id] for text in r.annotations]
    labels = {r.id: primitive_labels(r.meta) for r in records
              if (getattr(r, "meta", None) or {}).get("primitives")}
    return PairData(fs, vocab, splits, items, refs, seqs, labels, sources)


def sentence_lengths(data: PairData, split: str) -> tuple[list[str], list[int]]:
    """Every (sentence, length of its motion's first sequence in model frames) of ``split``:
    what an L2M's length model is fitted on."""
    pairs = [(text, len(data.sequences[split][i][0])) for i, texts in
             data.references[split].items() for text in texts if data.sequences[split][i]]
    return [t for t, _ in pairs], [n for _, n in pairs]


def primitive_labels(meta: dict) -> list[str]:
    """A procedural sample's primitives as labels: "action/direction" when the primitive
    has a direction (walk, run, jump), else "action"."""
    return [p.action + (f"/{p.direction}" if p.direction else "") for p in ground_truth(meta)]


def balance_repeats(labels: dict[str, list[str]], ids: Sequence[str], max_repeat: int
                    ) -> dict[str, int]:
    """How often each motion of ``ids`` goes into a balanced epoch.

    A label's count is the number of motions (of ``ids``) that have it; a motion is
    repeated round(sqrt(most common count / count of its rarest label)) times, at most
    ``max_repeat``. The square root halves the imbalance on a log scale instead of removing
    it, so that rare motions are not over-fitted. Why: on the procedural corpus "walks
    forward" outnumbers "walks backwards" 9 to 1 and sidesteps 20 to 1, and an L2M trained
    on it walks forward when asked to walk backwards.
    """
    if max_repeat < 1:
        raise MotionlangError(f"max_repeat must be >= 1, got {max_repeat}")
    missing = [i for i in ids if not labels.get(i)]
    if missing:
        raise DatasetError(f"balancing needs ground-truth primitives (a procedural corpus's "
                           f"_meta.json); {len(missing)} motions have none, e.g. {missing[0]}")
    counts: dict[str, int] = {}
    for i in ids:
        for lab in set(labels[i]):
            counts[lab] = counts.get(lab, 0) + 1
    top = max(counts.values())
    return {i: int(min(max_repeat, round(np.sqrt(top / min(counts[l] for l in labels[i])))))
            for i in ids}


def oversample(items: Sequence[dict], repeats: dict[str, int]) -> list[dict]:
    """``items`` with each item repeated ``repeats[item["id"]]`` times (order kept)."""
    return [it for it in items for _ in range(repeats[it["id"]])]
