"""The papers' yardstick (Guo et al. 2022) run on a dataset: ``evaluate-t2m --protocol guo``
as library functions.

A run: :func:`load_evaluator` (one trained here, or the public weights), the text-to-motion
models to score (:func:`model_specs` names the default, :func:`check_models` checks them
against the options), :meth:`GuoRun.prepare` (the dataset's test pairs on the evaluator's
body), then :meth:`GuoRun.text_to_motion` (ground truth, nearest neighbour, standing still
and each model, ``yardstick.guo_table``) and :meth:`GuoRun.motion_to_text` (the M2L models'
descriptions, ``m2t.m2t_table``), each a table and its Markdown; :meth:`GuoRun.report` and
:func:`write_guo_files` keep them. :class:`GuoOptions` holds the protocol's settings; its
errors name its fields (``GuoOptions.rp_batch``), which the command line turns into its
options. torch is imported inside the functions only.
"""
from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motionlang.datasets.evaluator_items import build_evaluator_data
from motionlang.errors import MotionlangError
from motionlang.evaluation.sampling import stratified_sample
from motionlang.evaluation.t2m.plots import plot_yardstick
from motionlang.evaluation.t2m.yardstick import (
    evaluator_body,
    generated_rows,
    guo_table,
    markdown_table,
    test_pairs,
)
from motionlang.models.evaluator.text import TextFileVectors
from motionlang.models.registry import load_model
from motionlang.utils.atomic import atomic_write
from motionlang.utils.checks import check_numbers

FID_REFERENCES = ("train", "val")
#: the pairs MultiModality draws among each caption's samples (the papers')
MM_PAIRS = 10


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class GuoOptions:
    """The settings of the yardstick (``evaluate-t2m --protocol guo`` options)."""

    repeats: int = _opt(20, "shuffles of the test pairs; each figure is their mean and its "
                            "95-percent interval")
    rp_batch: int = _opt(32, "R-precision and MM-Dist among batches of B pairs", metavar="B")
    multimodality: int = _opt(0, "also MultiModality of the models that sample: S > 10 "
                                 "samples for each of --mm-texts captions (the papers: 30 and "
                                 "100; 0: not measured)", metavar="S")
    mm_texts: int = _opt(100, "captions MultiModality samples for")
    fid_reference: str = _opt("train", "the real motions the ground truth's FID compares the "
                                       "test motions with (val: held out like them, when the "
                                       "training split holds data the test split has not, e.g. "
                                       "Bandai's dataset 1)",
                              choices=FID_REFERENCES)
    regenerate: bool = _opt(False, "the models that sample (e.g. --model l2m:method=sample) "
                                   "generate anew for each of the --repeats, as the papers "
                                   "do (that many times the generation time); default: one "
                                   "generation, its pairs reshuffled")
    m2l_width: int = _opt(5, "the M2L's beam width (its best hypothesis is scored)",
                          metavar="W")

    def __post_init__(self) -> None:
        check_numbers("GuoOptions", self, positive_ints=("repeats", "mm_texts", "m2l_width"),
                      nonneg_ints=("multimodality",))
        if not (isinstance(self.rp_batch, int) and self.rp_batch >= 2):
            raise MotionlangError(f"GuoOptions.rp_batch must be an integer >= 2, got "
                                  f"{self.rp_batch!r}")
        if 0 < self.multimodality <= MM_PAIRS:
            raise MotionlangError(f"GuoOptions.multimodality {self.multimodality}: need more "
                                  f"than {MM_PAIRS} samples a caption ({MM_PAIRS} pairs are "
                                  "drawn among them)")
        if self.fid_reference not in FID_REFERENCES:
            raise MotionlangError(f"GuoOptions.fid_reference must be train or val, got "
                                  f"{self.fid_reference!r}")


def draws(t2m) -> bool:
    """Whether a text-to-motion model's motions change with the seed under its options: not
    deterministic, and not told ``method=mean`` (what an evaluation row decodes by
    default, ``cli.models_arg.load_t2m``)."""
    return not t2m.deterministic and getattr(t2m.options, "method", None) != "mean"


