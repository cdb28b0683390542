"""Every model kind and every packaged model, in one place.

* :data:`KINDS` — a checkpoint's ``kind`` -> the class that reads it (imported on first use,
  so that asking for a CRBM never loads torch).
* :data:`PACKAGED` — the models shipped inside the package, by name, with their model cards
  (``data/models/NAME.md``: data, licence, recipe, measured figures).
* :func:`load_model` — a packaged name, a checkpoint file or a training run folder -> the
  model in eval mode, whatever its kind; ``kind=`` insists on one.

Checkpoints are ``.pt`` files (torch, weights only; M2L, L2M, two-stream) or ``.npz``
files (numpy; the CRBM family). Both say what they hold: :func:`checkpoint_kind` reads that
without building anything.
"""
from __future__ import annotations

import importlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from motionlang.errors import MotionlangError

PACKAGE_DIR = Path(__file__).resolve().parents[1] / "data" / "models"

#: kind -> "module:Class"; each class has ``kind``, ``load(path)`` and ``save(path)``
KINDS: dict[str, str] = {
    "m2l": "motionlang.models.seq2seq.m2l:MotionToLanguage",
    "l2m": "motionlang.models.seq2seq.l2m:LanguageToMotion",
    "twostream": "motionlang.models.twostream.model:TwoStreamModel",
    "crbm": "motionlang.models.crbm.model:CRBM",
    "crbm_stack": "motionlang.models.crbm.stack:CRBMStack",
    "ar": "motionlang.models.crbm.ar:ARModel",
    "evaluator": "motionlang.models.evaluator.model:TextMotionEvaluator",
    "judge": "motionlang.models.judge.model:MotionJudge",
}
#: the kinds that turn text into motion (``decoding.t2m.TextToMotion``)
TEXT_TO_MOTION = ("l2m", "twostream")
#: file names a training run folder keeps its model under, in order of preference
RUN_MODEL_FILES = ("model.pt", "model.npz", "best.pt")


#: the licences of packaged models: the project's own, or that of the Bandai Namco data
MIT = "MIT"
NON_COMMERCIAL = ("CC BY-NC 4.0: trained on the Bandai Namco Research Motion Datasets, "
                  "non-commercial use only")


@dataclass(frozen=True)
class Packaged:
    """A model shipped in the package: its file, kind, licence and model card (Markdown)."""

    name: str
    kind: str
    summary: str
    licence: str = MIT

    @property
    def commercial(self) -> bool:
        return self.licence == MIT

    @property
    def path(self) -> Path:
        return PACKAGE_DIR / f"{self.name}.pt"

    @property
    def card(self) -> str:
        card = PACKAGE_DIR / f"{self.name}.md"
        return card.read_text(encoding="utf-8") if card.is_file() else ""


PACKAGED: dict[str, Packaged] = {
    "m2l": Packaged("m2l", "m2l", "motion -> English (seq2seq, Plappert et al. 2018), "
                    "21-joint body, procedural corpus + Bandai Namco takes", NON_COMMERCIAL),
    "l2m": Packaged("l2m", "l2m", "English -> motion (seq2seq with a mixture density output, "
                    "Plappert et al. 2018), 21-joint body, procedural corpus + Bandai Namco "
                    "takes", NON_COMMERCIAL),
    "twostream": Packaged("twostream", "twostream", "English -> motion (hierarchical two-stream "
                          "model, Ghosh et al. 2021; MiniLM sentence encoder), 21-joint body, "
                          "procedural corpus + Bandai Namco takes; 4 epochs: weak on Bandai "
                          "sentences (see its card)", NON_COMMERCIAL),
    "m2l-procedural": Packaged("m2l-procedural", "m2l", "the M2L of the procedural corpus "
                               "alone (the packaged m2l until 2026-11-24)"),
    "l2m-procedural": Packaged("l2m-procedural", "l2m", "the L2M of the procedural corpus "
                               "alone (the packaged l2m until 2026-11-24)"),
    "judge": Packaged("judge", "judge", "action and style classifier of real motion "
                      "(evaluate-judge), Bandai Namco takes", NON_COMMERCIAL),
}


