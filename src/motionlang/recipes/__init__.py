"""Training recipes: data -> model -> trainer -> best checkpoint, one per trainable family.

A :class:`Recipe` is what ``Family.recipe`` names: the function that trains, the dataclass
of its data options, and the trainer defaults it starts from. ``motionlang train KIND`` and
:func:`train` (``ml.train``) are both built on it, so the command line holds no training
logic. Importing this package does not import torch.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motionlang.datasets.mixing import source_weights
from motionlang.datasets.sources import LICENCE_FILE, parse_source
from motionlang.errors import MotionlangError
from motionlang.models.family import load_object
from motionlang.models.registry import family, kinds_with
from motionlang.training.config import TrainConfig
from motionlang.training.run_guard import (
    check_identity,
    check_run_folder,
    checkpoints,
    clear_run,
    run_identity,
    stopped_before_checkpoint,
    write_identity,
)
from motionlang.training.run_log import lead_process
from motionlang.utils.folder_lock import folder_lock


@dataclass(frozen=True)
class Recipe:
    """A family's way to train.

    Attributes:
        run: ``run(sources, out_dir, model_cfg, train_cfg, data_cfg, *, resume, options)``
            -> the trained model's path. ``sources``: ``datasets.sources.DataSource`` list
            (with ``data_help``: folder paths); ``model_cfg``: the model config's user fields
            (a dict; the recipe adds what the data decides, e.g. vocabulary and feature
            sizes); ``train_cfg``: a ``training.config.TrainConfig`` (None without
            ``trainer``); ``data_cfg``: an instance of ``data_config``; ``options``: what
            to log in ``commands.jsonl`` (None: the configs).
        data_config: the dataclass of the recipe's data options (fields with ``help``
            metadata are command-line options).
        train_defaults: the recipe's own defaults for ``TrainConfig`` fields.
        model_defaults: the recipe's own defaults for model config fields.
        several_sources: the recipe reads several ``--data`` (mixed, weighted).
        trainer: the recipe trains with the shared ``Trainer``, so the ``TrainConfig``
            options and ``--resume`` are its options. False (a model with its own training
            loop, whose epochs and rates are model config fields): neither is offered.
        data_help: where set, ``--data`` is one folder in the recipe's own format (not a
            ``datasets.sources`` dataset) and this is its help; ``run`` gets its path.
        run_files: what the run folder holds besides the model and ``commands.jsonl``, for
            ``--out``'s help (None: the trainer's checkpoints, history and splits).
        source_kind: where set, the one kind of ``datasets.sources`` dataset the recipe
            reads (e.g. ``"bandai"``): ``--data`` is parsed as that kind, a bare folder
            included, and another kind is refused.
        description: what ``train KIND -h`` says after the family's summary (the data's
            terms, how it is split).
        resume_may_change: data options a ``--resume`` may change (they change what an
            epoch trains on or how, never the vocabulary, features or split); every other
            data option, the data and the seed must be the run's (``training.run_guard``).
        extra_files: what ``--overwrite`` removes besides the trainer's files and the model
            file (stage folders, a second model file).
    """

    run: Callable[..., Path]
    data_config: type
    train_defaults: dict[str, Any] = field(default_factory=dict)
    model_defaults: dict[str, Any] = field(default_factory=dict)
    several_sources: bool = True
    trainer: bool = True
    data_help: str = ""
    run_files: str | None = None
    source_kind: str | None = None
    description: str = ""
    resume_may_change: tuple[str, ...] = ()
    extra_files: tuple[str, ...] = ()


def recipe_of(kind: str) -> Recipe:
    """The recipe of a trainable kind (``Family.recipe``)."""
    fam = family(kind)
    if fam.recipe is None:
        raise MotionlangError(f"no training recipe for {kind} models (trainable: "
                              f"{', '.join(kinds_with('recipe'))})")
    return load_object(fam.recipe)


def split_options(kind: str, options: dict[str, Any]) -> tuple[dict, dict, dict]:
    """Keyword options -> (model config, trainer config, data config) values, by field.

    Raises:
        MotionlangError: a key that none of the three configs has.
    """
    recipe = recipe_of(kind)
    model_cls = family(kind).config_class()
    names = [set() if c is None else {f.name for f in dataclasses.fields(c)}
             for c in (model_cls, TrainConfig if recipe.trainer else None,
                       recipe.data_config)]
    parts: tuple[dict, dict, dict] = ({}, {}, {})
    for key, value in options.items():
        where = next((i for i, n in enumerate(names) if key in n), None)
        if where is None:
            known = sorted(set().union(*names))
            raise MotionlangError(f"train {kind}: unknown option {key!r} (known: "
                                  f"{', '.join(known)})")
        parts[where][key] = value
    return parts


def train(kind: str, data: str | Path | Sequence[str | Path], out: str | Path, *,
          resume: bool = False, overwrite: bool = False, **options: Any) -> Path:
    """Train a ``kind`` model on ``data`` (one ``--data`` value or several, e.g.
    ``"corpus@1"``, ``"bandai:DIR@1"``) into the run folder ``out``; ``options`` are fields
    of the model's config, of ``TrainConfig`` (where the recipe uses the shared trainer) or
    of the recipe's data options, as the command line's ``train KIND`` options
    (``enc_hidden=32``, ``epochs=2``, ``features="positions"``). ``out`` must be new or
    empty unless ``resume`` (continue the run there) or ``overwrite`` (replace it):
    :func:`run_recipe`. Returns the trained model's path."""
    recipe = recipe_of(kind)
    model_kw, train_kw, data_kw = split_options(kind, options)
    given = [data] if isinstance(data, (str, Path)) else list(data)
    sources = [str(d) if recipe.data_help else parse_source(str(d), kind=recipe.source_kind)
               for d in given]
    train_cfg = (TrainConfig(**{**recipe.train_defaults, **train_kw, "out_dir": str(out)})
                 if recipe.trainer else None)
    data_cfg = recipe.data_config(**data_kw)
    return run_recipe(kind, sources, Path(out), {**recipe.model_defaults, **model_kw},
                      train_cfg, data_cfg, resume=resume, overwrite=overwrite)


