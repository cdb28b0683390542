"""Every text-to-motion model on the same test sentences, in one table.

For each test motion: one description (the first that states all of its body actions,
else the first), the target = the motion's 21 joints at 12.5 Hz anchored at the origin
facing +Z (``PositionFeatures.decode`` of its features), and each model's generation of the
same length from the same sentence with its own sampling options
(``models.t2m.TextToMotion.positions21``: the two-stream model directly, the seq2seq L2M
through forward kinematics). Columns:

* APE / AVE local (mean of the 20 non-root joints in the body frame) and root (global
  trajectory), **millimetres** (AVE mm^2) after undoing the normalisation
  (``motion_metrics.position_metrics_mm``);
* order accuracy on the compositional items (>= 2 distinct body actions in sequence, the
  sentence stating all of them): the generated motion cut at the ground truth's rescaled
  frame ranges, each segment labelled by its nearest training segment (``action_order``,
  1-NN), compared with the true order. Needs the corpus's ``_meta.json``.
"""
from __future__ import annotations

import math
import textwrap
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.evaluation.action_order import Prototypes, rescale_ranges
from motionlang.evaluation.sampling import stratified_sample
from motionlang.evaluation.t2m.baselines import (
    GROUND_TRUTH,
    NEAREST,
    length_errors,
    retrieval_baseline,
    still_baseline,
)
from motionlang.evaluation.t2m.oracle import oracle_generations, oracle_table
from motionlang.evaluation.t2m.scoring import T2MItem, markdown_table, score_generated
from motionlang.evaluation.t2m.scoring import (  # importable from here, as before
    positions_to_features as positions_to_features,
)
from motionlang.features.frames import motion_frames
from motionlang.features.positions import DEFAULT_FPS as FPS
from motionlang.formats.mmm_model import mmm_skeleton
from motionlang.models.t2m import FPS as T2M_FPS
from motionlang.models.t2m import text_to_motion
from motionlang.utils.atomic import atomic_write
from motionlang.utils.progress import progress


def body_primitives(record) -> list[tuple[str, int, int]]:
    """(action, start, end) at 100 Hz of the record's body primitives, from its meta."""
    return [(p["action"], int(p["start"]), int(p["end"]))
            for p in (getattr(record, "meta", None) or {}).get("primitives", [])
            if p.get("layer", "body") == "body"]


def _stating_sentence(record) -> str:
    """The first description whose stated body actions are the true ones, in order."""
    truth = [a for a, _, _ in body_primitives(record)]
    stated = (getattr(record, "meta", None) or {}).get("annotation_params", [])
    for sentence, params in zip(record.annotations, stated):
        if [p["action"] for p in params if p.get("layer", "body") == "body"] == truth:
            return sentence
    return record.annotations[0]


def _ranges(record, n_frames: int) -> tuple[list[tuple[int, int]], list[str]]:
    """Body-primitive ranges in a sequence of ``n_frames`` 12.5 Hz frames that may be the
    motion's first frames only (``max_frames`` crop): primitives past the end are dropped."""
    prims = body_primitives(record)
    if not prims:
        return [], []
    src = int(getattr(record, "n_frames", 0) or max(e for _, _, e in prims))
    full = max(1, int(np.ceil(src * FPS / float(getattr(record, "fps", 100.0)) - 1e-9)))
    ranges = rescale_ranges([(s, e) for _, s, e in prims], src, max(full, n_frames))
    kept = [(min(a, n_frames - 1), min(b, n_frames), act)
            for (a, b), (act, _, _) in zip(ranges, prims) if a < n_frames]
    return [(a, b) for a, b, _ in kept], [act for _, _, act in kept]


def eval_items(data, split: str = "test", limit: int | None = None, seed: int = 0
               ) -> list[T2MItem]:
    """The evaluation items of a ``datasets.position_items.TwoStreamData`` split; with
    ``limit``, a sample of them drawn with ``seed``, stratified by each motion's first
    ground-truth action where the data has one (``evaluation.sampling``)."""
    ids = list(data.splits[split])
    spans = {rid: _ranges(data.records[rid], len(data.sequences[rid])) for rid in ids}
    labels = [spans[rid][1][0] if spans[rid][1] else None for rid in ids]
    out = []
    for i in stratified_sample(len(ids), limit, labels, seed=seed):
        rid = ids[i]
        rec, seq = data.records[rid], data.sequences[rid]
        ranges, truth = spans[rid]
        out.append(T2MItem(rid, _stating_sentence(rec), data.features.decode(seq),
                           ranges, truth))
    return out


def fit_prototypes(data, split: str = "train", nearest_example: bool = True
                   ) -> Prototypes | None:
    """Action labeller from the split's ground-truth segments (None without meta); by
    default 1-NN over the training segments (``Prototypes`` explains why)."""
    segs = []
    for rid in data.splits[split]:
        seq = data.sequences[rid]
        ranges, truth = _ranges(data.records[rid], len(seq))
        segs += [(a, seq[s:e]) for a, (s, e) in zip(truth, ranges)]
    return Prototypes.fit(segs, nearest_example) if segs else None


