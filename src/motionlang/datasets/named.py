"""Named small datasets of the CRBM papers: CMU subject 35 walk/jog and MIT walking.

Both ship as MATLAB files (see ``shared/data/README.md``):

* ``cmu35/cmu35WalkJog.mat`` (GPmat packaging of CMU subject 35, the data of Taylor, Hinton
  & Roweis 2006): AMC channels in degrees at 30 Hz. ``Y`` (2644 x 62) concatenates 31
  training trials (35_01-17, 19-26, 28, 30-34), ``lbls`` (2644 x 31) marks trial
  membership; ``Ytest`` (169 x 62) is 35_18 then 35_29, ``lblstest`` (169 x 2).
* ``mit/motion.mat``: Hsu, Pulli & Popovic 2005 walking as in Taylor's CRBM code.

Walk/jog labels of subject 35. Source: the data README states 35_18 is a jog and 35_29 a
walk; CMU lists subject 35 as "walk, run". The remaining labels follow from the trials
themselves: at 30 Hz trials 35_17-35_26 last 35-44 frames (one pass of the capture volume
at jogging speed) while all other trials last 90-125 frames (the same distance walked),
a two-to-one gap with no trial in between; ``test_named_datasets`` checks this.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motionlang.errors import DatasetError
from motionlang.formats.asf_amc import motion_from_channels, read_asf
from motionlang.formats.mit import read_mit
from motionlang.kinematics import Motion

DATA_ENV = "MOTIONLANG_DATA"
CMU35_FPS = 30.0
CMU35_TRAIN_TRIALS = tuple(f"35_{i:02d}" for i in
                           [*range(1, 18), *range(19, 27), 28, *range(30, 35)])
CMU35_TEST_TRIALS = ("35_18", "35_29")
CMU35_JOG_TRIALS = frozenset(f"35_{i:02d}" for i in range(17, 27))
MIT_FPS = 30.0


def default_data_dir() -> Path:
    """``$MOTIONLANG_DATA``, else ``../shared/data`` next to the project, else an error."""
    env = os.environ.get(DATA_ENV)
    if env:
        p = Path(env).expanduser()
        if not p.is_dir():
            raise DatasetError(f"{DATA_ENV}={env}: not a folder")
        return p
    project = Path(__file__).resolve().parents[3]  # src/motionlang/datasets/named.py
    p = project.parent / "shared" / "data"
    if p.is_dir():
        return p
    raise DatasetError(f"no data folder: set {DATA_ENV} or pass data_dir (looked in {p})")


def data_dirs() -> list[Path]:
    """The folders the shared data may lie in, most specific first: ``$MOTIONLANG_DATA``,
    then ``shared/data`` beside and below the current folder, then beside the source
    checkout; unlike :func:`default_data_dir`, a missing one is no error."""
    dirs = [Path(os.environ[DATA_ENV]).expanduser()] if os.environ.get(DATA_ENV) else []
    checkout = Path(__file__).resolve().parents[3]  # src/motionlang/datasets/named.py
    return dirs + [Path.cwd().parent / "shared" / "data", Path.cwd() / "shared" / "data",
                   checkout.parent / "shared" / "data"]


def find_data_file(rel: str | Path) -> Path | None:
    """``rel`` in the first of :func:`data_dirs` that holds it, else None."""
    for d in data_dirs():
        if (d / rel).is_file():
            return d / rel
    return None


def _data_file(data_dir: str | Path | None, rel: str) -> Path:
    root = Path(data_dir) if data_dir is not None else default_data_dir()
    path = root / rel
    if not path.is_file():
        raise DatasetError(f"{path}: missing")
    return path


def _loadmat(path: Path) -> dict:
    from scipy.io import loadmat  # scipy only for the .mat datasets

    try:
        return loadmat(path)
    except Exception as exc:  # scipy raises assorted types on corrupt files
        raise DatasetError(f"{path}: cannot read MATLAB file ({exc})") from None


@dataclass
class Cmu35Trial:
    """One trial: ``motion`` (30 Hz), ``trial`` id ("35_01"), ``label`` "walk" or "jog",
    ``split`` "train" or "test", and ``rows`` (its row range in ``Y`` / ``Ytest``)."""
    trial: str
    label: str
    split: str
    motion: Motion
    rows: tuple[int, int]


@dataclass
class Cmu35WalkJog:
    """The trials and the raw arrays (for the CRBM: channels in degrees, 62 columns).

    Attributes:
        train, test: lists of ``Cmu35Trial`` (31 and 2).
        Y (2644, 62), lbls (2644, 31), Ytest (169, 62), lblstest (169, 2): as in the file.
        skeleton_path: the ``35.asf`` used.
    """
    train: list[Cmu35Trial]
    test: list[Cmu35Trial]
    Y: np.ndarray
    lbls: np.ndarray
    Ytest: np.ndarray
    lblstest: np.ndarray
    skeleton_path: Path

    @property
    def trials(self) -> list[Cmu35Trial]:
        return self.train + self.test


def _segments(lbls: np.ndarray, path: Path, what: str) -> list[tuple[int, int]]:
    """Contiguous row ranges of each one-hot column, in column order."""
    if lbls.ndim != 2 or not np.all(lbls.sum(axis=1) == 1):
        raise DatasetError(f"{path}: {what} is not one-hot per row")
    out = []
    for j in range(lbls.shape[1]):
        rows = np.flatnonzero(lbls[:, j])
        if len(rows) == 0 or rows[-1] - rows[0] + 1 != len(rows):
            raise DatasetError(f"{path}: {what} column {j} is not one contiguous block")
        out.append((int(rows[0]), int(rows[-1]) + 1))
    return out


def cmu35_walkjog(data_dir: str | Path | None = None) -> Cmu35WalkJog:
    """CMU subject 35 walking and jogging (Taylor et al. 2006) as Motions and raw arrays.

    Args:
        data_dir: folder holding ``cmu35/cmu35WalkJog.mat`` and ``cmu35/35.asf``
            (default ``default_data_dir()``).
    """

    mat_path = _data_file(data_dir, "cmu35/cmu35WalkJog.mat")
    asf_path = _data_file(data_dir, "cmu35/35.asf")
    d = _loadmat(mat_path)
    try:
        Y, lbls, Yt, lt = (np.asarray(d[k]) for k in ("Y", "lbls", "Ytest", "lblstest"))
    except KeyError as exc:
        raise DatasetError(f"{mat_path}: variable {exc} missing") from None
    if lbls.shape[1] != len(CMU35_TRAIN_TRIALS) or lt.shape[1] != len(CMU35_TEST_TRIALS):
        raise DatasetError(f"{mat_path}: expected {len(CMU35_TRAIN_TRIALS)} training and "
                           f"{len(CMU35_TEST_TRIALS)} test trials, got {lbls.shape[1]} and "
                           f"{lt.shape[1]}")
    skeleton = read_asf(asf_path)
    parts = {"train": [], "test": []}
    for split, data, lab, names in (("train", Y, lbls, CMU35_TRAIN_TRIALS),
                                    ("test", Yt, lt, CMU35_TEST_TRIALS)):
        for name, (a, b) in zip(names, _segments(lab, mat_path, "lbls" if split == "train"
                                                 else "lblstest")):
            motion = motion_from_channels(skeleton, data[a:b], CMU35_FPS, name=name)
            motion.meta.update(trial=name, path=str(mat_path))
            label = "jog" if name in CMU35_JOG_TRIALS else "walk"
            parts[split].append(Cmu35Trial(name, label, split, motion, (a, b)))
    return Cmu35WalkJog(parts["train"], parts["test"], Y, lbls, Yt, lt, asf_path)


def mit_walk(data_dir: str | Path | None = None) -> list[Motion]:
    """The MIT walking sequences (``mit/motion.mat``, 30 Hz) via ``formats.mit.read_mit``."""
    path = _data_file(data_dir, "mit/motion.mat")
    return read_mit(path)


def cmu_dev_folder(data_dir: str | Path, dest: str | Path) -> Path:
    """The ``cmu-dev`` folder of the shared ``cmu_dev/cmu-dev.tar.xz`` (56 CMU trials of other
    subjects in three rigs), extracted under ``dest`` the first time (never into the data
    folder)."""
    import tarfile
    folder = Path(dest) / "cmu-dev"
    if not folder.is_dir():
        archive = Path(data_dir) / "cmu_dev" / "cmu-dev.tar.xz"
        if not archive.is_file():
            raise DatasetError(f"{archive}: not found")
        Path(dest).mkdir(parents=True, exist_ok=True)
        with tarfile.open(archive) as tar:
            tar.extractall(dest, filter="data")
    return folder
