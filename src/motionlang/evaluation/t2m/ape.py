"""The ``ape`` protocol of ``evaluate-t2m``: text-to-motion models on a dataset's test
motions, one table (APE/AVE, action order; :func:`~motionlang.evaluation.t2m.compare.compare`)
from the dataset's folder and the models already wrapped."""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from motionlang.datasets.position_items import build_twostream_data
from motionlang.errors import MotionlangError
from motionlang.evaluation.t2m.compare import compare


def evaluate_ape(models: dict[str, Any], data: str | Path | Sequence[str | Path], *,
                 split: str = "test", seed: int = 0, max_seconds: float = 30.0,
                 limit: int | None = None, autoencode: bool = False, true_start: bool = False,
                 oracle: int = 0, out_dir: str | Path | None = None, figures: int = 3
                 ) -> tuple[dict, str]:
    """Evaluate ``{row label: model}`` (each behind ``models.t2m.TextToMotion`` with its
    sampling options) on the ``split`` of ``data`` (a dataset folder or source, split as
    training split it with ``seed``, motions over ``max_seconds`` dropped), at most ``limit``
    motions. ``autoencode``, ``true_start``, ``oracle``, ``out_dir`` (``t2m_table.md``,
    ``t2m_report.json``, ``figures`` trajectory PNGs): as
    :func:`~motionlang.evaluation.t2m.compare.compare`. Returns (results, table).

    Raises:
        MotionlangError: ``autoencode`` without a model that autoencodes (a two-stream
            model), unreadable data, an unknown split.
    """
    if autoencode and not any(m.autoencodes for m in models.values()):
        raise MotionlangError("--autoencode needs a two-stream model among --model")
    dataset = build_twostream_data(data, seed=seed, max_seconds=max_seconds)
    return compare(models, dataset, split=split, limit=limit or None, seed=seed,
                   autoencode=autoencode,
                   out_dir=out_dir, figures=figures, oracle=oracle, true_start=true_start)