def evaluate_model(generate: Callable[[str, int], np.ndarray], items: Sequence[T2MItem],
                   features, prototypes: Prototypes | None) -> dict:
    """Metrics of one model. ``generate(sentence, n_frames) -> (n_frames, 21, 3)``.

    Returns: ``ape_local, ape_root, ave_local, ave_root`` (mm / mm^2), ``order_accuracy``
    (NaN without compositional items), ``n_items``, ``n_compositional`` and
    ``generated`` ({id: positions}).
    """
    if not items:
        raise MotionlangError("no test items to evaluate")
    gen = {it.id: np.asarray(generate(it.sentence, len(it.target)))
           for it in progress(items, desc="generate", unit="sentences")}
    return score_generated(gen, items, features, prototypes)


def trajectory_figures(results: dict[str, dict], items: Sequence[T2MItem], out_dir: str | Path,
                       n: int = 3) -> list[Path]:
    """One top-view PNG per compositional item (the first ``n``): ground truth and every
    model's root path with footsteps (``render.plot_trajectory``)."""
    from motionlang.rendering.trajectory import plot_trajectory
    chosen = [it for it in items if it.compositional][:n] or list(items)[:n]
    paths = []
    for it in chosen:
        path = Path(out_dir) / f"trajectory_{it.id}.png"
        plot_trajectory([it.target] + [r["generated"][it.id] for r in results.values()], path,
                        labels=["ground truth", *results], fps=FPS,
                        title="\n".join(textwrap.wrap(it.sentence, 58)[:3]))
        paths.append(path)
    return paths


def subject_height(record) -> float | None:
    """The subject's height in metres: the corpus meta's, else the motion file's (MMM)."""
    h = ((getattr(record, "meta", None) or {}).get("subject") or {}).get("height_m")
    if h is None:
        h = record.load_motion().meta.get("height")
    return None if h is None else float(h)


def _l2m_on_subjects(results, name, t2m, data, items, protos) -> None:
    """The L2M's counterparts of a true start, two rows: its joint angles drive each test
    subject's own body (``mmm_skeleton`` of the subject's height) instead of the mean
    build; and on that body, its motion also starts with the test motion's first frame in
    its own features (posture and root speed included) and continues from it, which is
    what the two-stream model is told with a true start. Only for angles models; skipped,
    with a log line, when a test motion's height is unknown (an MMM file without one reads
    as the reader's default height, so not for those). The second row needs "mean" or
    "sample" decoding (``t2m``'s options decide, as in its main row)."""
    import logging

    model = t2m.model
    if getattr(getattr(model, "features", None), "kind", None) != "angles":
        return   # a positions L2M has no body to scale: its joints are its output
    heights = {it.id: subject_height(data.records[it.id]) for it in items}
    if any(h is None for h in heights.values()):
        logging.getLogger(__name__).info("%s: no subject heights, no row on their bodies", name)
        return
    rows = {"on the test subject's body": None}
    if getattr(t2m.options, "method", None) == "beam":
        logging.getLogger(__name__).info("%s: the sampled beam takes no first pose, no row "
                                         "from the test motion's first pose", name)
    else:
        rows["from the test motion's first pose, on its body"] = {
            it.id: motion_frames(model.features, data.records[it.id].load_motion())[0][0]
            for it in items}
    for row, firsts in rows.items():
        gen = {it.id: t2m.positions21(
                   it.sentence, len(it.target), skeleton=mmm_skeleton(heights[it.id]),
                   first_frame=None if firsts is None else firsts[it.id]) for it in items}
        results[f"{name}, {row}"] = score_generated(gen, items, data.features, protos)


