"""Options of building an index, searching it and describing motions, torch- and numpy-free
(``--help`` reads them).

Each field with a ``help`` is an option of ``motionlang index``, ``search`` or ``describe``
(``cli.config_options``) and a keyword of ``ml.index`` / ``ml.search`` /
``ml.describe_many``; the checks are the config's own.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.utils.checks import MAX_WIDTH, check_numbers

#: what runs ``index --workers``
ENGINES = ("processes", "ray")
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
        workers: processes that read, analyse and embed the files, each loading the
            model once (at most the CPU count and the files to embed).
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
    workers: int = _opt(1, "processes reading, analysing and embedding files, each loading "
                           "the model once (at most the CPU count)", metavar="N")
    engine: str = _opt("processes", "what runs --workers: processes on this machine, or ray: "
                                    "actors on the Ray cluster RAY_ADDRESS names, else on a "
                                    "Ray started here (the ray extra)",
                        choices=ENGINES)
    shard: str | None = _opt(None, "index only share K of N of the files (by the hash of "
                                   "their path): shards made apart, on other machines too, "
                                   "are joined by 'motionlang merge-index'", metavar="K/N")
    save_every: float = 60.0
    show_progress: bool | None = None

    def __post_init__(self) -> None:
        check_numbers("IndexOptions", self, positive=("window", "hop", "save_every"),
                      positive_ints=("workers",))
        if self.hop > self.window:
            raise MotionlangError(f"IndexOptions.hop ({self.hop:g}) must be at most "
                                  f"IndexOptions.window ({self.window:g}): windows must "
                                  "cover the take")
        if self.engine not in ENGINES:
            raise MotionlangError(f"IndexOptions.engine must be one of {', '.join(ENGINES)}, "
                                  f"got {self.engine!r}")
        if self.shard is not None:
            k, n = shard_of(self.shard, "IndexOptions.shard")
            self.shard = f"{k}/{n}"


def shard_of(text: str, name: str = "shard") -> tuple[int, int]:
    """``"K/N"`` -> (K, N), 1 <= K <= N.

    Raises:
        MotionlangError: anything else.
    """
    m = re.fullmatch(r"\s*(\d{1,6})\s*/\s*(\d{1,6})\s*", str(text))
    if m is None or not 1 <= int(m.group(1)) <= int(m.group(2)):
        raise MotionlangError(f"{name} must be K/N with 1 <= K <= N (e.g. 2/8), got {text!r}")
    return int(m.group(1)), int(m.group(2))


#: nearest-window backends of ``library.search``
BACKENDS = ("auto", "numpy", "faiss", "usearch")
_SECONDS = re.compile(r"\s*([0-9]*\.?[0-9]+(?:e[+-]?[0-9]+)?)\s*(ms|s|min)?\s*", re.I)
_UNIT = {None: 1.0, "s": 1.0, "ms": 1e-3, "min": 60.0}


def seconds(value: Any, name: str) -> float:
    """A duration given as a number or a text with a unit (``2``, ``2s``, ``500ms``,
    ``1.5min``) -> seconds.

    Raises:
        MotionlangError: anything else, or a duration that is negative or not finite.
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        out = float(value)
    else:
        m = _SECONDS.fullmatch(str(value))
        if m is None:
            raise MotionlangError(f"{name} must be a duration such as 2, 2s or 500ms, got "
                                  f"{value!r}")
        out = float(m.group(1)) * _UNIT[m.group(2) and m.group(2).lower()]
    if not math.isfinite(out) or out < 0:
        raise MotionlangError(f"{name} must be a finite duration >= 0, got {value!r}")
    return out


