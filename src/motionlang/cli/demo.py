"""``motionlang demo``: the main job on :mod:`motionlang.api`, with no download and no shared
data needed.

1. Generate a motion for a sentence with the packaged text-to-motion model (L2M), as
   ``motionlang generate`` does; print its hypotheses with their log likelihoods and write
   the best as an animated GIF, a pose strip and a BVH file.
2. Describe motions with the packaged M2L, as ``motionlang describe`` orders the sentences:
   a procedural-corpus sample made on the fly from a corpus seed the packaged models never
   saw and, when one is at hand, a real motion (``--input FILE``, else KIT-ML 00001 from the
   shared data: ``datasets.named.data_dirs``).
3. Render the real motion: a GIF, a pose strip and a trajectory plot.
"""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from motionlang import api as ml
from motionlang.cli.motion_commands import add_joint_map_arg
from motionlang.cli.options import frames_int, output_dir, seed_int, width_int
from motionlang.datasets import named
from motionlang.datasets.kitml import caption_of
from motionlang.datasets.synth import generate_sample
from motionlang.errors import MotionlangError
from motionlang.library.describe import score_text
from motionlang.models.registry import PACKAGED

DEFAULT_SENTENCE = "a person waves with the left hand"
DEMO_MOTION = Path("kitml") / "00001_mmm.xml"
#: length cap of the generated motion in model frames; the packaged L2M plans the length
#: from the sentence, usually well below
DEMO_MAX_FRAMES = 100
#: the packaged models were trained on corpus seed 0; this seed's samples are unseen
SYNTH_SEED = 2026


def _print_hyps(hyps, label: str) -> None:
    for i, (text, score) in enumerate(hyps, 1):
        print(f"  {i}. {score_text(label, score, '9.2f')}  {text}")


def generate_part(out_dir: Path, sentence: str, *, width: int, seed: int,
                  max_frames: int) -> list[Path]:
    """The packaged L2M's hypotheses for ``sentence`` printed; the best written as
    ``generated.gif``, ``generated_strip.png`` and ``generated.bvh`` in ``out_dir``."""

    t2m = ml.text_to_motion("l2m")
    method = t2m.default_method()
    width = 1 if method == "mean" else width
    # --max-frames caps the length the model plans; a model told its length (the packaged
    # L2M) would generate exactly max_frames
    planned = t2m.frames_for(sentence)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        hyps, fps = ml.generate_hypotheses(
            sentence, t2m, width=width, seed=seed, min_frames=5,
            max_frames=min(planned, max_frames) if planned else max_frames)
    for w in caught:
        print(f"motionlang demo: warning: {w.message}", file=sys.stderr)
    how = "expected frames" if method == "mean" else f"{width} ancestral samples, likeliest first"
    print(f'generate "{sentence}" (L2M, {how}):')
    _print_hyps([(f"{len(m)} frames, {len(m) / fps:.1f} s", s) for m, s in hyps], "log L")
    paths = [out_dir / "generated.gif", out_dir / "generated_strip.png",
             out_dir / "generated.bvh"]
    for path in paths:
        ml.write_result(hyps[0][0], path, fps=fps, title=f'"{sentence}" (L2M #1)')
    return paths


def describe_part(motions: list[tuple[str, object]], width: int) -> None:
    """The packaged M2L's sentences for each (label, Motion), printed; a motion it cannot
    read (a rig no joint map fits) is said to be not described."""

    m2l = ml.load_model("m2l", kind="m2l")
    for label, motion in motions:
        print(f"describe {label} (M2L, beam search, W={width}, as 'motionlang describe' "
              "orders it):")
        try:
            hyps = ml.describe(motion, m2l, width=width)
        except MotionlangError as exc:
            print(f"  (not described: {exc})")
            hyps = []
        _print_hyps(hyps, "log P")


def cmd_demo(args: argparse.Namespace) -> int:

    out_dir = Path(args.out)
    written = generate_part(out_dir, args.sentence, width=args.width, seed=args.seed,
                            max_frames=args.max_frames)
    sample = generate_sample(SYNTH_SEED, 0)
    print(f"procedural sample (seed {SYNTH_SEED}), its reference: {sample.annotations[0]}")
    to_describe = [("a procedural-corpus sample", sample.motion)]
    real = Path(args.input) if args.input else named.find_data_file(DEMO_MOTION)
    if real is not None:
        motion = ml.read_motion(real, skeleton=args.asf, joint_map=args.joint_map)
        caption = caption_of(real)
        if caption:
            print(f"reference of {caption}")
        to_describe.append((str(real), motion))
    else:
        print(f"(no shared data found: the real-motion part is skipped; set "
              f"{named.DATA_ENV} or pass --input FILE)")
    describe_part(to_describe, args.width)
    if real is not None and not args.no_render:
        title = caption or motion.name
        written += [
            ml.render(motion, out_dir / f"{real.stem}.gif", title=title),
            ml.render(motion, out_dir / f"{real.stem}_strip.png", title=title),
            ml.render(motion, out_dir / f"{real.stem}_trajectory.png", trajectory=True,
                      title=f"{motion.name}: root path and footsteps")]
    for name in ("l2m", "m2l"):   # what the results above may be used for
        if not PACKAGED[name].commercial:
            print(f"note: the packaged {name} is {PACKAGED[name].licence}; "
                  f"'motionlang models {name}' shows its card")
    print("written:")
    for path in written:
        print(f"  {path}")
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "demo", help="generate a motion from text and describe motions (packaged models)",
        description="The main job, offline: generate a motion for SENTENCE with the packaged "
                    "L2M model (GIF, pose strip and BVH written; hypotheses printed with log "
                    "likelihoods), describe a procedural-corpus motion and KIT-ML 00001 (when "
                    "the shared data is present) with the packaged M2L model, and render the "
                    "real motion (GIF, pose strip, trajectory plot).")
    p.add_argument("--sentence", default=DEFAULT_SENTENCE,
                   help=f'text to generate a motion for (default: "{DEFAULT_SENTENCE}")')
    p.add_argument("-w", "--width", type=width_int, default=5,
                   help="hypotheses shown (beam width / samples)")
    p.add_argument("--seed", type=seed_int, default=0, help="seed of the sampling")
    p.add_argument("--max-frames", type=frames_int, default=DEMO_MAX_FRAMES,
                   help="length cap of the generated motion in model frames (the model "
                        "plans the length from the sentence, at most this)")
    p.add_argument("--input", default=None, metavar="FILE",
                   help="real motion to describe and render (default: kitml/00001_mmm.xml "
                        "in the shared data, when present)")
    p.add_argument("--asf", default=None, metavar="PATH", help="ASF skeleton of an .amc input")
    add_joint_map_arg(p)
    p.add_argument("--no-render", action="store_true",
                   help="skip rendering the real motion (the generated one is always rendered)")
    p.add_argument("--out", default="out/demo", metavar="DIR", type=output_dir,
                   help="output folder (default: out/demo, as the README says)")
    p.set_defaults(func=cmd_demo)