def model_class(kind: str) -> type:
    """The class that reads checkpoints of ``kind``."""
    if kind not in KINDS:
        raise MotionlangError(f"unknown model kind {kind!r} (known: {', '.join(KINDS)})")
    module, name = KINDS[kind].split(":")
    return getattr(importlib.import_module(module), name)


def resolve(name_or_path: str | Path) -> Path:
    """A packaged model's name, a checkpoint file or a run folder -> the checkpoint file.

    Raises:
        MotionlangError: no such model, or a folder without a model file in it.
    """
    if isinstance(name_or_path, str) and name_or_path in PACKAGED:
        path = PACKAGED[name_or_path].path
        if not path.is_file():
            raise MotionlangError(f"{path}: the packaged {name_or_path} model is missing "
                                  "from this installation")
        return path
    path = Path(name_or_path)
    if path.is_dir():
        for name in RUN_MODEL_FILES:
            if (path / name).is_file():
                return path / name
        raise MotionlangError(f"{path}: a folder without a model file "
                              f"({', '.join(RUN_MODEL_FILES)})")
    if not path.is_file():
        names = ", ".join(PACKAGED)
        raise MotionlangError(f"{path}: no such model file or run folder (packaged models: "
                              f"{names})")
    return path


def _npz_kind(path: Path) -> str:
    import numpy as np
    try:
        with np.load(path, allow_pickle=False) as z:
            if "kind" in z.files:
                return str(z["kind"])
            if "meta" in z.files:
                return str(json.loads(str(z["meta"])).get("kind"))
    except (OSError, ValueError, KeyError, json.JSONDecodeError) as exc:
        raise MotionlangError(f"{path}: not a readable model file ({type(exc).__name__})"
                              ) from exc
    raise MotionlangError(f"{path}: an .npz without a model kind")


def checkpoint_kind(path: str | Path) -> str:
    """The ``kind`` a checkpoint file declares (its format checked, nothing built)."""
    path = Path(path)
    if path.suffix.lower() == ".npz":
        return _npz_kind(path)
    from motionlang.models.checkpoint import model_dict
    return str(model_dict(path)["kind"])


def load_model(name_or_path: str | Path, kind: str | tuple[str, ...] | None = None,
               **kw) -> Any:
    """A model in eval mode from a packaged name (:data:`PACKAGED`), a checkpoint file or a
    training run folder; ``kind`` (one kind or several) refuses any other kind by name;
    ``kw`` go to the class's ``load`` (e.g. a two-stream model's ``text_encoder``).

    Raises:
        MotionlangError: missing or unreadable file, a newer checkpoint format, or a kind
            other than the one asked for.
    """
    path = resolve(name_or_path)
    found = checkpoint_kind(path)
    wanted = (kind,) if isinstance(kind, str) else kind
    if wanted and found not in wanted:
        raise MotionlangError(f"{path}: a model of kind {found}, not {' or '.join(wanted)}")
    if found not in KINDS:
        raise MotionlangError(f"{path}: unknown model kind {found!r}")
    return model_class(found).load(path, **kw)


def describe_packaged() -> str:
    """One line per packaged model: name, file state, summary, and a licence note where the
    model is not under the project's licence."""
    width = max(len(n) for n in PACKAGED)
    return "\n".join(f"{p.name:{width}s} {'' if p.path.is_file() else '(missing) '}{p.summary}"
                     + ("" if p.commercial else " [non-commercial]")
                     for p in PACKAGED.values())


def licence_note(name: str) -> str:
    """For ``--help``: what licence the packaged model ``name`` is under, and the
    commercial-use alternative of the same kind when it is non-commercial."""
    p = PACKAGED[name]
    if p.commercial:
        return f"the packaged {name} is {p.licence}-licensed"
    free = [q.name for q in PACKAGED.values() if q.kind == p.kind and q.commercial]
    return (f"the packaged {name} is {p.licence}" +
            (f"; {free[0]} is trained on the procedural corpus alone (MIT)" if free else ""))
