"""Pictures of the fill-in experiment: true vs filled joint angles (the paper's Figure 4)
and an animation of the true and the CRBM-filled motion side by side."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from motionlang.evaluation.crbm.fill import JOINT_CHANNELS
from motionlang.utils.atomic import atomic_path

# 59-space index -> readable name, for the dimensions the plots show (ASF 35 channel names).
_ASF_CHANNELS = (["root tx", "root ty", "root tz", "root rx", "root ry", "root rz"]
                 + [f"{b} r{a}" for b, dofs in [
                     ("lfemur", "xyz"), ("ltibia", "x"), ("lfoot", "xz"), ("ltoes", "x"),
                     ("rfemur", "xyz"), ("rtibia", "x"), ("rfoot", "xz"), ("rtoes", "x"),
                     ("lowerback", "xyz"), ("upperback", "xyz"), ("thorax", "xyz"),
                     ("lowerneck", "xyz"), ("upperneck", "xyz"), ("head", "xyz"),
                     ("lclavicle", "yz"), ("lhumerus", "xyz"), ("lradius", "x"), ("lwrist", "y"),
                     ("lhand", "xz"), ("lfingers", "x"), ("lthumb", "xz"),
                     ("rclavicle", "yz"), ("rhumerus", "xyz"), ("rradius", "x"), ("rwrist", "y"),
                     ("rhand", "xz"), ("rfingers", "x"), ("rthumb", "xz")] for a in dofs])


def dim_name(dim59: int) -> str:
    """Readable name of a joint dimension of the 59-value frame (index >= 9)."""
    return _ASF_CHANNELS[JOINT_CHANNELS[dim59 - 9]] if dim59 >= 9 else f"root value {dim59}"


def plot_fill(result: dict, path: str | Path, dims59: list[int] | None = None,
              title: str | None = None) -> Path:
    """Plot true vs filled angles (degrees) over the frames of one fill-in.

    ``result`` is what :func:`crbm_reproduce.fill_trial` returns. Shown per dimension: the
    truth, the mean of the CRBM repeats with one individual repeat, AR(n) and hold-last-value;
    a vertical line marks where the gap starts. Default dimensions: the first three erased.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dims59 = list(result["erased_dims59"][:3]) if dims59 is None else dims59
    true = result["true59"]
    fills = result["filled59"]
    t = np.arange(len(true))
    fig, axes = plt.subplots(len(dims59), 1, figsize=(7, 2.2 * len(dims59)), sharex=True,
                             squeeze=False)
    for ax, d in zip(axes[:, 0], dims59):
        ax.plot(t, true[:, d], "k-", lw=2, label="true")
        if len(fills["CRBM"]) > 1:   # sampled fill-ins: one of them and their mean
            ax.plot(t, fills["CRBM"][0][:, d], "-", color="tab:red", lw=0.7, alpha=0.6,
                    label="CRBM (one repeat)")
        ax.plot(t, fills["CRBM"].mean(axis=0)[:, d], "-", color="tab:red", lw=1.5,
                label="CRBM (mean of repeats)" if len(fills["CRBM"]) > 1 else "CRBM")
        ax.plot(t, fills["AR(n)"][:, d], "--", color="tab:blue", lw=1, label="AR(n)")
        ax.plot(t, fills["hold last value"][:, d], ":", color="tab:gray", lw=1, label="hold last")
        ax.axvline(result["gap_start"], color="k", lw=0.5)
        ax.set_ylabel(f"{dim_name(d)} (deg)")
    axes[0, 0].legend(fontsize=7, ncol=3, loc="upper left")
    axes[-1, 0].set_xlabel("frame (30 Hz); gap from the vertical line to the end")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90)
    plt.close(fig)
    return path
