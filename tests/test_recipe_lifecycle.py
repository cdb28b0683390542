"""Every registered recipe through ``ml.train``: one tiny run, then a resume of it; the run
folder holds the same files after both (the lifecycle of ``recipes.run_recipe`` and the
recipe's own steps agree for every family), and the command log gains a line."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from helpers.data import bandai_folder, shared_file
from helpers.patching import patch_everywhere
from motionlang.models.registry import family, kinds_with
from motionlang.training import run_steps

SRC = Path(__file__).resolve().parents[1] / "src" / "motionlang"

pytest.importorskip("torch")

SEQ2SEQ = dict(epochs=1, batch_size=8, offsets=2, enc_hidden=8, dec_hidden=16, embed_dim=8,
               dec_layers=2)
#: the tiny options of each trainable kind (its data: "corpus", "bandai" or "cmu35")
TINY = {
    "m2l": ("corpus", SEQ2SEQ),
    "l2m": ("corpus", SEQ2SEQ),
    "twostream": ("corpus", dict(h=8, h1=4, h2=8, text_layers=[6], epochs=1, batch_size=16,
                                 max_frames=12, progress=False)),
    "evaluator": ("corpus", dict(epochs=1, batch_size=16, as_given=True, embed_dim=8,
                                 text_hidden=8, motion_hidden=8, movement_hidden=8,
                                 movement_latent=8)),
    "retrieval": ("corpus", dict(hidden=16, layers=1, heads=2, text_hidden=16, embed=8,
                                 window=2.0, epochs=1, batch_size=8, progress=False,
                                 plot=False)),
    "masked": ("corpus", dict(width=16, depth=1, code_dim=8, codes=16, quantizers=3,
                              hidden=16, layers=1, res_layers=1, heads=2, window=2.56,
                              tokenizer_epochs=1, tokenizer_batch=8, epochs=1, batch_size=8,
                              progress=False, plot=False)),
    "judge": ("bandai", dict(epochs=1, mirror=False, plot=False, hidden=8, embed=8, layers=2,
                             kernel=3, window=12)),
    "crbm": ("cmu35", dict(n_hidden=6, epochs=2, quiet=True)),
}


def run_files(out: Path) -> list[str]:
    """The run folder's files (recursively, relative), hidden ones left out."""
    return sorted(str(p.relative_to(out)) for p in out.rglob("*")
                  if p.is_file() and not any(part.startswith(".")
                                             for part in p.relative_to(out).parts))


@pytest.fixture(scope="module")
def data(tmp_path_factory) -> dict[str, Path]:
    from motionlang.datasets.synth import write_corpus
    root = tmp_path_factory.mktemp("lifecycle")
    corpus = root / "corpus"
    write_corpus(corpus, n=16, seed=3, workers=1, show_progress=False)
    return {"corpus": corpus, "bandai": root / "bandai-lazy", "cmu35": root / "cmu35-lazy",
            "root": root}


def _source(kind: str, data: dict[str, Path]) -> Path:
    name = TINY[kind][0]
    if name == "bandai":
        return bandai_folder(data["root"] / "b")
    if name == "cmu35":
        return shared_file("cmu35/cmu35WalkJog.mat").parent
    return data[name]


def test_every_trainable_kind_is_under_the_lifecycle_test():
    assert sorted(TINY) == sorted(kinds_with("recipe"))


@pytest.mark.parametrize("kind", sorted(TINY))
def test_a_fresh_run_and_its_resume_leave_the_same_files(kind, data, tmp_path, monkeypatch,
                                                         capsys):
    import motionlang as ml
    from motionlang.errors import MotionlangError
    from motionlang.recipes import recipe_of
    monkeypatch.setenv("MOTIONLANG_CACHE", str(data["root"] / "cache"))
    source = _source(kind, data)
    options = TINY[kind][1]
    out = tmp_path / "run"
    steps: list[str] = []
    recipe_of(kind)   # its module loaded, so that the spies below replace its bindings
    for name in ("begin_run", "finish_run"):
        real = getattr(run_steps, name)
        patch_everywhere(monkeypatch, run_steps, name,
                         lambda *a, _real=real, _name=name, **k: steps.append(_name)
                         or _real(*a, **k))
    path = ml.train(kind, str(source), out, **options)
    fresh = run_files(out)
    # the run folder's steps, once each and in order (the masked recipe saves its model at
    # the end of its second stage)
    assert steps == (["begin_run"] if kind == "masked" else ["begin_run", "finish_run"])
    assert path == out / family(kind).model_file and path.is_file()
    assert {"run.json", "commands.jsonl", family(kind).model_file} <= set(fresh)
    log = (out / "commands.jsonl").read_text(encoding="utf-8").splitlines()
    assert len(log) == 1 and json.loads(log[0])
    if not recipe_of(kind).trainer:   # a model with its own loop (the CRBM) cannot resume
        with pytest.raises(MotionlangError, match="resume"):
            ml.train(kind, str(source), out, resume=True, **options)
        assert run_files(out) == fresh
        return
    ml.train(kind, str(source), out, resume=True, **{**options, "epochs": 2})
    assert run_files(out) == fresh
    assert len((out / "commands.jsonl").read_text(encoding="utf-8").splitlines()) == 2
    capsys.readouterr()


def test_recipes_write_the_run_files_through_the_shared_steps():
    """No recipe writes the split, the licence or the command log itself."""
    for path in sorted((SRC / "recipes").glob("*.py")):
        text = path.read_text(encoding="utf-8")
        for name in ("keep_splits", "write_licence", "log_command", "save_splits"):
            assert name not in text, f"{path.name} calls {name}: use training.run_steps"
