"""Files of a dataset folder stay inside it: a symbolic link found in the folder that
leads elsewhere is never read as one of its files (a training run would read, and a
published split would count, a file the folder's owner never put there)."""
from __future__ import annotations

from pathlib import Path

from motionlang.errors import DatasetError


def leads_outside(path: Path, real_root: Path) -> bool:
    """Whether ``path`` (found under the folder whose resolved path is ``real_root``) is a
    symbolic link to something outside it. Only links count: a folder reached through
    its own resolved path is inside by definition."""
    return path.is_symlink() and real_root not in path.resolve().parents


def check_inside(paths, root: Path) -> None:
    """Refuse the first of ``paths`` that is a link leading out of ``root``.

    Raises:
        DatasetError: ``PATH: a symbolic link that leads out of the dataset folder ROOT``.
    """
    real = Path(root).resolve()
    for p in paths:
        if leads_outside(Path(p), real):
            raise DatasetError(f"{p}: a symbolic link that leads out of the dataset folder "
                               f"{root}; copy the file in, or link the whole folder")
