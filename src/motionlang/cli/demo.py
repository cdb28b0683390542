"""``motionlang demo``: render a real motion to an animated GIF, a pose strip and a
trajectory plot — the quickest way to see that reading, kinematics and rendering work.

The motion is ``--input FILE`` or, by default, KIT-ML motion 00001 ("A person is walking
forwards.") from the shared data folder: ``$MOTIONLANG_DATA``, else ``../shared/data``
relative to the current folder, else next to the package's source checkout.
"""
from __future__ import annotations

import argparse
import os
import re
from pathlib import Path

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
             n_poses: int = 8) -> list[Path]:
    """Render ``input_path`` (default: the KIT demo motion) into ``out_dir``.

    Returns:
        the files written: ``<name>.gif``, ``<name>_strip.png``, ``<name>_trajectory.png``.

    Raises:
        MotionlangError: no input given and no shared data found, or an unreadable input.
    """
    from motionlang.formats import read_motion
    from motionlang.render import plot_trajectory, render_animation, render_strip

    if input_path is None:
        input_path = find_demo_motion()
        if input_path is None:
            looked = ", ".join(str(d) for d in data_dirs())
            raise MotionlangError(
                f"no demo motion found ({DEMO_MOTION} not in {looked}); pass a motion file "
                f"with 'motionlang demo --input FILE' (.xml, .bvh or .amc) or set {DATA_ENV} "
                "to the folder that holds kitml/00001_mmm.xml")
    input_path = Path(input_path)
    if asf is not None:
        motion = read_motion(input_path, skeleton=asf)
    else:
        motion = read_motion(input_path)
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


def cmd_demo(args: argparse.Namespace) -> int:
    for path in run_demo(args.input, args.out, asf=args.asf):
        print(path)
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "demo", help="render a real motion (GIF, pose strip, trajectory plot)",
        description="Render KIT-ML motion 00001 (or --input FILE) to an animated GIF, a PNG "
                    "strip of poses and a PNG trajectory plot, and print their paths.")
    p.add_argument("--input", default=None, metavar="FILE",
                   help="motion to render (default: kitml/00001_mmm.xml in the shared data)")
    p.add_argument("--asf", default=None, metavar="PATH", help="ASF skeleton of an .amc input")
    p.add_argument("--out", default="out/demo", metavar="DIR",
                   help="output folder (default: out/demo, as the README says)")
    p.set_defaults(func=cmd_demo)
