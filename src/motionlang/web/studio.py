"""What the page asks for, as Python: the models loaded once, generated takes, uploaded rigs,
descriptions, searches and exports. :mod:`.app` only turns HTTP into these calls.

Every answer for the viewer is a dict of :mod:`.views`; every failure a
:class:`~motionlang.errors.MotionlangError` of one line. Takes and rigs are kept in memory
(the :data:`KEEP` most recent), so that a download writes only where the user saves it.
"""
from __future__ import annotations

import contextlib
import itertools
import math
import tempfile
import threading
import warnings
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import motionlang.api as ml
from motionlang.errors import MotionlangError
from motionlang.kinematics.motion import Motion
from motionlang.library.search import Hit, Library
from motionlang.models.registry import PACKAGED, kinds_with
from motionlang.models.t2m import SelfAdapter
from motionlang.rendering.output import RESULT_OUT
from motionlang.utils.checks import SEED_MAX
from motionlang.web.options import DEFAULT_MODELS, ServeOptions
from motionlang.web.uploads import Upload, page_message, read_upload
from motionlang.web.views import body21_view, motion_view, view_step

#: takes and rigs kept for downloads (older ones are forgotten)
KEEP = 64
#: longest generated take, seconds
MAX_SECONDS = 60.0
#: longest sentence, characters
MAX_TEXT = 500
#: a take longer than this (seconds) is also described as a timeline
TIMELINE_FROM_S = 10.0
#: download formats the page offers, when the result writer has them
EXPORTS = {"bvh": "application/octet-stream", "glb": "model/gltf-binary", "mp4": "video/mp4"}
METHODS = ("sample", "beam", "mean")
#: sentences generated at start: the second's rare word makes a model that maps unknown
#: words onto its vocabulary read its sentence encoder then, not in a user's request
WARM_UP = ("a person walks forward", "a person pirouettes")


def model_methods(t2m: Any) -> list[str]:
    """The decodings the page offers for a text-to-motion model: every one of
    :data:`METHODS`, but only its own for a model that samples by itself (``SelfAdapter``,
    e.g. the masked-token model: it refuses the others)."""
    return [t2m.default_method()] if isinstance(t2m, SelfAdapter) else list(METHODS)


@dataclass
class Take:
    """A generated motion: the model's result (positions (T, 21, 3) or a Motion) at fps."""
    text: str
    model: str
    result: Any
    fps: float


class _Recent(OrderedDict):
    """The ``KEEP`` most recently added items by id."""

    def add(self, item: Any, ids: itertools.count) -> str:
        key = f"{next(ids):x}"
        self[key] = item
        while len(self) > KEEP:
            self.popitem(last=False)
        return key

    def find(self, key: str | None, what: str) -> Any:
        if key not in self:
            raise MotionlangError(f"no {what} {key!r} here (the server keeps the {KEEP} most "
                                  "recent; generate or upload it again)")
        return self[key]


@contextlib.contextmanager
def _for_page():
    """A MotionlangError raised inside, worded for the page (``uploads.page_message``)."""
    try:
        yield
    except MotionlangError as exc:
        raise MotionlangError(page_message(exc)) from None


