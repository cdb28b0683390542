"""The yardstick's figure: one PNG beside ``evaluate-t2m --protocol guo``'s tables.

Text to motion: R-precision top-3 (higher is better) and FID (lower; log scale, FID spans
0.1 to several hundred) per row; motion to text, when measured: R-precision top-3 of the
descriptions and BLEU@4. Error bars are the tables' 95 % intervals.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from motionlang.utils.atomic import atomic_path


def _values(table: dict[str, dict], measure: str) -> tuple[list[str], np.ndarray, np.ndarray]:
    names, mean, half = [], [], []
    for name, row in table.items():
        v = row.get(measure)
        if v is None:
            continue
        m, h = (v if isinstance(v, (tuple, list)) else (v, 0.0))
        names.append(name)
        mean.append(float(m))
        half.append(float(h))
    return names, np.array(mean), np.array(half)


def plot_yardstick(t2m: dict[str, dict], path: str | Path,
                   m2t: dict[str, dict] | None = None, title: str = "") -> None:
    """Bar charts of :func:`yardstick.guo_table`'s rows (and :func:`m2t.m2t_table`'s) as a
    PNG at ``path`` (atomic write)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    panels = [(t2m, "R-precision top-3", "text -> motion: R-precision top-3", False),
              (t2m, "FID", "text -> motion: FID (log)", True)]
    if m2t:
        panels += [(m2t, "R-precision top-3", "motion -> text: R-precision top-3", False),
                   (m2t, "BLEU@4", "motion -> text: BLEU@4", False)]
    fig = Figure(figsize=(4.2 * len(panels), 3.6), dpi=100)
    FigureCanvasAgg(fig)
    for k, (table, measure, label, log) in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), k + 1)
        names, mean, half = _values(table, measure)
        y = np.arange(len(names))
        ax.barh(y, mean, xerr=half, color="tab:blue" if k < 2 else "tab:green", alpha=0.8)
        ax.set_yticks(y, names, fontsize=8)
        ax.invert_yaxis()
        if log and len(mean) and (mean > 0).all():
            ax.set_xscale("log")
        for yi, m in zip(y, mean):
            ax.text(m, yi, f" {m:.3g}", va="center", fontsize=7)
        ax.set_title(label, fontsize=9)
        ax.grid(axis="x", alpha=0.3)
    if title:
        fig.suptitle(title, fontsize=8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp)
