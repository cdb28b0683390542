"""``motionlang demo``: the main job, with no download and no shared data needed.

1. Generate a motion for a sentence with the packaged language-to-motion model (L2M) and
   write it as an animated GIF, a pose strip and a BVH file; print its log likelihood
   (W ancestral samples, likeliest first, for models that decode by sampling).
2. Describe a motion with the packaged motion-to-language model (M2L): a procedural-corpus
   sample generated on the fly (from a corpus seed the packaged models never saw) and,
   when the shared data is present, KIT-ML motion 00001; print the W beam hypotheses with
   their log probabilities.
3. When a real motion is available (``--input FILE`` or KIT-ML 00001 from the shared data
   folder: ``$MOTIONLANG_DATA``, else ``../shared/data`` relative to the current folder,
   else next to the package's source checkout), render it to a GIF, a pose strip and a
   trajectory plot as well.
"""
from __future__ import annotations

import argparse
import os
import re
from pathlib import Path

from motionlang.cli.options import frames_int, output_dir, seed_int, width_int
from motionlang.errors import MotionlangError

DATA_ENV = "MOTIONLANG_DATA"
DEMO_MOTION = Path("kitml") / "00001_mmm.xml"


def data_dirs() -> list[Path]:
    """Candidate shared-data folders, most specific first."""
    dirs = []
    if os.environ.get(DATA_ENV):
        dirs.append(Path(os.environ[DATA_ENV]).expanduser())
    dirs.append(Path.cwd().parent / "shared" / "data")
    dirs.append(Path.cwd() / "shared" / "data")
    checkout = Path(__file__).resolve().parents[3]  # <root>/src/motionlang/cli/demo.py
    dirs.append(checkout.parent / "shared" / "data")
    return dirs


def find_demo_motion() -> Path | None:
    """The demo's real motion in the first data folder that has it, else None."""
    for d in data_dirs():
        if (d / DEMO_MOTION).is_file():
            return d / DEMO_MOTION
    return None


def kit_caption(motion_path: Path) -> str | None:
    """"KIT-ML 00001: A person is walking forwards." for ``NNNNN_mmm.xml`` when TMR's
    annotation file lies beside it; None otherwise (a caption is a nicety, not a need)."""
    m = re.fullmatch(r"(\d{5})_mmm", motion_path.stem)
    ann = motion_path.parent / "annotations_tmr.json"
    if not m or not ann.is_file():
        return None
    from motionlang.datasets.kitml import load_annotations_tmr

    try:
        texts = load_annotations_tmr(ann).get(m.group(1), {}).get("texts") or []
    except MotionlangError:
        return None
    return f"KIT-ML {m.group(1)}: {texts[0]}" if texts else None


def run_demo(input_path: str | Path | None, out_dir: str | Path, *, asf: str | None = None,
             n_poses: int = 8, joint_map: str | Path | None = None) -> list[Path]:
    """Render ``input_path`` (default: the KIT demo motion) into ``out_dir``.

    Returns:
        the files written: ``<name>.gif``, ``<name>_strip.png``, ``<name>_trajectory.png``.

    Raises:
        MotionlangError: no input given and no shared data found, or an unreadable input.
    """
    from motionlang.formats import read_motion
    from motionlang.rendering import plot_trajectory, render_animation, render_strip

    if input_path is None:
        input_path = find_demo_motion()
        if input_path is None:
            looked = ", ".join(str(d) for d in data_dirs())
            raise MotionlangError(
                f"no demo motion found ({DEMO_MOTION} not in {looked}); pass a motion file "
                f"with 'motionlang demo --input FILE' (.xml, .bvh or .amc) or set {DATA_ENV} "
                "to the folder that holds kitml/00001_mmm.xml")
    input_path = Path(input_path)
    motion = read_motion(input_path, skeleton=asf, joint_map=joint_map)
    out_dir = Path(out_dir)
    stem = input_path.stem
    title = kit_caption(input_path) or motion.name
    written = [
        render_animation(motion, out_dir / f"{stem}.gif", title=title),
        render_strip(motion, out_dir / f"{stem}_strip.png", n_frames=n_poses, title=title),
        plot_trajectory(motion, out_dir / f"{stem}_trajectory.png",
                        title=f"{motion.name}: root path and footsteps"),
    ]
    return written


# ------------------------------------------------------------------ the main job
DEFAULT_SENTENCE = "a person waves with the left hand"
#: Length cap of the demo's generated motion, in model frames (10 Hz, so 10 s); the
#: packaged L2M plans its length from the sentence (its length model), usually well below.
DEMO_MAX_FRAMES = 100
#: The packaged models were trained on corpus seed 0; this seed's samples are unseen.
SYNTH_SEED = 2026


def _print_hyps(echo, hyps, label: str) -> None:
    for i, (text, score) in enumerate(hyps, 1):
        echo(f"  {i}. {label} = {score:9.2f}  {text}")


