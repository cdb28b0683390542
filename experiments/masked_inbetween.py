"""Filling in lost motion: a masked-token model's text-conditioned in-betweening against
linear interpolation and a CRBM fill-in (Taylor et al. 2006) on held-out Bandai takes
(docs/results/masked.md).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/masked_inbetween.py --model runs/masked \
        [--data ../shared/data/bandai] [--gaps 2 4] [--limit 100] [--crbm-takes 200] \
        [--drafts N] [--figure runs/masked_inbetween.png]

Each Bandai test take at least ``gap + 2`` seconds long loses the ``gap`` seconds at its
middle; each method fills them: ``linear`` (every joint on a straight line between the
frames around the gap), ``crbm`` (a CRBM over the model's normalised 21-joint position rows,
trained here on ``--crbm-takes`` training takes, filling the gap frame by frame; its
global path joined to the kept frames as the masked model's is) and ``masked`` (the model,
told the take's sentence, regenerates the tokens of the gap: one draft, the best of its
``drafts`` drafts (the one that arrives closest to the frames after the gap), and that one
with its feet locked). Prints, per gap length, the mean joint position error over the gap
frames (mm, global positions) and the foot skating (m/s) over the gap and the frame on
each side, with the real takes' skating over the same frames. ``--figure``: the root's
progress along the take's direction, the right toe's speed over the floor and its height,
real and filled, of the take that travels furthest through a gap of the first length.
About 5 minutes with the defaults on one core. Non-commercial: Bandai data (CC BY-NC 4.0).
"""
from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def gap_cases(test: list, n_gap: int, fps: float, limit: int, seed: int):
    """The test takes at least ``n_gap`` frames + 2 s long (``limit`` > 0: that many drawn
    with ``seed``, in order; the takes are ordered by content), each with its middle
    ``n_gap`` frames cut: yields ``(index, positions (T, 21, 3), first gap frame, kept
    frames (T,) bool, the gap and a frame either side as a slice)``."""
    import numpy as np
    takes = [i for i, it in enumerate(test) if len(it.positions) >= n_gap + round(2 * fps)]
    if limit:
        takes = sorted(np.random.default_rng(seed).permutation(takes)[:limit])
    for i in takes:
        p21 = test[i].positions
        a = (len(p21) - n_gap) // 2
        keep = np.ones(len(p21), dtype=bool)
        keep[a:a + n_gap] = False
        yield i, p21, a, keep, slice(a - 1, a + n_gap + 1)