def load_evaluator(path: str | Path | None = None, *, official: str | Path | None = None,
                   mean: str | Path | None = None, std: str | Path | None = None,
                   word_vectors: str | Path | None = None):
    """A text-motion evaluator: ``path`` (a file, run folder or packaged name), or the public
    weights ``official`` (``finest.tar`` of EricGuo5513/text-to-motion) with their ``mean``
    and ``std`` (``.npy``); ``word_vectors``: a GloVe-format text file of the evaluator's
    word size (default: the built-in GloVe 50d).

    Raises:
        MotionlangError: neither ``path`` nor ``official``, a missing or damaged file, word
            vectors of another size.
    """
    from motionlang.models.evaluator.model import TextMotionEvaluator
    if path is None and official is None:
        raise MotionlangError("an evaluator is needed: its file, or the public weights with "
                              "their mean and std")
    vectors = None
    if word_vectors:
        vectors = TextFileVectors(word_vectors)
    if official:
        model = TextMotionEvaluator.load_official(official, mean, std, vectors=vectors)
    else:
        assert path is not None
        model = load_model(path, kind="evaluator", vectors=vectors)
    if vectors is not None and vectors.dim != model.config.word_dim:
        raise MotionlangError(f"word vectors {word_vectors}: {vectors.dim}-d words, the "
                              f"evaluator reads {model.config.word_dim}-d ones")
    return model


def model_specs(evaluator, specs: Sequence[str] | None) -> list[str]:
    """The text-to-motion models to score: ``specs`` (``--model`` values), default the
    packaged l2m; none on an SMPL-body evaluator, which cannot read their 21-joint motions."""
    kit = evaluator_body(evaluator) == "kit"
    out = list(specs or (["l2m"] if kit else []))
    if out and not kit:
        raise MotionlangError("the models' 21-joint motions cannot be scored by an SMPL-body "
                              "(263-value) evaluator; use a kit-body (251) one")
    return out


def check_models(models: dict, options: GuoOptions) -> None:
    """The loaded models against the options, before any data is read."""
    if options.regenerate and not any(draws(m) for m in models.values()):
        raise MotionlangError("GuoOptions.regenerate needs a model that samples, e.g. --model "
                              "l2m:method=sample (the others give the same motions every "
                              "time)")


def model_rows(models: dict, captions: list[str], frames: list[int], bones=None, *,
               seed: int = 0, options: GuoOptions | None = None) -> tuple[dict, dict]:
    """Each text-to-motion model's rows for the captions with its own options (a function
    of the repetition with ``options.regenerate``, for the models that sample), and with
    ``options.multimodality`` S samples for the first ``mm_texts`` captions; laid on
    ``bones`` (the evaluator's) if given."""
    options = options or GuoOptions()
    gen: dict[str, Any] = {}
    for name, m in models.items():
        if options.regenerate and draws(m):
            # a new generation for each repetition, seeds seed, seed + 1, ... (the papers')
            gen[name] = (lambda i, m=m, name=name: generated_rows(
                m, captions, frames, seed=seed + i, desc=f"{name} #{i + 1}", bones=bones))
        else:
            gen[name] = generated_rows(m, captions, frames, seed=seed, desc=name, bones=bones)
    samples = {}
    if options.multimodality:
        n = min(options.mm_texts, len(captions))
        for name, m in models.items():
            if m.deterministic:   # one motion a caption: nothing to measure
                continue
            samples[name] = [[generated_rows(m, [c], [f], method="sample", seed=k,
                                             desc=f"{name} sample", bones=bones)[0]
                              for k in range(options.multimodality)]
                             for c, f in zip(captions[:n], frames[:n])]
    return gen, samples