def generate_part(out_dir: Path, sentence: str, *, width: int = 5, seed: int = 0,
                  max_frames: int | None = DEMO_MAX_FRAMES,
                  model_path: str | Path | None = None, echo=print) -> list[Path]:
    """L2M: ``sentence`` -> W motions; the best one written as GIF, strip PNG and BVH.

    max_frames: length cap in model frames (None: the model's own cap).
    """
    from motionlang.decoding.seq2seq import generate
    from motionlang.decoding.t2m import default_method
    from motionlang.formats import write_motion
    from motionlang.models.registry import load_model
    from motionlang.rendering import render_animation, render_strip
    from motionlang.rendering.output import body_motion

    model = load_model(model_path or "l2m", kind="l2m")
    # as `motionlang generate` does: expected frames for joint-position models (a draw
    # stretches bones), ancestral samples otherwise (the sampled beam keeps the likeliest
    # frames, and standing still is always likelier than moving)
    method = default_method(model)
    width = 1 if method == "mean" else width
    hyps = generate(model, sentence, width=width, seed=seed, min_frames=5,
                    max_frames=max_frames, method=method)
    how = "expected frames" if method == "mean" else f"{width} ancestral samples, likeliest first"
    echo(f'generate "{sentence}" (L2M, {how}):')
    fps = model.features.fps
    _print_hyps(echo, [(f"{len(m)} frames, {len(m) / fps:.1f} s", s) for m, s in hyps], "log L")
    # position features decode to 21 joints: joint angles fitted to them for the BVH
    best = body_motion(hyps[0][0], fps, name="generated")[0]
    title = f'"{sentence}" (L2M #1)'
    stem = out_dir / "generated"
    written = [render_animation(best, stem.with_suffix(".gif"), title=title),
               render_strip(best, out_dir / "generated_strip.png", title=title)]
    write_motion(best, stem.with_suffix(".bvh"))
    written.append(stem.with_suffix(".bvh"))
    return written


def describe_part(motions: list[tuple[str, object]], *, width: int = 5,
                  model_path: str | Path | None = None, echo=print) -> list[list]:
    """M2L: each (label, Motion) -> W sentences with log P, printed; returns the lists
    (empty for a motion the model's feature set cannot read, e.g. a non-MMM skeleton)."""
    from motionlang.decoding.seq2seq import describe
    from motionlang.models.registry import load_model

    model = load_model(model_path or "m2l", kind="m2l")
    out = []
    for label, motion in motions:
        echo(f"describe {label} (M2L, beam search, W={width}, as 'motionlang describe' "
             "orders it):")
        try:
            hyps = describe(model, motion, width=width, rank="mbr")
        except MotionlangError as exc:  # e.g. a rig no joint map fits
            echo(f"  (not described: {exc})")
            hyps = []
        _print_hyps(echo, hyps, "log P")
        out.append(hyps)
    return out


def synth_motion(index: int = 0):
    """A procedural sample unseen in training: (Motion, its reference sentences)."""
    from motionlang.datasets.synth import generate_sample

    sample = generate_sample(SYNTH_SEED, index)
    return sample.motion, sample.annotations


def run_main_job(out_dir: str | Path, *, sentence: str = DEFAULT_SENTENCE, width: int = 5,
                 seed: int = 0, max_frames: int | None = DEMO_MAX_FRAMES,
                 input_path: str | Path | None = None, asf: str | None = None,
                 render_real: bool = True, m2l: str | Path | None = None,
                 l2m: str | Path | None = None, joint_map: str | Path | None = None,
                 echo=print) -> list[Path]:
    """The whole demo (see the module docstring); returns the files written."""
    from motionlang.formats import read_motion

    out_dir = Path(out_dir)
    written = generate_part(out_dir, sentence, width=width, seed=seed, max_frames=max_frames,
                            model_path=l2m, echo=echo)
    motion, refs = synth_motion()
    echo(f"procedural sample (seed {SYNTH_SEED}), its reference: {refs[0]}")
    to_describe = [("a procedural-corpus sample", motion)]
    real = Path(input_path) if input_path else find_demo_motion()
    if real is not None:
        real_motion = read_motion(real, skeleton=asf, joint_map=joint_map)
        caption = kit_caption(real)
        if caption:
            echo(f"reference of {caption}")
        to_describe.append((str(real), real_motion))
    else:
        echo("(no shared data found: the real-motion part is skipped; "
             f"set {DATA_ENV} or pass --input FILE)")
    describe_part(to_describe, width=width, model_path=m2l, echo=echo)
    if real is not None and render_real:
        written += run_demo(real, out_dir, asf=asf, joint_map=joint_map)
    return written


def cmd_demo(args: argparse.Namespace) -> int:
    written = run_main_job(args.out, sentence=args.sentence, width=args.width, seed=args.seed,
                           max_frames=args.max_frames, input_path=args.input, asf=args.asf,
                           render_real=not args.no_render, joint_map=args.joint_map)
    from motionlang.models.registry import PACKAGED
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
                   help=f"length cap of the generated motion in 10 Hz frames "
                        f"(default {DEMO_MAX_FRAMES})")
    p.add_argument("--input", default=None, metavar="FILE",
                   help="real motion to describe and render (default: kitml/00001_mmm.xml "
                        "in the shared data, when present)")
    p.add_argument("--asf", default=None, metavar="PATH", help="ASF skeleton of an .amc input")
    from motionlang.cli.motion_commands import add_joint_map_arg
    add_joint_map_arg(p)
    p.add_argument("--no-render", action="store_true",
                   help="skip rendering the real motion (the generated one is always rendered)")
    p.add_argument("--out", default="out/demo", metavar="DIR", type=output_dir,
                   help="output folder (default: out/demo, as the README says)")
    p.set_defaults(func=cmd_demo)
