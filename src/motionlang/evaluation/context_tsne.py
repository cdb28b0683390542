"""Context vectors of the seq2seq models and their t-SNE map (Plappert et al. 2018, Fig. 9).

The encoder's context vector is all the decoder knows about its input; a map in which
motions of one type cluster shows that the encoder separates them. t-SNE is
scikit-learn's (``sklearn.manifold.TSNE``), an optional dependency imported on use.
"""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch

from motionlang.errors import MotionlangError
from motionlang.models.seq2seq.decode.codec import encode_sentence, normalize
from motionlang.utils.atomic import atomic_path


@torch.no_grad()
def m2l_contexts(model, features: Sequence[np.ndarray]) -> np.ndarray:
    """Raw motion features, each (T_i, F) -> context vectors (N, C) of the M2L encoder."""
    model.eval()
    out = []
    for f in features:
        x = torch.as_tensor(normalize(model.normalizer, f), dtype=torch.float32)[None]
        out.append(model.encode(x, torch.tensor([len(f)]))["context"][0].numpy())
    return np.stack(out)


@torch.no_grad()
def l2m_contexts(model, sentences: Sequence[str]) -> np.ndarray:
    """Sentences -> context vectors (N, C) of the L2M encoder."""
    model.eval()
    out = []
    for s in sentences:
        ids = encode_sentence(model.vocab, s)
        out.append(model.encode(torch.tensor([ids]), torch.tensor([len(ids)]))["context"][0]
                   .numpy())
    return np.stack(out)


def tsne_2d(vectors: np.ndarray, seed: int = 0) -> np.ndarray:
    """(N, C) -> (N, 2) t-SNE embedding (perplexity capped for small N)."""
    from sklearn.manifold import TSNE

    if len(vectors) < 4:
        raise MotionlangError(f"t-SNE needs at least 4 points, got {len(vectors)}")
    perplexity = float(min(30.0, max(1.0, (len(vectors) - 1) / 3)))
    return TSNE(2, perplexity=perplexity, random_state=seed, init="pca").fit_transform(
        np.asarray(vectors, dtype=np.float64))


def plot_context_tsne(panels: dict[str, tuple[np.ndarray, Sequence[str]]], path: str | Path,
                      seed: int = 0) -> Path:
    """One scatter panel per model: title -> (context vectors (N, C), N type labels)."""
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib import pyplot as plt


    fig, axes = plt.subplots(1, len(panels), figsize=(5.5 * len(panels), 5), squeeze=False)
    for ax, (title, (vec, labels)) in zip(axes[0], panels.items()):
        xy = tsne_2d(vec, seed)
        labels = np.asarray(labels)
        cmap = plt.get_cmap("tab20")
        for k, name in enumerate(sorted(set(labels))):
            sel = labels == name
            ax.scatter(xy[sel, 0], xy[sel, 1], s=10, color=cmap(k % 20), label=name)
        ax.set_title(title)
        ax.set_xticks([])
        ax.set_yticks([])
    axes[0][-1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5))
    fig.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, format=path.suffix.lstrip(".") or "png")
    plt.close(fig)
    return path
