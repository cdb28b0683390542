"""Options of building an index, torch- and numpy-free (``--help`` reads them).

Each field with a ``help`` is an option of ``motionlang index`` (``cli.config_options``) and
a keyword of ``ml.index``; the checks are the config's own.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.utils.checks import check_numbers


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class IndexOptions:
    """How a folder is cut and embedded.

    Attributes:
        window: seconds of motion each vector summarises.
        hop: seconds between the starts of two windows (at most ``window``, so that
            windows cover the take; less, so that every action has a window holding most
            of it wherever it starts).
        rebuild: embed every file again, even where an index exists (one made with
            another model or other windows is otherwise refused).
        save_every: seconds between saves of the index while it is built, so that an
            interrupted run keeps what it embedded (the next one goes on from there).
        show_progress: None: a bar on a terminal, log lines elsewhere; False: nothing.
    """

    window: float = _opt(3.0, "seconds of motion each vector summarises", metavar="S")
    hop: float = _opt(1.0, "seconds between the starts of two overlapping windows "
                           "(at most --window)", metavar="S")
    rebuild: bool = _opt(False, "embed every file again, even where the index exists (one "
                                "made with another model or other windows is refused "
                                "otherwise)")
    save_every: float = 60.0
    show_progress: bool | None = None

    def __post_init__(self) -> None:
        check_numbers("IndexOptions", self, positive=("window", "hop", "save_every"))
        if self.hop > self.window:
            raise MotionlangError(f"IndexOptions.hop ({self.hop:g}) must be at most "
                                  f"IndexOptions.window ({self.window:g}): windows must "
                                  "cover the take")
