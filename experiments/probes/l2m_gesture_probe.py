"""Why does an L2M not start a procedural wave? (docs/results/real-motion.md, eighth session)

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/l2m_gesture_probe.py \
        --motion CORPUS/00030_mmm.xml --text "a woman waves with the right hand" \
        [--model l2m] [--feature RW_y] [--frame 20] [--bandai TAKE.bvh --bandai-text TEXT]

For one motion and its sentence (normalised features, every 4th frame):
1. the expected value of ``--feature`` teacher forced on the true frames with the motion's
   own plan; fed the first frame at every step instead; with a zero plan; with the plan the
   model's planner makes from the sentence; and the true values, beside the plan's parts;
2. at ``--frame``, each mixture component's weight, mean and standard deviation of it;
3. generated (21-joint body, metres): the named feature's joint at its highest, with mean
   decoding, with ancestral sampling at temperature 1 and 0.5, and with the expected frames
   written while a tempered draw (0.5, 1) is fed back.
With ``--bandai``, step 1 and 2 for that take too (e.g. a Bandai wave, which the packaged L2M
follows). The packaged ``l2m`` is CC BY-NC 4.0 (Bandai data).
"""
from __future__ import annotations

import argparse

import numpy as np
import torch


def _expected(params) -> torch.Tensor:
    """The expected frames (T, F) of one motion's params (1, T, ...)."""
    from motionlang.models.seq2seq.mdn import mixture_mean
    return mixture_mean(params.flatten())


def teacher_forced(m, path: str, text: str, j: int, frame: int) -> None:
    import motionlang as ml
    from motionlang.models.seq2seq.decode.search import encode_sentence, motion_frames
    from motionlang.models.seq2seq.l2m import _previous_frames
    x = torch.as_tensor(motion_frames(m.features, ml.read_motion(path), 1)[0])[None]
    T = x.shape[1]
    ids = encode_sentence(m.vocab, text)
    tok, tl, n = torch.tensor([ids]), torch.tensor([len(ids)]), torch.tensor([T])
    plan = m.plan_target(x, n)
    prev = _previous_frames(x)
    print(f"{path} ({T} frames), {text!r}: feature {m.features.names[j]}, normalised, "
          "every 4th frame")
    cases = (("true plan, true frames", plan, prev),
             # the motion's first frame at every step (prev[:, 0] is the zero start frame)
             ("true plan, first frame fed", plan, x[:, :1].expand_as(prev)),
             ("zero plan, true frames", torch.zeros_like(plan), prev),
             ("sentence's plan, true frames", None, prev))
    with torch.no_grad():
        for name, p, pv in cases:
            params, _ = m._decode(m.encode(tok, tl, n, p), pv)
            print(f"  {name:30s}", _expected(params)[::4, j].numpy().round(1))
            if name.startswith("true plan, true"):
                at = params
    print(f"  {'true':30s}", x[0, ::4, j].numpy().round(1))
    print(f"  {'plan parts (means)':30s}", plan[0, :, j].numpy().round(1))
    w = torch.softmax(at.logit_pi[0, frame], -1).numpy()
    print(f"  frame {frame}: weights {w.round(3)}, means "
          f"{at.mu[0, frame, :, j].numpy().round(2)}, deviations "
          f"{at.log_sigma[0, frame, :, j].exp().numpy().round(2)}")


def generated(m, t2m, text: str, joint: int) -> None:
    import motionlang.models.seq2seq.decode.motion_beam as mb
    import motionlang.models.seq2seq.decode.search as s2s
    from motionlang.models.seq2seq.mdn import mixture_mean, sample
    plain = mb.mean_decode

    def rows(label, **kw):
        p = t2m.hypotheses(text, width=1, seed=0, max_frames=60, **kw)[0][0]
        print(f"  {label:40s} highest {p[:, joint, 1].max():.2f} m")

    print(f"generated, {text!r}, joint {joint} of the 21-joint body:")
    rows("mean decoding", method="mean")
    for tau in (1.0, 0.5):
        rows(f"ancestral sampling, temperature {tau}", method="sample", temperature=tau)
    for tau in (0.5, 1.0):
        def fed_draw(step, state, *, batch_size, max_frames, dim=None, min_frames=1,
                     threshold=0.5, first=None, tau=tau, **_):
            g = torch.Generator().manual_seed(0)
            prev, out = mb._start(None, batch_size, dim), []
            for t in range(max_frames):
                params, state = step(state, prev)
                out.append(mixture_mean(params)[0])
                if t >= min_frames - 1 and not bool(
                        (torch.sigmoid(params.active_logit) >= threshold).all()):
                    break
                prev = sample(params, 1, g, tau)[0][:, 0]
            return [mb.MotionHypothesis(torch.stack(out).numpy(), 0.0)]
        s2s.mean_decode = fed_draw
        try:
            rows(f"expected frames written, draw fed (tau {tau})", method="mean")
        finally:
            s2s.mean_decode = plain


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--motion", required=True)
    ap.add_argument("--text", required=True)
    ap.add_argument("--model", default="l2m")
    ap.add_argument("--feature", default="RW_y")
    ap.add_argument("--frame", type=int, default=20)
    ap.add_argument("--bandai")
    ap.add_argument("--bandai-text", default="a person waves with the right hand")
    args = ap.parse_args()
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.features.joint_map import KIT21_NAMES
    t2m = ml.text_to_motion(args.model)
    m = t2m.model.eval()
    j = m.features.names.index(args.feature)
    teacher_forced(m, args.motion, args.text, j, args.frame)
    if args.bandai:
        teacher_forced(m, args.bandai, args.bandai_text, j, args.frame)
    generated(m, t2m, args.text, KIT21_NAMES.index(args.feature.split("_")[0]))


if __name__ == "__main__":
    np.set_printoptions(linewidth=120)
    main()