def _files(out: Path) -> set[tuple[str, int]]:
    """(name, mtime) of the visible entries of a run folder but run.json: what a run has
    written."""
    if not out.is_dir():
        return set()
    return {(p.name, p.stat().st_mtime_ns) for p in out.iterdir()
            if not p.name.startswith(".") and p.name != "run.json"}


def run_recipe(kind: str, sources: Sequence, out: Path, model_cfg: dict, train_cfg: Any,
               data_cfg: Any, *, resume: bool = False, overwrite: bool = False,
               options: dict | None = None) -> Path:
    """``recipe.run`` inside the run folder's guard (``training.run_guard``): a new run
    refuses a non-empty ``out`` unless ``overwrite`` (which first removes the previous
    run's files); the folder is locked against a second process for the whole run; a
    ``resume`` whose data, seed or data options differ from the run's, or whose checkpoint
    does not read, is refused before anything is written, as are weights on some sources
    only. Under torchrun only the lead process checks and locks (the
    others write nothing)."""
    import dataclasses

    recipe = recipe_of(kind)

    def go() -> Path:
        return recipe.run(sources, out, model_cfg, train_cfg, data_cfg, resume=resume,
                          options=options)

    if not lead_process():
        return go()
    if out.exists() and not out.is_dir():
        raise MotionlangError(f"--out {out}: a file, not a folder")
    data_options = (dataclasses.asdict(data_cfg) if dataclasses.is_dataclass(data_cfg)
                    and not isinstance(data_cfg, type) else {})
    identity = run_identity(kind, list(sources), getattr(train_cfg, "seed", None),
                            data_options)
    if recipe.several_sources:
        source_weights(sources)   # all weighted or none
    if resume and recipe.trainer:   # a checkpoint to continue from, readable, checked first
        last = checkpoints(out)
        if not last:
            raise MotionlangError(f"--resume: no checkpoint {out / 'last.pt'} to continue "
                                  "from" + (" (the run stopped before its first one: "
                                            "--overwrite starts it again)"
                                            if stopped_before_checkpoint(out) else ""))
        from motionlang.training.run_files import read_training_checkpoint  # torch
        read_training_checkpoint(last[0])
    with folder_lock(out):   # a busy folder is named as such before its content is
        check_run_folder(out, resume=resume, overwrite=overwrite)
        if resume and recipe.trainer:
            check_identity(out, identity, recipe.resume_may_change)
        elif overwrite:
            clear_run(out, family(kind).model_file, (LICENCE_FILE, *recipe.extra_files))
        fresh = not (out / "run.json").exists()
        before = _files(out)
        if fresh:
            write_identity(out, identity)
        try:
            return go()
        except BaseException:
            # a run that failed before writing anything (a fresh one, or a resume of a
            # folder from before run.json whose checkpoint does not read) leaves no run.json
            if fresh and _files(out) == before:
                (out / "run.json").unlink(missing_ok=True)
            raise
