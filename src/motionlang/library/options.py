"""Options of building an index and of describing motions, torch- and numpy-free (``--help``
reads them).

Each field with a ``help`` is an option of ``motionlang index`` or ``motionlang describe``
(``cli.config_options``) and a keyword of ``ml.index`` / ``ml.describe_many``; the checks
are the config's own.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.utils.checks import MAX_WIDTH, check_numbers

#: how neighbouring windows of a timeline are merged (``library.timeline.merge_windows``)
MERGES = ("action", "sentence")


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


RANKS = ("mbr", "logp")   # decoding.seq2seq.RANKS, named here without importing torch


def _option(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass(frozen=True)
class DescribeOptions:
    """How motions are described. The fields with a help text are ``motionlang describe``
    options (``cli/config_options.py``); ``width``, ``length_penalty`` and ``rank`` are the
    beam's (``motionlang evaluate`` takes those three with its own rank default)."""

    width: int = _option(5, "beam width: at most this many sentences a motion gets (fewer "
                         "where the model's repeat themselves)", flag="--width",
                         aliases=("-w",), metavar="W")
    length_penalty: float = _option(0.0, "beam search ranks by log P / length**ALPHA (0: "
                                    "total log P, the paper's; no effect with -w 1); with "
                                    "--rank mbr it only changes which sentences the beam "
                                    "keeps", metavar="ALPHA")
    rank: str = _option("mbr", "order of the beam's sentences: mbr puts first the one the "
                        "beam agrees on most (mean sentence BLEU against the beam, "
                        "decoding/mbr.py), logp the likeliest (the paper's; it favours the "
                        "shortest phrasing)", choices=RANKS)
    segments: bool = _option(False, "each take as a timeline of (start, end, sentence) "
                             "segments, cut where the grounded analysis sees the action "
                             "change and each part described (with --bank or --raw: "
                             "overlapping windows, neighbours that agree merged)")
    window: float = _option(3.0, "--segments: window length in seconds", metavar="S")
    hop: float = _option(1.0, "--segments: seconds between window starts (at most the "
                         "window)", metavar="S")
    merge: str = _option("action", "--segments: neighbours are merged when they name the "
                         "same action (main verb and side: left, right, both, back) or the "
                         "same sentence", choices=MERGES)
    bridge: int = _option(1, "--segments: a run of at most N windows between two that "
                          "agree is taken for a flicker and joins them (0: none is)",
                          metavar="N")
    bank: str | None = _option(None, "describe by retrieval: the nearest sentences of this "
                               "bank (one sentence a line, captions.csv/.jsonl, or KIT-ML's "
                               "annotations .json) in the joint space of a model that encodes "
                               "both (--model; default: the packaged one), scored by cosine",
                               metavar="FILE")
    workers: int = _option(1, "processes describing files, each loading the model once "
                           "(at most the CPU count)", metavar="N")
    explain: bool = _option(False, "after the sentences, the evidence of each phrase of the "
                            "grounded sentence: time span, what was measured, against which "
                            "threshold, with what confidence (motionlang.analysis)")
    raw: bool = _option(False, "the model's sentences as its beam ranks them: not checked "
                        "against the gait the feet show (walk, run, jump), verbless ones "
                        "kept, no 'unfamiliar movement' line")

    def __post_init__(self) -> None:
        check_numbers("DescribeOptions", self, positive_ints=("workers", "width"),
                      nonneg_ints=("bridge",),
                      positive=("window", "hop"), nonneg=("length_penalty",))
        if self.width > MAX_WIDTH:
            raise MotionlangError(f"DescribeOptions.width must be an integer in "
                                  f"1..{MAX_WIDTH}, got {self.width}")
        if self.hop > self.window:
            raise MotionlangError(f"DescribeOptions.hop ({self.hop:g}) must not exceed "
                                  f"DescribeOptions.window ({self.window:g}): time between "
                                  "windows would go undescribed")
        for name, allowed in (("rank", RANKS), ("merge", MERGES)):
            if getattr(self, name) not in allowed:
                raise MotionlangError(f"DescribeOptions.{name} must be one of "
                                      f"{', '.join(allowed)}, got {getattr(self, name)!r}")