def test_takes(model_spec: str, data: str):
    """The masked model (loaded, one torch thread), its sampling options, and the Bandai test
    takes at its frame rate with one sentence each (seed 0): what the in-betweening
    experiments of this folder share. Returns ``(model, options, takes, sentences)``."""
    import torch
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    model = ml.load_model(model_spec, kind="masked")
    return (model, ml.text_to_motion(model).options,
            bandai_items(data, "test", fps=model.fps), bandai_sentences(data, "test", seed=0))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--model", required=True, help="a masked model (file or run folder)")
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    p.add_argument("--gaps", type=float, nargs="+", default=[2.0, 4.0])
    p.add_argument("--limit", type=int, default=100, help="test takes per gap (0: all)")
    p.add_argument("--crbm-takes", type=int, default=200)
    p.add_argument("--crbm-epochs", type=int, default=30)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--figure", default=None)
    p.add_argument("--drafts", type=int, default=None, help="drafts of the masked rows "
                                                             "(default: the model's option)")
    args = p.parse_args()

    from dataclasses import replace

    import numpy as np
    import torch
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.evaluation.metrics.physics import foot_skating
    from motionlang.features.joint_map import KIT21_NAMES
    from motionlang.features.positions import positions_to_rows
    from motionlang.models.crbm.config import CRBMConfig
    from motionlang.models.crbm.model import CRBM
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.masked.inbetween import blend, linear_fill

    model = ml.load_model(args.model, kind="masked")
    fps, feats = model.fps, model.features
    t2m = ml.text_to_motion(model)
    if args.drafts is not None:
        t2m.options = replace(t2m.options, drafts=args.drafts)
    test = bandai_items(args.data, "test", fps=fps)
    sentences = bandai_sentences(args.data, "test", seed=0)
    rng = np.random.default_rng(args.seed)
    train = bandai_items(args.data, "train", fps=fps)
    pick = rng.choice(len(train), min(args.crbm_takes, len(train)), replace=False)
    rows = [feats.encode_positions(train[i].positions).astype(np.float64) for i in pick]
    crbm = CRBM(CRBMConfig(n_hidden=150, order=3, epochs=args.crbm_epochs, batch_size=100,
                           seed=args.seed), rows[0].shape[1]).fit(rows)
    print(f"CRBM on {len(rows)} training takes ({sum(map(len, rows))} frames), "
          f"{args.crbm_epochs} epochs")

    def crbm_fill(p21: np.ndarray, keep: np.ndarray) -> np.ndarray:
        r = feats.encode_positions(p21).astype(np.float64)
        known = np.repeat(keep[:, None], r.shape[1], axis=1)
        filled = crbm.fill_in(r, known, seed=args.seed).reshape(r.shape)
        gen = feats.decode(filled, positions_to_rows(p21[:1])[1], pin_root=True)
        return blend(gen, p21, keep)

    methods = {"linear": lambda p21, keep, s: linear_fill(p21, keep),
               "crbm": lambda p21, keep, s: crbm_fill(p21, keep),
               "masked, one draft": lambda p21, keep, s: model.inbetween(
                   s, p21, keep, seed=args.seed, options=replace(t2m.options, drafts=1)),
               "masked": lambda p21, keep, s: model.inbetween(s, p21, keep, seed=args.seed,
                                                              options=t2m.options),
               "masked, feet locked": lambda p21, keep, s: model.inbetween(
                   s, p21, keep, seed=args.seed, options=t2m.options, foot_lock=True)}
    shown = None
    TOE = KIT21_NAMES.index("RF")
    print(f"\n{len(test)} Bandai test takes, model {args.model}, options "
          f"{t2m.describe_options() or 'default'}\n")
    print("| gap | takes | method | joint error in the gap (mm) | skating (m/s) | "
          "real takes' skating there |")
    print("|---|---|---|---|---|---|")
    for gap in args.gaps:
        n_gap = round(gap * fps)
        err = {m: [] for m in methods}
        skate = {m: [] for m in methods}
        real_skate = []
        cases = list(gap_cases(test, n_gap, fps, args.limit, args.seed))
        for i, p21, a, keep, span in cases:
            real_skate.append(foot_skating(p21[span], fps))
            outs = {name: fill(p21, keep, sentences[i].text) for name, fill in methods.items()}
            for name, out in outs.items():
                err[name].append(1000 * np.linalg.norm(out[~keep] - p21[~keep], axis=-1).mean())
                skate[name].append(foot_skating(out[span], fps))
            # the figure shows the first gap's take that travels furthest through its gap
            travel = float(np.linalg.norm(p21[a + n_gap - 1, 0, [0, 2]] - p21[a, 0, [0, 2]]))
            if gap == args.gaps[0] and (shown is None or travel > shown[0]):
                shown = (travel, i, keep, outs)
        for name in methods:
            print(f"| {gap:g} s | {len(cases)} | {name} | {np.mean(err[name]):.1f} | "
                  f"{np.nanmean(skate[name]):.3f} | {np.nanmean(real_skate):.3f} |")
    if args.figure and shown is not None:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        _, i, keep, outs = shown
        real = test[i].positions
        fig, ax = plt.subplots(1, 3, figsize=(14, 4))
        t = np.arange(len(real)) / fps
        ahead = real[-1, 0, [0, 2]] - real[0, 0, [0, 2]]   # the take's overall direction
        ahead = ahead / max(float(np.linalg.norm(ahead)), 1e-9)
        for name, out in {"real": real, **outs}.items():
            ax[0].plot(t, out[:, 0, [0, 2]] @ ahead, label=name)
            speed = np.linalg.norm(np.diff(out[:, TOE, :][:, [0, 2]], axis=0), axis=-1) * fps
            ax[1].plot(t[1:], speed, label=name)
            ax[2].plot(t, out[:, TOE, 1], label=name)
        for a in ax:   # the gap shaded, a second of kept frames either side
            a.axvspan(t[~keep][0], t[~keep][-1], color="0.9")
            a.set_xlim(t[~keep][0] - 1.0, t[~keep][-1] + 1.0)
        ax[0].set(title=f"root along the take's direction (m)\n{sentences[i].text}",
                  xlabel="s")
        ax[1].set(title="right toe's speed over the floor (m/s)", xlabel="s")
        ax[2].set(title="right toe height (m); the gap shaded", xlabel="s")
        ax[0].legend(loc="lower right", fontsize=8)
        fig.tight_layout()
        fig.savefig(args.figure, dpi=90)
        print(f"\n{args.figure}")


if __name__ == "__main__":
    main()