@dataclass(frozen=True)
class SearchOptions:
    """How an index is searched (``library.search``): how many hits, which takes may give
    them, and whether the analysis stored in the index takes part."""

    k: int = _opt(10, "hits to show", flag="-k", metavar="K")
    where: str | None = _opt(None, "only spans where the analysis stored in the index sees "
                             "this action (sit, crouch, kneel, lie, climb, crawl, balance, "
                             "walk, run, jump, kick, punch, wave, turn, ...)", metavar="ACTION")
    min_duration: float | str = _opt(0.0, "findings of the actions asked for (by the query "
                                     "or --where) count only when at least this long (2, "
                                     "2s, 500ms); hits shorter than it are left out",
                                     metavar="S")
    rig: str | None = _opt(None, "only takes of this rig: the name of the map that put it "
                           "on the 21-joint body (as 'motionlang info' prints it)",
                           metavar="NAME")
    path_glob: str | None = _opt(None, "only takes whose path under the indexed folder "
                                 "matches this glob ('subject05/*', '*.bvh')", metavar="GLOB")
    grounded: bool = _opt(True, "rank by the learned model alone: no take is lifted for "
                          "showing an action the query names (the analysis still answers "
                          "--where)")
    backend: str = _opt("auto", "nearest windows by numpy or faiss (exact), or usearch "
                        "(approximate, an HNSW graph kept beside the index); auto: exact, "
                        "faiss or usearch where installed and the index is very large",
                        choices=BACKENDS)

    def __post_init__(self) -> None:
        check_numbers("SearchOptions", self, positive_ints=("k",))
        object.__setattr__(self, "min_duration",
                           seconds(self.min_duration, "SearchOptions.min_duration"))
        if self.backend not in BACKENDS:
            raise MotionlangError(f"SearchOptions.backend must be one of "
                                  f"{', '.join(BACKENDS)}, got {self.backend!r}")
        for name in ("where", "rig", "path_glob"):
            v = getattr(self, name)
            if v is not None and (not isinstance(v, str) or not v.strip()):
                raise MotionlangError(f"SearchOptions.{name} must be a non-empty text, got "
                                      f"{v!r}")


RANKS = ("mbr", "logp")   # models.seq2seq.decode.search.RANKS, named here without importing torch


@dataclass(frozen=True)
class DescribeOptions:
    """How motions are described. The fields with a help text are ``motionlang describe``
    options (``cli/config_options.py``); ``width``, ``length_penalty`` and ``rank`` are the
    beam's (``motionlang evaluate`` takes those three with its own rank default)."""

    width: int = _opt(5, "beam width: at most this many sentences a motion gets (fewer "
                         "where the model's repeat themselves)", flag="--width",
                         aliases=("-w",), metavar="W")
    length_penalty: float = _opt(0.0, "beam search ranks by log P / length**ALPHA (0: "
                                    "total log P, the paper's; no effect with -w 1); with "
                                    "--rank mbr it only changes which sentences the beam "
                                    "keeps", metavar="ALPHA")
    rank: str = _opt("mbr", "order of the beam's sentences: mbr puts first the one the "
                        "beam agrees on most (mean sentence BLEU against the beam, "
                        "models/seq2seq/decode/mbr.py), logp the likeliest (the paper's; it favours the "
                        "shortest phrasing)", choices=RANKS)
    segments: bool = _opt(False, "each take as a timeline of (start, end, sentence) "
                             "segments, cut where the grounded analysis sees the action "
                             "change and each part described (with --bank or --raw: "
                             "overlapping windows, neighbours that agree merged)")
    window: float = _opt(3.0, "--segments: window length in seconds", metavar="S")
    hop: float = _opt(1.0, "--segments: seconds between window starts (at most the "
                         "window)", metavar="S")
    merge: str = _opt("action", "--segments: neighbours are merged when they name the "
                         "same action (main verb and side: left, right, both, back) or the "
                         "same sentence", choices=MERGES)
    bridge: int = _opt(1, "--segments: a run of at most N windows between two that "
                          "agree is taken for a flicker and joins them (0: none is)",
                          metavar="N")
    bank: str | None = _opt(None, "describe by retrieval: the nearest sentences of this "
                               "bank (one sentence a line, captions.csv/.jsonl, or KIT-ML's "
                               "annotations .json) in the joint space of a model that encodes "
                               "both (--model; default: the packaged one), scored by cosine",
                               metavar="FILE")
    workers: int = _opt(1, "processes describing files, each loading the model once "
                           "(at most the CPU count)", metavar="N")
    explain: bool = _opt(False, "after the sentences, the evidence of each phrase of the "
                            "grounded sentence: time span, what was measured, against which "
                            "threshold, with what confidence (motionlang.analysis)")
    raw: bool = _opt(False, "the model's own sentences as its beam ranks them, none of "
                            "the default's checks (models/seq2seq/decode/grounded.py): no "
                            "sentence of what the body does put first, none re-searched for "
                            "the gait the feet show, none left out for being verbless, "
                            "broken or repeated, style and gender words kept, no "
                            "'unfamiliar movement' line")

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
