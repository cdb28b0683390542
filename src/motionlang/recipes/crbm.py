"""The recipe of the conditional RBM (Taylor, Hinton & Roweis 2006): the CMU subject-35
folder (``datasets.cmu35``) -> the 31 training trials as model frames -> a CRBM trained by
its own CD-k loop -> ``model.npz``; with ``level2``, a second level on its hidden
activations -> ``stack.npz`` beside it.

The CRBM does not use the shared trainer: its passes, learning rate, batch size and seed are
fields of :class:`~motionlang.models.crbm.config.CRBMConfig`, whose defaults here are the
settings selected on held-out training trials (``CRBMConfig``'s :data:`SELECTED`). Every
option is checked before the data is read, and nothing is written before it is read.
Torch-free.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motionlang.datasets.cmu35 import load_cmu35, model_frames
from motionlang.errors import MotionlangError
from motionlang.models.crbm.config import SELECTED, CRBMConfig
from motionlang.models.crbm.model import CRBM as CRBMModel
from motionlang.models.crbm.stack import CRBMStack
from motionlang.models.registry import family
from motionlang.recipes import Recipe
from motionlang.training.run_steps import begin_run, finish_run

#: the two-level model of ``level2``, beside the run folder's model.npz
STACK_FILE = "stack.npz"
#: the model defaults of ``train crbm``: the paper's sizes with the selected settings
MODEL_DEFAULTS = {k: SELECTED[k] for k in ("epochs", "lr", "weight_decay",
                                           "weight_decay_autoregressive", "history_noise")}
DATA_HELP = "folder with cmu35WalkJog.mat, cmu35TaylorScaleBias.mat and 35.asf"
_LEVEL2_SIZE = {"level2_hidden": "n_hidden", "level2_order": "order"}


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class CRBMRunOptions:
    """The options of ``train crbm`` that are not the first level's config: the second
    level and the progress display."""

    level2: bool = _opt(False, f"also train a second level on the hidden activations; the "
                               f"two-level model is OUT/{STACK_FILE}")
    level2_hidden: int = _opt(CRBMConfig.n_hidden, "hidden units of the second level")
    level2_order: int = _opt(CRBMConfig.order, "frames of past of the second level")
    quiet: bool = _opt(False, "no progress")

    def __post_init__(self) -> None:
        # the second level's sizes obey the CRBM's own bounds, named as these fields
        for name, size in _LEVEL2_SIZE.items():
            try:
                CRBMConfig(**{size: getattr(self, name)})
            except MotionlangError as exc:
                raise MotionlangError(str(exc).replace(f"CRBMConfig.{size}",
                                                       f"CRBMRunOptions.{name}")) from None


def model_config(model_cfg: dict[str, Any]) -> CRBMConfig:
    """The first level's config: :data:`MODEL_DEFAULTS`, then the user's fields; the
    autoregressive weights learn at ``lr`` unless ``lr_autoregressive`` is given."""
    values = {**MODEL_DEFAULTS, **model_cfg}
    values.setdefault("lr_autoregressive", values["lr"])
    return CRBMConfig(**values)


def run(sources: Sequence, out_dir: Path, model_cfg: dict[str, Any], train_cfg: Any = None,
        data_cfg: CRBMRunOptions | None = None, *, resume: bool = False,
        options: dict | None = None) -> Path:
    """Train a CRBM on the CMU subject-35 folder ``sources[0]`` into the run folder
    ``out_dir``; ``model_cfg``: ``CRBMConfig`` fields over :data:`MODEL_DEFAULTS`;
    ``train_cfg``: accepted for the recipe signature and ignored (the CRBM trains with its
    own loop, configured by ``model_cfg``); ``options``: what to log in ``commands.jsonl``
    (default: the configs). Returns ``out_dir/model.npz``.

    Raises:
        MotionlangError: ``resume`` (a CRBM run cannot be resumed), not one folder, a bad
            config value, unreadable data.
    """

    if resume:
        raise MotionlangError("a CRBM run cannot be resumed: train it again")
    if len(sources) != 1:
        raise MotionlangError(f"train crbm reads one folder ({DATA_HELP}), got "
                              f"{len(sources)}")
    data_cfg = data_cfg if data_cfg is not None else CRBMRunOptions()
    config = model_config(model_cfg)   # checked before the data is read
    # level 2's visibles are hidden probabilities in [0, 1]: level 1's noise (normalised
    # units) does not carry over
    config2 = dataclasses.replace(config, visible="binary", n_hidden=data_cfg.level2_hidden,
                                  order=data_cfg.level2_order, history_noise=0.0)
    out = Path(out_dir)
    data = load_cmu35(str(sources[0]))
    seqs = [model_frames(c) for c in data.train]
    # the paper's fixed trials, no split of its own; the CMU database restricts no use
    note = begin_run(out, sources=(), what="CRBM", resume=False, options=options,
                     logged={"model": "crbm", "data": str(sources[0]),
                             **dataclasses.asdict(config), **vars(data_cfg)})
    model = CRBMModel(config, 59).fit(seqs, show_progress=not data_cfg.quiet)
    path = finish_run(out / family("crbm").model_file, model,
                      lambda: f"{out / family('crbm').model_file}: {model.describe()}", note)
    if data_cfg.level2:
        stack = CRBMStack.fit(model, seqs, config2, show_progress=not data_cfg.quiet)
        stack.save(out / STACK_FILE)
        print(f"{out / STACK_FILE}: two-level model, level 2 {stack.level2.describe()}")
    return path


CRBM = Recipe(run=run, data_config=CRBMRunOptions, model_defaults=MODEL_DEFAULTS,
              several_sources=False, trainer=False, data_help=DATA_HELP,
              run_files=f"{STACK_FILE} (with --level2)", extra_files=(STACK_FILE,))