class Studio:
    """The app's state: models loaded at construction, then one method per page action.

    Args:
        options: the server's options (models, describer, index, upload limit).
        models: loaded text-to-motion models by name, instead of loading ``options.model``.
    """

    def __init__(self, options: ServeOptions, models: dict[str, Any] | None = None):
        self.options = options
        self.lock = threading.Lock()   # one model call at a time: torch modules are shared
        self._ids = itertools.count(1)
        self.takes: _Recent = _Recent()
        self.rigs: _Recent = _Recent()
        self.library = None
        if options.index is not None:   # a bad index is named before any model loads
            self.library = Library.open(options.index)
        self.describer = ml.load_model(options.describe_model, kind=kinds_with("describes"))
        self.models = models if models is not None else self._load_models()
        if options.warm:
            for name in self.models:
                for text in WARM_UP:
                    self.generate(text, name)
            self.takes.clear()

    def _load_models(self) -> dict[str, Any]:
        names = self.options.model or [n for n in DEFAULT_MODELS if PACKAGED[n].path.is_file()]
        if not names:
            raise MotionlangError("no text-to-motion model is installed; name one with --model")
        return {name: ml.text_to_motion(name) for name in names}

    # ------------------------------------------------------------------ the page's calls
    def info(self) -> dict[str, Any]:
        """What the page offers: models (with their decoding), exports, search."""
        return {"models": [{"name": n, "method": t.default_method(),
                            "methods": model_methods(t),
                            "deterministic": bool(t.deterministic), "fps": t.fps}
                           for n, t in self.models.items()],
                "methods": list(METHODS), "max_seconds": MAX_SECONDS,
                "exports": [e for e in EXPORTS if f".{e}" in RESULT_OUT],
                "search": self.library is not None,
                "max_upload_bytes": self.options.max_upload_bytes}

    def generate(self, text: str, model: str | None = None, seconds: float | None = None,
                 seed: int = 0, method: str | None = None, rig: str | None = None
                 ) -> dict[str, Any]:
        """A motion for ``text`` by ``model`` (a name offered; default the first),
        ``seconds`` long (None: the model's own length), drawn with ``seed``; with ``rig``
        (an uploaded rig's id) shown on that rig. Returns the viewer's JSON with ``id``
        (for :meth:`export`), ``text``, ``model`` and ``notes`` (warnings)."""
        text = " ".join(str(text).split())
        if not text:
            raise MotionlangError("type a sentence first")
        if len(text) > MAX_TEXT:
            raise MotionlangError(f"the sentence has {len(text)} characters; at most "
                                  f"{MAX_TEXT}")
        name = model or next(iter(self.models))
        if name not in self.models:
            raise MotionlangError(f"model {name!r} is not offered here (these are: "
                                  f"{', '.join(self.models)})")
        t2m = self.models[name]
        frames = None
        if seconds is not None:
            if not (np.isfinite(seconds) and 0 < seconds <= MAX_SECONDS):
                raise MotionlangError(f"length must be in (0, {MAX_SECONDS:g}] seconds, got "
                                      f"{seconds:g}")
            frames = max(1, round(seconds * t2m.fps))
        if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= SEED_MAX:
            raise MotionlangError(f"seed must be an integer in 0..{SEED_MAX}, got {seed}")
        if method is not None and method not in METHODS:
            raise MotionlangError(f"decoding must be one of {', '.join(METHODS)}")
        rig_motion = None if rig is None else self.rigs.find(rig, "rig")
        with self.lock, warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UserWarning)
            hyps, fps = ml.generate_hypotheses(
                text, t2m, seed=seed, method=method, max_frames=frames,
                min_frames=5 if frames is None else frames)   # a length asked for is kept
        result = hyps[0][0]
        key = self.takes.add(Take(text, name, result, fps), self._ids)
        extra = {"id": key, "text": text, "model": name, "rig": rig,
                 "notes": [str(w.message) for w in caught]}
        if rig_motion is not None:
            with self.lock:
                return motion_view(ml.body_motion(result, fps, rig_motion)[0], **extra)
        if isinstance(result, Motion):
            return motion_view(result, **extra)
        return body21_view(result, fps, **extra)

    def add_rig(self, files: list[Upload]) -> dict[str, Any]:
        """An uploaded rig (a BVH-like skeleton) to retarget takes onto: ``{"id", "name",
        "joints"}``."""
        # a rig's rate is never used: what reading it warns of is not said
        with self.lock, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            motion = read_upload(files, self.options.max_upload_bytes)
        with self.lock, _for_page():
            rig = ml.load_rig(motion[:1])
        key = self.rigs.add(rig, self._ids)
        return {"id": key, "name": motion.name, "joints": len(rig.skeleton.joints)}

    def describe(self, files: list[Upload], width: int | None = None) -> dict[str, Any]:
        """An uploaded motion described: the viewer's JSON of it on the 21-joint body with
        ``name``, ``seconds``, ``sentences`` ([{"text", "log_p"}], best first) and, for a
        take longer than :data:`TIMELINE_FROM_S`, ``timeline`` ([{"start", "end",
        "text"}]) and ``notes``: what reading it warned of (a rate its body contradicts).
        ``width``: as ``motionlang describe -w`` (None: its default)."""
        # warnings are the process's: caught only while no other call runs (the lock)
        with self.lock, warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            motion = read_upload(files, self.options.max_upload_bytes)
        most = self.options.max_describe_minutes
        if motion.duration > most * 60:   # checked before the models are held
            raise MotionlangError(
                f"{motion.name}: the take lasts {motion.duration / 60:,.1f} minutes "
                f"({motion.n_frames:,} frames at {motion.fps:g} Hz); this server describes "
                f"up to {most:g} (motionlang serve --max-describe-minutes; or motionlang "
                "describe FILE)")
        with self.lock, _for_page():
            sentences = ml.describe(motion, self.describer, width)
            segments = ml.timeline(motion, self.describer) \
                if motion.duration > TIMELINE_FROM_S else []
            shown = motion[::view_step(motion.fps)]
            positions = ml.body21(shown)
        return body21_view(positions, shown.fps, name=motion.name,
                           seconds=round(motion.duration, 2),
                           # a grounded sentence has no model score: null
                           sentences=[{"text": t, "log_p": None if math.isnan(s) else
                                       round(float(s), 3)} for t, s in sentences],
                           timeline=[{"start": round(s.start, 2), "end": round(s.end, 2),
                                      "text": s.text} for s in segments],
                           notes=[page_message(w.message) for w in caught])

    def search(self, query: str, k: int = 10, where: str | None = None,
               min_duration: str | None = None) -> list[dict[str, Any]]:
        """The index's best ``k`` spans for ``query``: [{"file", "start", "end", "score",
        "why"}]; ``where``, ``min_duration``: the filters of ``motionlang search``."""
        if self.library is None:
            raise MotionlangError("no index was given (motionlang serve --index FILE)")
        filters = {n: v for n, v in (("where", where), ("min_duration", min_duration)) if v}
        with self.lock, warnings.catch_warnings():
            warnings.simplefilter("ignore")   # "no take shows it": the reasons say as much
            hits = ml.search(query, self.library, k, **filters)
        return [{"file": h.file, "start": round(h.start, 2), "end": round(h.end, 2),
                 "score": round(float(h.score), 4), "why": h.why} for h in hits]

    def search_take(self, file: str, start: float, end: float) -> dict[str, Any]:
        """A span of an indexed take, for the viewer (on the 21-joint body)."""
        if self.library is None:
            raise MotionlangError("no index was given (motionlang serve --index FILE)")
        with self.lock:
            motion = self.library.take(Hit(file, start, end, 0.0)).between(start, end)
            shown = motion[::view_step(motion.fps)]
            return body21_view(ml.body21(shown), shown.fps, name=file)

    def export(self, take: str, fmt: str, rig: str | None = None) -> tuple[bytes, str, str]:
        """A take as a file of ``fmt`` (``bvh``, ``glb``, ``mp4``; with ``rig``: on that
        rig): ``(bytes, file name, media type)``, written in a private temporary folder."""
        item: Take = self.takes.find(take, "take")
        offered = self.info()["exports"]
        if fmt not in offered:
            raise MotionlangError(f"cannot download .{fmt}; this server writes "
                                  f"{', '.join('.' + e for e in offered)}")
        rig_motion = None if rig is None else self.rigs.find(rig, "rig")
        stem = "_".join(item.text.lower().split()[:8]).strip("_.") or "motion"
        stem = "".join(c for c in stem if (c.isascii() and c.isalnum()) or c == "_")[:60] \
            or "motion"   # an HTTP header: ASCII
        name = f"{stem}.{fmt}"
        with tempfile.TemporaryDirectory(prefix="motionlang-serve-") as tmp, self.lock:
            path = Path(tmp) / name
            ml.write_result(item.result, path, fps=item.fps, title=item.text, rig=rig_motion)
            return path.read_bytes(), name, EXPORTS[fmt]