def compare(models: dict[str, object], data, *, split: str = "test", limit: int | None = None,
            out_dir: str | Path | None = None, figures: int = 3, baseline: bool = True,
            autoencode: bool = False, true_start: bool = False, oracle: int = 0,
            seed: int = 0) -> tuple[dict, str]:
    """Evaluate ``{name: model}`` on ``data`` (``TwoStreamData``). A model is a
    text-to-motion model behind ``models.t2m.TextToMotion`` and decodes with its own
    sampling options (``text_to_motion(model, options)``; a loaded model as it is: its
    default options, an L2M's mean decoding). Extra rows unless ``baseline`` is False: the no-motion baseline
    (``still_baseline``), the nearest-neighbour baseline (``retrieval_baseline``) and the
    ground truth (:data:`GROUND_TRUTH`); with ``autoencode``, each
    two-stream model decoding each test motion from its own pose embedding
    (``TwoStreamModel.reconstruct``); with ``true_start``, each two-stream model
    generating from the sentence but starting at the test motion's first pose, as JL2P and
    Ghosh et al. evaluate (it tells the model the subject's build and posture), each L2M
    model on the test subject's own body, and on it starting with the test motion's
    first frame (``_l2m_on_subjects``), and the no-motion
    baseline holding the test motion's first pose. With ``oracle`` = k > 0, a second table
    (``t2m_oracle.oracle_table``): every row again on the test motions with k training
    motions of the same parameters, beside the oracles; its rows go into the results with
    names prefixed "same-parameter subset: ". With ``out_dir`` also write ``t2m_table.md``,
    ``t2m_report.json`` (with each model's options that differ from the defaults) and the
    trajectory figures. Returns (results, table)."""
    models = {name: text_to_motion(model) for name, model in models.items()}
    items = eval_items(data, split, limit, seed)   # a sample drawn with seed
    protos = fit_prototypes(data)
    if oracle:   # before the models run: a K no test motion meets fails at once
        kept, oracle_gens = oracle_generations(data, items, oracle)
    results = {name: evaluate_model(t2m.positions21, items, data.features, protos)
               for name, t2m in models.items()}
    for name, t2m in models.items():
        _extra_model_rows(results, name, t2m, data, items, protos, autoencode=autoencode,
                          true_start=true_start)
    if baseline:
        _baseline_rows(results, data, items, protos, true_start)
    table = markdown_table(results)
    lengths, length_line = _length_rows(models, data, items)
    table += length_line
    if oracle:
        rows, sub_table = oracle_table(results, data, kept, oracle_gens, len(items), protos)
        results.update({f"same-parameter subset: {k}": r for k, r in rows.items()})
        table += "\n" + sub_table
    if out_dir is not None:
        _write_report(Path(out_dir), table, results, lengths, split,
                      {name: t2m.describe_options() for name, t2m in models.items()})
        if figures:
            # models only: the no-motion baseline is a dot at the origin
            trajectory_figures({k: results[k] for k in models}, items, Path(out_dir), figures)
    return results, table


def _extra_model_rows(results: dict, name: str, t2m, data, items, protos, *,
                      autoencode: bool, true_start: bool) -> None:
    """The rows of :func:`compare`'s ``autoencode`` and ``true_start``, for the models that
    can do them (``TextToMotion.autoencodes``, ``takes_start_pose``,
    ``starts_from_positions``)."""
    if true_start and t2m.takes_start_pose:
        _l2m_on_subjects(results, name, t2m, data, items, protos)
    if autoencode and t2m.autoencodes:
        gen = {it.id: t2m.reconstruct21(it.target) for it in items}
        results[f"{name}, from the motion's own embedding"] = score_generated(
            gen, items, data.features, protos)
    if true_start and t2m.starts_from_positions:
        gen = {it.id: t2m.start_from21(it.sentence, it.target) for it in items}
        results[f"{name}, from the test motion's first pose"] = score_generated(
            gen, items, data.features, protos)


def _baseline_rows(results: dict, data, items, protos, true_start: bool) -> None:
    """No motion, the nearest training motion, and the test motions themselves."""
    results["no motion (mean first pose)"] = evaluate_model(still_baseline(data), items,
                                                            data.features, protos)
    if true_start:
        results["no motion (the test motion's first pose)"] = score_generated(
            {it.id: np.repeat(it.target[:1], len(it.target), axis=0) for it in items},
            items, data.features, protos)
    results[NEAREST] = evaluate_model(retrieval_baseline(data), items, data.features, protos)
    # the test motions themselves: APE 0, and the order check's ceiling (how often the
    # labeller gets true motions right)
    results[GROUND_TRUTH] = score_generated({it.id: it.target for it in items}, items,
                                            data.features, protos)


def _length_rows(models: dict, data, items) -> tuple[dict, str]:
    """Sentence -> length errors of each model's length model (and of one refit on the
    training motions), and the table's line about them."""
    lengths = {"refit on the whole training motions": length_errors(data, items)}
    # models whose length model counts frames at 12.5 Hz (an angles L2M's counts at 10 Hz)
    lengths.update({name: length_errors(data, items, t2m.model.length_model)
                    for name, t2m in models.items()
                    if getattr(t2m.model, "length_model", None) is not None
                    and abs(t2m.fps - T2M_FPS) < 1e-9})
    line = ("\nSentence -> length (what `generate` uses without --max-frames), mean absolute "
            "error in frames at 12.5 Hz: "
            + "; ".join(f"{k} {v['mae_frames']:.1f}" for k, v in lengths.items())
            + f"; always the training mean "
              f"{lengths[next(iter(lengths))]['constant_mae_frames']:.1f}.\n")
    return lengths, line


def _write_report(out: Path, table: str, results: dict, lengths: dict, split: str,
                  options: dict[str, dict]) -> None:
    """``t2m_table.md`` and ``t2m_report.json`` (NaN as null) in ``out``; ``options``: each
    model's sampling options that differ from its family's defaults."""
    import json

    with atomic_write(out / "t2m_table.md") as fh:
        fh.write(table)
    report = {k: {kk: (None if isinstance(vv, float) and math.isnan(vv) else vv)
                  for kk, vv in r.items() if kk != "generated"}
              for k, r in results.items()}
    with atomic_write(out / "t2m_report.json") as fh:
        json.dump({"split": split, "results": report, "length_model": lengths,
                   "options": options}, fh, indent=1)
