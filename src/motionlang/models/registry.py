"""Every model kind and every packaged model, in one place.

* :func:`families` — every model family, one :class:`~motionlang.models.family.Family`
  entry per checkpoint kind (model class, config, recipe, capabilities, run-file name),
  read from the family folders listed in :data:`FAMILY_MODULES`; every other table
  (:func:`kinds_with`, the ``train`` commands, the encoders) derives from it.
  Classes are imported on first use, so that asking for a CRBM never loads torch.
* :data:`PACKAGED` — the models shipped inside the package, by name, with their model cards
  (``data/models/NAME.md``: data, licence, recipe, measured figures).
* :func:`load_model` — a packaged name, a checkpoint file or a training run folder -> the
  model in eval mode, whatever its kind; ``kind=`` insists on one.

Checkpoints are ``.pt`` files (torch, weights only; M2L, L2M, two-stream) or ``.npz``
files (numpy; the CRBM family). Both say what they hold: :func:`checkpoint_kind` reads that
without building anything.
"""
from __future__ import annotations

import functools
import hashlib
import importlib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.models.family import Family, ModelClass, load_object
from motionlang.utils.sidecar import parse_json

PACKAGE_DIR = Path(__file__).resolve().parents[1] / "data" / "models"

#: One module per model family folder, each defining ``FAMILIES``: a tuple of
#: :class:`~motionlang.models.family.Family` entries (one per checkpoint kind). This list is
#: the only place outside a family's folder that names it (``docs/contributing.md``).
FAMILY_MODULES: tuple[str, ...] = (
    "motionlang.models.seq2seq.family",     # m2l, l2m (Plappert et al. 2018)
    "motionlang.models.twostream.family",   # twostream (Ghosh et al. 2021)
    "motionlang.models.crbm.family",        # crbm, crbm_stack, ar (Taylor et al. 2006)
    "motionlang.models.evaluator.family",   # evaluator (Guo et al. 2022 protocol)
    "motionlang.models.judge.family",       # judge (action and style of real motion)
    "motionlang.models.retrieval.family",   # retrieval (text-motion, TMR-style)
    "motionlang.models.masked.family",      # masked (masked-token text-to-motion, MoMask-style)
)


@functools.cache
def families() -> dict[str, Family]:
    """Every model family by checkpoint kind, in :data:`FAMILY_MODULES` order.

    Raises:
        MotionlangError: a listed module that does not import, or two entries of one kind
            (a broken family is an error, never silently skipped).
    """
    out: dict[str, Family] = {}
    for name in FAMILY_MODULES:
        try:
            module = importlib.import_module(name)
        except ImportError as exc:
            raise MotionlangError(f"model family {name} does not import: {exc}") from exc
        entries = getattr(module, "FAMILIES", None)
        if not entries:
            raise MotionlangError(f"model family {name} defines no FAMILIES")
        for fam in entries:
            if fam.kind in out:
                raise MotionlangError(f"model kind {fam.kind!r} is defined twice ({name})")
            out[fam.kind] = fam
    return out


def family(kind: str) -> Family:
    """The family entry of a checkpoint kind."""
    fams = families()
    if kind not in fams:
        raise MotionlangError(f"unknown model kind {kind!r} (known: {', '.join(fams)})")
    return fams[kind]


def describer(model: Any) -> Any:
    """The function that describes motions for ``model``'s family (``Family.describes``).

    Raises:
        MotionlangError: a model whose family does not turn motion into text.
    """
    kind = getattr(model, "kind", None)
    fam = families().get(kind) if isinstance(kind, str) else None
    if fam is None or fam.describes is None:
        raise MotionlangError(f"a {kind or type(model).__name__} model does not describe "
                              f"motion (kinds that do: {', '.join(kinds_with('describes'))})")
    return load_object(fam.describes)


def kinds_with(capability: str) -> tuple[str, ...]:
    """The kinds that have ``capability`` (a :class:`Family` attribute: "text_to_motion",
    "describes", "encodes_text", "encodes_motion", "recipe")."""
    return tuple(k for k, f in families().items() if getattr(f, capability))


#: file names a training run folder keeps its model under, in order of preference
RUN_MODEL_FILES = ("model.pt", "model.npz", "best.pt")


#: the licences of packaged models: the project's own, or that of the Bandai Namco data
MIT = "MIT"
NON_COMMERCIAL = ("CC BY-NC 4.0: trained on the Bandai Namco Research Motion Datasets, "
                  "non-commercial use only")


@dataclass(frozen=True)
class Packaged:
    """A model shipped in the package: its file, kind, licence, model card (Markdown) and
    the SHA-256 of its file (checked on load: :func:`verify_packaged`)."""

    name: str
    kind: str
    summary: str
    licence: str = MIT
    sha256: str = ""

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