@dataclass
class GuoRun:
    """The test pairs of a dataset read on an evaluator's body, and the settings every
    table of the run shares. ``data``: ``datasets.evaluator_items.EvaluatorData``;
    ``pairs``: one item per test motion (``yardstick.test_pairs``); ``reference``: the
    items the ground truth's FID compares with (None: the training split's)."""

    evaluator: Any
    evaluator_name: str
    source: str
    data: Any
    split: str
    pairs: list[dict]
    reference: list[dict] | None
    seed: int
    options: GuoOptions

    @classmethod
    def prepare(cls, evaluator, data, *, evaluator_name: str = "", split: str = "test",
                seed: int = 0, max_seconds: float | None = 30.0, limit: int = 0,
                options: GuoOptions | None = None) -> GuoRun:
        """Read ``data`` (anything ``build_evaluator_data`` reads) as the evaluator's rows
        (its body, its bones), split with ``seed``; ``limit`` pairs drawn with it (0: all).

        Raises:
            MotionlangError: unreadable data, fewer test pairs than a batch, a FID
                reference split with fewer than 2 motions.
        """
        options = options or GuoOptions()
        built = build_evaluator_data(data, evaluator_body(evaluator), seed=seed,
                                     max_seconds=max_seconds, bones=evaluator.config.bones)
        pairs = test_pairs(built.items.get(split) or [], seed)
        pairs = [pairs[i] for i in stratified_sample(len(pairs), limit, seed=seed)]
        if len(pairs) < options.rp_batch:
            raise MotionlangError(f"{data}: {len(pairs)} {split} motions, R-precision needs "
                                  f"at least GuoOptions.rp_batch {options.rp_batch}")
        reference = None
        if options.fid_reference != "train":
            reference = built.items.get(options.fid_reference) or []
            if len({it["id"] for it in reference}) < 2:
                raise MotionlangError(f"GuoOptions.fid_reference {options.fid_reference}: "
                                      f"{data} has fewer than 2 {options.fid_reference} "
                                      "motions")
        return cls(evaluator, evaluator_name, str(data), built, split, pairs, reference,
                   seed, options)

    @property
    def body(self) -> str:
        return evaluator_body(self.evaluator)

    def text_to_motion(self, models: dict) -> tuple[dict, str]:
        """The text-to-motion table (``yardstick.guo_table``) with a row per model
        (``{label: models.t2m.TextToMotion}``), and its Markdown with a title."""
        o = self.options
        captions = [p["caption"] for p in self.pairs]
        frames = [len(p["motion"]) + 1 for p in self.pairs]   # rows: steps between frames
        gen, samples = model_rows(models, captions, frames, self.data.bones, seed=self.seed,
                                  options=o)
        table = guo_table(self.evaluator, self.pairs, self.data.items.get("train") or [], gen,
                          samples=samples, reference_items=self.reference, repeats=o.repeats,
                          seed=self.seed, batch_size=o.rp_batch)
        against = "training" if o.fid_reference == "train" else o.fid_reference
        title = (f"{len(self.pairs)} {self.split} pairs of {self.source}, evaluator "
                 f"{self.evaluator_name} ({self.body} body"
                 f"{', every motion laid on one body' if self.data.bones else ''}); mean ± "
                 f"95 % interval over {o.repeats} shuffles, R-precision in batches of "
                 f"{o.rp_batch}; FID against the test motions (ground truth: test against "
                 f"{against} motions); retrieval (t2m R@k %, MedR) among all pairs")
        return table, markdown_table(table, title)

    def motion_to_text(self, m2l_models: dict) -> tuple[dict, str]:
        """The motion-to-text table (``m2t.m2t_table``) of the M2L models (``{label:
        model}``) on the test motions, and its Markdown ("" when there are none)."""
        if not m2l_models:
            return {}, ""
        from motionlang.evaluation.t2m.m2t import describe_motions, m2t_table
        o = self.options
        records = [self.data.records[p["id"]] for p in self.pairs]
        motions = [r.load_motion() for r in records]
        described: dict[str, Sequence[str]] = {
            name: describe_motions(m, motions, width=o.m2l_width, desc=name)
            for name, m in m2l_models.items()}
        table, counted = m2t_table(self.evaluator, self.pairs, [r.annotations for r in records],
                                   self.data.items.get("train") or [], described,
                                   repeats=o.repeats, seed=self.seed, batch_size=o.rp_batch)
        title = (f"Motion to text, the same {len(self.pairs)} test motions: each row's "
                 f"description (M2L: best of a beam of {o.m2l_width}) against the motion's "
                 f"other captions (BLEU, ROUGE-L, CIDEr; {counted} motions have one) and "
                 f"ranked by the evaluator among batches of {o.rp_batch} motions (mean ± 95 % "
                 f"interval over {o.repeats} shuffles); ground truth: the pair's own caption")
        return table, markdown_table(table, title)

    def report(self, rows: dict, m2t_rows: dict, models: dict[str, str],
               m2l: dict[str, str]) -> dict:
        """The run as JSON: its settings, the tables' rows, the models as given (``{label:
        spec}``)."""
        return {"protocol": "guo", "data": self.source, "split": self.split,
                "evaluator": self.evaluator_name, "body": self.body, "pairs": len(self.pairs),
                "repeats": self.options.repeats, "rp_batch": self.options.rp_batch,
                "models": models, "rows": rows, "m2l": m2l, "m2t_rows": m2t_rows}


def write_guo_files(out: str | Path, text: str, report: dict) -> None:
    """``t2m_guo.md`` (``text``), ``t2m_guo.json`` (``report``, :meth:`GuoRun.report`) and
    ``t2m_guo.png`` in ``out`` (atomic writes)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_write(out / "t2m_guo.md") as fh:
        fh.write(text)
    with atomic_write(out / "t2m_guo.json") as fh:
        fh.write(json.dumps(report, indent=1, default=list) + "\n")
    plot_yardstick(report["rows"], out / "t2m_guo.png", report.get("m2t_rows") or None,
                   title=f"{report['pairs']} {report['split']} pairs of {report['data']}")
