"""The checks every ``.npz`` of the CRBM family passes before a model is built from it
(the schema of :mod:`motionlang.models.schema`, the family's torch-free counterpart of
``Checkpointed.load``): its zip members' CRCs, its JSON metadata read with bounds, the
config's field types and values, the feature count, and every stored array's shape
against the one its config needs.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.models.schema import check_array, check_config
from motionlang.models.versions import check_archive, check_config_fields
from motionlang.utils.checks import MAX_DIM
from motionlang.utils.sidecar import parse_json


def open_npz(path: str | Path) -> Any:
    """``np.load`` of a model file whose zip members all pass their CRC check; a member
    that is no ``.npy`` array is an error naming it when read (:class:`_Members`)."""
    if not Path(path).is_file():
        raise FileNotFoundError(path)
    check_archive(path)
    return _Members(path, np.load(path, allow_pickle=False))


class _Members:
    """The members of an ``.npz`` as arrays: numpy hands back raw bytes for a member that
    lacks the ``.npy`` magic, and a tokenizer error for a garbled ``.npy`` header."""

    def __init__(self, path: str | Path, z: Any):
        self.path, self.z, self.files = path, z, z.files

    def __enter__(self) -> _Members:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.z.close()

    def __getitem__(self, key: str) -> np.ndarray:
        try:
            a = self.z[key]
        except Exception as exc:   # noqa: BLE001 - ValueError, SyntaxError, TokenError...
            raise MotionlangError(f"{self.path}: a damaged checkpoint ({key}: "
                                  f"{type(exc).__name__})") from None
        if not isinstance(a, np.ndarray):
            raise MotionlangError(f"{self.path}: a damaged checkpoint ({key}: not an array)")
        return a


def read_meta(path: str | Path, z: Any, key: str, kind: str) -> dict:
    """The JSON dict stored under ``key`` (bounded: :func:`~motionlang.utils.sidecar.parse_json`).

    Raises:
        MotionlangError: ``PATH: a damaged KIND checkpoint (KEY: ...)``.
    """
    if key not in z.files:
        raise MotionlangError(f"{path}: a damaged {kind} checkpoint ({key}: missing)")
    raw = z[key]
    if raw.shape != () or raw.dtype.kind != "U":
        raise MotionlangError(f"{path}: a damaged {kind} checkpoint ({key}: not a text)")
    try:
        meta = parse_json(str(raw), key)
    except MotionlangError as exc:
        raise MotionlangError(f"{path}: a damaged {kind} checkpoint ({exc})") from None
    if not isinstance(meta, dict):
        raise MotionlangError(f"{path}: a damaged {kind} checkpoint ({key}: not a JSON "
                              "object)")
    return meta


def read_config(path: str | Path, meta: dict, kind: str, config_cls: type) -> tuple[Any, int]:
    """The config dataclass and the feature count ``n_visible`` of one level's metadata."""
    config = check_config(path, kind, config_cls, meta.get("config"))
    check_config_fields(config_cls, meta.get("config"), path, kind)
    n = meta.get("n_visible")
    if not (isinstance(n, int) and not isinstance(n, bool) and 1 <= n <= MAX_DIM):
        raise MotionlangError(f"{path}: a damaged {kind} checkpoint (n_visible: expected an "
                              f"integer in 1..{MAX_DIM}, got {str(n)[:40]!r})")
    return config, n


def arrays(path: str | Path, z: Any, kind: str, shapes: dict[str, tuple[int, ...]],
           prefix: str = "") -> dict[str, np.ndarray]:
    """The stored arrays ``prefix + name``, each numeric and of its expected shape."""
    out = {}
    for name, shape in shapes.items():
        key = prefix + name
        if key not in z.files:
            raise MotionlangError(f"{path}: a damaged {kind} checkpoint ({key}: missing)")
        a = z[key]
        if a.dtype.kind not in "fiu":
            raise MotionlangError(f"{path}: a damaged {kind} checkpoint ({key}: not numbers)")
        check_array(path, kind, key, a.shape, shape)
        out[name] = a
    return out


def crbm_shapes(config: Any, n_visible: int) -> dict[str, tuple[int, ...]]:
    """What a CRBM of ``config`` over ``n_visible`` features stores."""
    D, H, nD = n_visible, config.n_hidden, n_visible * config.order
    return {"W": (D, H), "A": (nD, D), "B": (nD, H), "a": (D,), "b": (H,), "mean": (D,),
            "std": (D,)}