#: SHA-256 of each packaged file, kept in step by ``scripts/packaged_digests.py`` (a test
#: fails when they differ): a packaged model is checked against it on first use
PACKAGED_SHA256: dict[str, str] = {
    "m2l": "644963b4e696933fb7d86318905093468f658a2dc1a2a6d9fda4b13d29e1428d",
    "l2m": "e2ca8ae530b370f1245ed7506d757a25683af29c781df7cf98b3353b62b42a3a",
    "twostream": "f1b5a1039ee4ef6672ba10a9597c08f9cb92a51584af34f3ed5ba36c81171e32",
    "m2l-procedural": "f1c0da99bc3a90ac9bbb40616cc027cb490dbb61115c75316afc4fe372925eef",
    "l2m-procedural": "75e9dca9b55abc02b251158048b4903aca9f68af1d2c40c1c4c2cfc1964d1ae8",
    "retrieval": "c4a589d890161d0923f59ac502ee28d9376239204b3d582c91b4f17e80e67f8a",
    "judge": "53e34ff070150aa1f7926a6e4ce62e3a87fd29c10fb0d576631337c70b801e74",
    "masked": "7b139a08eeec9463572ae974e1d16822761f162274643539647b287df55733ad",
    "retrieval-mpnet": "bcd6aa9fb5ea597df5fd06c1a9da99302372786d0de1b6c9d0ce62b54b163c6a",
}

PACKAGED: dict[str, Packaged] = {k: replace(p, sha256=PACKAGED_SHA256.get(k, "")) for k, p in {
    "m2l": Packaged("m2l", "m2l", "motion -> English (seq2seq, Plappert et al. 2018), "
                    "21-joint body, procedural corpus + Bandai Namco takes", NON_COMMERCIAL),
    "l2m": Packaged("l2m", "l2m", "English -> motion (seq2seq with a mixture density output, "
                    "Plappert et al. 2018), 21-joint body, procedural corpus + Bandai Namco "
                    "takes", NON_COMMERCIAL),
    "twostream": Packaged("twostream", "twostream", "English -> motion (hierarchical two-stream "
                          "model, Ghosh et al. 2021; MiniLM sentence encoder), 21-joint body, "
                          "procedural corpus + Bandai Namco takes (each normalised by its own "
                          "motions); its first pose read from the sentence", NON_COMMERCIAL),
    "m2l-procedural": Packaged("m2l-procedural", "m2l", "the M2L of the procedural corpus "
                               "alone, free of the Bandai Namco licence"),
    "l2m-procedural": Packaged("l2m-procedural", "l2m", "the L2M of the procedural corpus "
                               "alone, free of the Bandai Namco licence"),
    "retrieval": Packaged("retrieval", "retrieval", "text-motion retrieval (TMR-style "
                          "contrastive encoders; MiniLM sentence vectors), 21-joint body, "
                          "procedural corpus + Bandai Namco takes: index, search, describe "
                          "--bank", NON_COMMERCIAL),
    "judge": Packaged("judge", "judge", "action and style classifier of real motion "
                      "(evaluate-judge), Bandai Namco takes", NON_COMMERCIAL),
    "masked": Packaged("masked", "masked", "English -> motion and text-conditioned "
                       "in-betweening (masked-token model, MoMask-style; MiniLM sentence "
                       "vectors), 21-joint body, procedural corpus + Bandai Namco takes",
                       NON_COMMERCIAL),
    "retrieval-mpnet": Packaged("retrieval-mpnet", "retrieval", "text-motion retrieval as "
                                "retrieval, reading sentences with all-mpnet-base-v2: finds "
                                "more of what a query in a user's own words means; needs "
                                "'motionlang encoders install mpnet'", NON_COMMERCIAL),
}.items()}


def model_class(kind: str) -> ModelClass:
    """The class that reads checkpoints of ``kind``."""
    return load_object(family(kind).model)


#: packaged files already checked by this process: (path, size, mtime); a file changed
#: since is checked again
_VERIFIED: set[tuple[str, int, int]] = set()


def file_sha256(path: str | Path) -> str:
    """The SHA-256 of a file, hex."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def verify_packaged(p: Packaged) -> None:
    """Refuse a packaged model whose file is not the one shipped (its SHA-256 differs from
    :data:`PACKAGED_SHA256`): changed on disk, damaged, or swapped. Checked once per
    process and file.

    Raises:
        MotionlangError: one line naming the file and both digests' first characters.
    """
    path = p.path
    try:
        st = path.stat()
        key = (str(path), st.st_size, st.st_mtime_ns)
        if key in _VERIFIED:
            return
        got = file_sha256(path)
    except OSError as exc:
        raise MotionlangError(f"{path}: cannot read the packaged {p.name} model: "
                              f"{exc.strerror or exc}") from None
    if got != p.sha256:
        want = f"{p.sha256[:12]}..." if p.sha256 else "none recorded"
        raise MotionlangError(f"{path}: the packaged {p.name} model is not the file it "
                              f"shipped as (SHA-256 {got[:12]}..., expected {want}): damaged "
                              f"or changed; reinstall motionlang")
    _VERIFIED.add(key)


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
        verify_packaged(PACKAGED[name_or_path])
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
    import tokenize
    import zipfile

    import numpy as np

    try:
        with np.load(path, allow_pickle=False) as z:
            if "kind" in z.files:
                return str(z["kind"])
            if "meta" in z.files:
                meta = parse_json(str(z["meta"]), f"{path}: meta")
                if isinstance(meta, dict):
                    return str(meta.get("kind"))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, SyntaxError,
            tokenize.TokenError, OverflowError, NotImplementedError) as exc:
        # the last four: a garbled .npy header, a size beyond C's, a zip flag numpy lacks
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
    if found not in families():
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
