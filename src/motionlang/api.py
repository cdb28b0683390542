"""The Python API under the command line: one call per job, the same defaults as the CLI.

    >>> import motionlang as ml
    >>> walk = ml.generate("a person walks forward")   # a Motion, packaged L2M (expected frames)
    >>> walk
    Motion('generated': 58 frames at 12.5 Hz (4.6 s), 21 joints, from positions)
    >>> text, log_p = ml.describe(walk)[0]             # packaged M2L, beam width 5
    >>> "walks" in text
    True
    >>> path = ml.write_motion(walk, tmp / "walk.bvh")  # the 21-joint body, for Blender
    >>> ml.read_motion(path).n_frames
    58
    >>> ml.encode("a person walks").shape              # the L2M's summary of a sentence
    (128,)

Any motion file whose rig maps onto the 21-joint body works in place of ``walk``
(``joint_map=`` for rigs no built-in map fits). Generated motions are :class:`Motion`
objects on the 21-joint body (joint angles fitted to the positions) or, with
``rig="my_character.bvh"``, on your own skeleton. Models are packaged names
(``models.registry.PACKAGED``, each with a card), checkpoint files or run folders.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from motionlang.analysis import analyse, analyse_positions, check  # noqa: F401  (re-exported)
from motionlang.analysis.check import not_shown_line, unmet
from motionlang.analysis.words import warn_never_learnt
from motionlang.errors import MotionlangError
from motionlang.features.body21 import body21 as _body21
from motionlang.features.frames import motion_frames
from motionlang.features.joint_map import as_joint_map, kit21_weights, match_rig, positions21
from motionlang.formats import read_motion, write_motion
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.retarget import retarget as retarget_positions
from motionlang.library.compose import compose
from motionlang.library.describe import ReadOptions, describe_run
from motionlang.library.describe import describer as timeline_describer
from motionlang.library.index import build_index
from motionlang.library.options import DescribeOptions
from motionlang.library.rates import at_export_rate
from motionlang.library.search import search as run_search
from motionlang.models.family import load_object
from motionlang.models.inbetween import fill_between
from motionlang.models.options import ModelSpec, parse_model_spec
from motionlang.models.registry import describer, families, kinds_with
from motionlang.models.registry import load_model as _load
from motionlang.models.t2m import text_to_motion as wrap
from motionlang.models.word_map import WordsRead
from motionlang.recipes import train as run_recipe
from motionlang.rendering.output import body_motion, check_drawable, render_file, write_result


def load_model(name_or_path: str | Path, kind: str | tuple[str, ...] | None = None):
    """A model in eval mode from a packaged name (``"m2l"``, ``"l2m"``), a checkpoint file
    or a training run folder, whatever its kind (``kind=`` insists on one);
    ``motionlang.models.registry`` lists the kinds and the packaged models with their cards.
    """
    return _load(name_or_path, kind)


def text_to_motion(model: Any = None, options: Any = None):
    """A text-to-motion model behind the one interface (``models.t2m.TextToMotion``):
    ``model`` loaded, a packaged name, a checkpoint, a run folder, ``"NAME:key=value,..."``
    (its sampling options, ``models.options``) or None (the packaged L2M); ``options`` (a
    dict or the family's ``Options``) are applied after those of the text."""
    spec_options: dict = {}
    if model is None or isinstance(model, (str, Path)):
        name = str(model or "l2m")   # an existing file or folder is a name, whatever it holds
        spec = ModelSpec(name) if Path(name).exists() else parse_model_spec(name)
        spec_options = spec.options
        model = load_model(spec.name, kind=kinds_with("text_to_motion"))
    t2m = wrap(model)
    if spec_options or options is not None:
        merged = options if options is not None and not isinstance(options, dict) \
            else {**spec_options, **(options or {})}
        t2m.configure(merged)
    return t2m


_t2m = text_to_motion


def with_options(t2m: Any, options: dict[str, Any]) -> Any:
    """A text-to-motion model (``models.t2m.TextToMotion``) with more sampling options over
    its own: a new wrapper of the same model, so that one shared by several callers (the
    web app's) keeps its own; the family's ``Options`` checks them once. A ``method``
    its family has no option for is taken when it is the one way the model decodes.

    Raises:
        MotionlangError: an option the family does not take, or a value it refuses.
    """
    options = {k: v for k, v in options.items() if v is not None}
    fields = {f.name for f in dataclasses.fields(t2m.Options)} \
        if dataclasses.is_dataclass(t2m.Options) else set()
    if "method" in options and "method" not in fields:
        if options["method"] != t2m.default_method():
            raise MotionlangError(f"method {options['method']!r}: a {t2m.model.kind} model "
                                  f"decodes only by {t2m.default_method()!r}")
        del options["method"]
    if not options:
        return t2m
    return wrap(t2m.model, {**t2m.describe_options(), **options})


def read_mapped(path: str | Path, joint_map: dict | str | Path | None = None,
                **kw) -> Motion:
    """``read_motion`` with ``joint_map`` checked against the file's rig at once: a map that
    names joints the rig lacks, misses body joints or is malformed is refused here, naming
    the map file, not later inside a model."""
    motion = read_motion(path, joint_map=joint_map, **kw)
    if joint_map is not None:
        check_map(motion, joint_map)
    return motion


def check_map(motion: Motion, joint_map) -> None:
    """Raise MotionlangError (naming the map) unless ``joint_map`` maps ``motion``'s rig."""
    where = joint_map if isinstance(joint_map, (str, Path)) else "joint map"
    try:
        match_rig(motion.skeleton, joint_map=as_joint_map(joint_map))
    except MotionlangError as exc:
        said = str(exc)   # the map's own checks name it already
        raise MotionlangError(said if said.startswith(f"{where}:") or f"({where})" in said
                              else f"{where}: {said}") from None


#: how a user of the API reads a file at another rate than the one its body names
API_RATE_ADVICE = "ml.read_mapped(path).replace(fps=HZ) reads it at another rate"


def _motion(motion: Motion | str | Path, joint_map, *, timed: bool = True) -> Motion:
    """A Motion, or a file read (at the rate its body or export says, unless not
    ``timed``: a rig's rate is never used)."""
    if isinstance(motion, Motion):
        if joint_map is not None:
            check_map(motion, joint_map)
            motion = motion.replace(meta={**motion.meta, "joint_map": as_joint_map(joint_map)})
        return motion
    read = read_mapped(motion, joint_map)
    return at_export_rate(read, motion, joint_map=joint_map, advice=API_RATE_ADVICE) \
        if timed else read


def load_rig(rig: Motion | str | Path, joint_map: dict | str | Path | None = None) -> Motion:
    """A rig to write generated motions on, checked before anything is generated: its map
    onto the 21-joint body is found and its joints can be aimed (BVH-like rigs with full
    3-axis joints; hinge knees of ASF or MMM skeletons cannot be).

    Raises:
        MotionlangError: naming the rig file and the problem.
    """
    where = rig if isinstance(rig, (str, Path)) else rig.meta.get("path", rig.name)
    motion = _motion(rig, joint_map, timed=False)
    try:
        W = kit21_weights(motion.skeleton, joint_map=motion.meta.get("joint_map"))[1]
        retarget_positions(positions21(motion[:1]), motion.fps, motion, weights=W)  # one-frame trial
    except MotionlangError as exc:
        raise MotionlangError(f"rig {where}: {exc}") from None
    return motion


def first_frame(model, start: Motion | str | Path,
                joint_map: dict | str | Path | None = None) -> np.ndarray:
    """(F,) model features of the first pose of ``start`` (a Motion or file), for L2M models
    to begin their motions with."""
    t2m = _t2m(model)
    if not t2m.takes_start_pose:
        raise MotionlangError(f"a start pose applies to L2M models, not {t2m.model.kind}")
    return motion_frames(t2m.model.features, _motion(start, joint_map), 1)[0][0]


def describe(motion: Motion | str | Path, model: Any = None, width: int | None = None, *,
             joint_map: dict | str | Path | None = None, **options: Any
             ) -> list[tuple[str, float]]:
    """Sentences for a motion (a Motion or a file), best first: ``[(text, log P), ...]``.

    model: a loaded model whose family describes motion (``Family.describes``: the M2L), a
    packaged name, a checkpoint path, or None for the packaged M2L. width, options: the
    beam's fields of ``library.options.DescribeOptions``, each with its one default there
    (as ``motionlang describe``'s options): ``width`` (beam width and number of
    sentences), ``length_penalty``, ``rank`` ("mbr" puts first the sentence the beam agrees
    on most, ``models.seq2seq.decode.mbr``; "logp" the likeliest, the paper's) and ``raw``
    (the beam as it is, not checked against what the body does:
    ``models.seq2seq.decode.grounded``)."""
    beam = ("length_penalty", "rank", "raw")
    other = sorted(set(options) - set(beam))
    if other:
        raise MotionlangError(f"describe takes the options width, {', '.join(beam)}; not "
                              f"{', '.join(other)}")
    given: dict[str, Any] = {**options, **({} if width is None else {"width": width})}
    o = DescribeOptions(**given)
    if model is None or isinstance(model, (str, Path)):
        model = load_model(model or "m2l", kind=kinds_with("describes"))
    return describer(model)(model, _motion(motion, joint_map), width=o.width,
                            length_penalty=o.length_penalty, rank=o.rank, grounded=not o.raw)


def describe_many(paths: Any, model: Any = None, *, joint_map: dict | str | Path | None = None,
                  source_fps: float | None = None, show_progress: bool | None = False,
                  **options: Any) -> list[dict]:
    """One record per motion file of ``paths`` (a file or folder, or a list of them; folders
    recursively), what ``motionlang describe PATHS -o FILE.jsonl`` writes a line of:
    ``{"file", "sentences": [{"text", "log_p"}, ...]}``, ``"segments"`` instead with
    ``segments=True``, ``"cos"`` scores with a ``bank``, ``{"file", "error"}`` for a file that
    cannot be read. ``options``: the fields of ``library.describe.DescribeOptions``
    (``width``, ``rank``, ``segments``, ``window``, ``hop``, ``merge``, ``bank``, ``workers``).
    ``source_fps``: the rate every file is read at (as ``--source-fps``; None: each file's
    own, or the one its body or its export's other files say, ``library.rates``)."""
    run = describe_run([paths] if isinstance(paths, (str, Path)) else paths, model,
                       DescribeOptions(**options),
                       read=ReadOptions(fps=source_fps, joint_map=joint_map))
    return list(run.records(show_progress=show_progress))


def timeline(motion: Motion | str | Path, model: Any = None, *,
             joint_map: dict | str | Path | None = None, **options: Any) -> list:
    """A long take (a Motion or file) as ``library.timeline.Segment``s (``start``, ``end``
    seconds, ``text``, ``score``), as ``motionlang describe --segments`` prints it;
    ``options`` as :func:`describe_many`'s."""
    d = timeline_describer(model, DescribeOptions(**{**options, "segments": True}))
    return d.timeline(_motion(motion, joint_map))


def generate_hypotheses(text: str, model: Any = None, *, seed: int = 0,
                        max_frames: int | None = None, min_frames: int = 5,
                        start_from: Motion | str | Path | None = None,
                        joint_map: dict | str | Path | None = None, foot_lock: bool = True,
                        keep: Any = None, **options: Any
                        ) -> tuple[list[tuple[Any, float]], float]:
    """Every hypothesis ``motionlang generate`` makes for ``text``, best first, and their
    frame rate: ``([(result, score), ...], fps)``; a result is a Motion (joint-angle
    models) or global 21-joint positions (T, 21, 3) metres; the score is the log likelihood
    (with ``rerank``: the M2L's log P(text | motion)), NaN for deterministic models.

    model: as :func:`text_to_motion` (None: the packaged L2M; ``"NAME:key=value"`` sets
    its sampling options). options: more of those sampling options, over the model's: the
    fields of its family's ``Options`` (the L2M's ``models.seq2seq.t2m.L2MOptions``:
    ``width``, ``method``, ``temperature``, ``length_norm``, ``rerank``; the masked model's
    ``steps``, ``guidance``, ``temperature``, ``width`` ...), each with its one default
    there; ``method`` may also name the one way a model without that option decodes.
    max_frames: length cap in model frames (a model told its length generates exactly
    this many). min_frames: no end before this many frames. start_from: a Motion or file
    whose first pose begins every motion (``joint_map``: its map, if no built-in map fits).
    foot_lock: move the body with its planted feet and hold them (position models). keep:
    ``"FILE:0-2s,8-10s"`` or ``(motion, [(t0, t1), ...])``: in-betweening of those seconds.

    Raises: MotionlangError: options that contradict each other or the model (checked first).
    """
    if not isinstance(text, str):
        raise MotionlangError(f"the text to generate from must be a sentence (a str), got "
                              f"{type(text).__name__}")
    if max_frames is not None and min_frames > max_frames:
        raise MotionlangError(f"--min-frames {min_frames} exceeds --max-frames {max_frames}")
    t2m = with_options(text_to_motion(model), options)
    kw: dict[str, Any] = {}
    if getattr(t2m, "reranker", None) is not None:
        kw["reranker"] = t2m.reranker
    import warnings
    reading = t2m.read_words(text)
    if reading.mapped:   # shown, so that a user sees which word steered instead of theirs
        warnings.warn(reading.message(), WordsRead, stacklevel=2)
    unknown = reading.unknown
    if unknown:   # a warning, not an error: the rest of the sentence still steers
        vocab = getattr(t2m.model, "vocab", None)
        each = "each is" if len(unknown) > 1 else "it is"
        warnings.warn(f"the model does not know {', '.join(repr(w) for w in unknown)}; {each} "
                      f"read as an unknown word (its vocabulary: {len(vocab or ())} words)",
                      UserWarning, stacklevel=2)
    warn_never_learnt(text, t2m.model)
    if keep is not None:   # the kept seconds of a motion, the rest from the text
        return fill_between(t2m, text, keep, lambda m: _motion(m, joint_map), seed=seed,
                            foot_lock=foot_lock), t2m.fps
    if start_from is not None:
        kw["first_frame"] = first_frame(t2m, start_from, joint_map)
    hyps = t2m.hypotheses(text, seed=seed, max_frames=max_frames, min_frames=min_frames,
                          foot_lock=foot_lock, **kw)
    if hyps:
        _warn_not_shown(text, hyps[0][0], t2m.fps)
    return hyps, t2m.fps


#: s: a motion made shorter than this (a cap on its frames) is not checked against its
#: sentence: too short for the analysis to see a walk (0.8 s of travel) or a wave's swings
CHECK_SHORTEST = 1.5


def _warn_not_shown(text: str, result: Any, fps: float, *, hint: bool = True) -> None:
    """One warning where the motion made for ``text`` (a Motion, or (T, 21, 3) positions at
    ``fps``) does not do an action of it as the sentence says (the open-world check,
    ``analysis.check.unmet``), naming them: a model asked for two things in a row often
    makes one."""
    import warnings
    seconds = (result.n_frames if isinstance(result, Motion) else len(result)) / fps
    if seconds < CHECK_SHORTEST:
        return
    try:
        missed = unmet(text, analyse(result) if isinstance(result, Motion) else
                       analyse_positions(np.asarray(result), fps))
    except MotionlangError:   # too short to analyse, or nothing it can read
        return
    if missed:
        warnings.warn(not_shown_line(missed) + ("; --library composes a sentence from the "
                                                "takes of your own index" if hint else ""),
                      UserWarning, stacklevel=3)


def read_words(text: str, model: Any = None):
    """How a text-to-motion model (as :func:`text_to_motion`; None: the packaged L2M) reads
    ``text``: a ``models.word_map.WordReading`` with ``mapped`` (each unknown word, the
    known word read instead, their similarity), ``unknown`` (words still unknown) and
    ``text`` (the sentence it decodes); ``message()`` is what ``generate`` prints."""
    return text_to_motion(model).read_words(text)


def generate(text: str, model: Any = None, *, rig: Motion | str | Path | None = None,
             rig_joint_map: dict | str | Path | None = None, library: Any = None,
             **options: Any) -> Motion:
    """A motion for ``text`` (the best of ``width`` hypotheses), as a :class:`Motion`: on
    the 21-joint body, or with ``rig`` (a Motion or motion file; ``rig_joint_map``: its map
    onto the 21-joint body, if no built-in map fits) retargeted onto that skeleton.
    ``options``: those of :func:`generate_hypotheses` (``width``, ``method``, ``seed``,
    ``max_frames``, ``start_from`` ...), the same as ``motionlang generate``'s.
    ``library``: an index file (or open ``library.search.Library``): the motion is composed
    of its clips (``library.compose``; ``model``: the index's model) instead of generated;
    ``library.compose.compose`` gives the clips too.
    """
    rig_motion = None if rig is None else load_rig(rig, rig_joint_map)
    if library is not None:
        made = compose(text, library, model=model)
        _warn_not_shown(text, made.positions, made.fps, hint=False)
        return body_motion(made.positions, made.fps, rig_motion)[0]
    hyps, fps = generate_hypotheses(text, model, **options)
    return body_motion(hyps[0][0], fps, rig_motion)[0]


def body21(motion: Motion | str | Path, *, joint_map: dict | str | Path | None = None,
           stature: float | None = None) -> np.ndarray:
    """Any motion (or file) -> (T, 21, 3) metres on the common 21-joint body: feet on the
    floor, frame 0 at the origin facing +Z, scaled to ``stature`` metres if given."""
    return _body21(_motion(motion, joint_map), stature=stature)


def retarget(motion: Motion | str | Path, rig: Motion | str | Path, *,
             joint_map: dict | str | Path | None = None,
             rig_joint_map: dict | str | Path | None = None) -> Motion:
    """``motion`` (any rig) moved onto ``rig``'s skeleton through the 21-joint body."""
    src = _motion(motion, joint_map)
    return body_motion(positions21(src), src.fps, load_rig(rig, rig_joint_map),
                       name=src.name)[0]


def render(motion: Motion | str | Path, path: str | Path, *, title: str | None = None,
           joint_map: dict | str | Path | None = None, **options: Any) -> Path:
    """Draw a motion (a Motion or a file): ``.gif`` / ``.mp4`` animation or ``.png`` pose
    strip, as ``motionlang render``; ``title`` defaults to the motion's name, ``options``
    are those of ``rendering.output.render_file`` (``n_poses``, ``fps``, ``camera``,
    ``trajectory``). Returns the path written."""
    check_drawable(path)   # before a file is read
    m = _motion(motion, joint_map)
    return render_file(m, path, title=m.name if title is None else title, **options)


def encode(x: Motion | str | Path, model: Any = None, *,
           joint_map: dict | str | Path | None = None) -> np.ndarray:
    """A sentence or a motion -> one vector (D,) float32, the model's summary of it.

    A ``str`` that names no file is a sentence, anything else a motion (a Motion or a
    motion file). ``model``: any model whose family encodes that side
    (``Family.encodes_text`` / ``encodes_motion``); default the packaged L2M for sentences
    (its text encoder) and the packaged M2L for motions (its motion encoder). A two-stream
    model puts both in one space (its embeddings are trained to meet); the seq2seq encoders
    do not, so compare sentences with sentences, motions with motions.
    """
    is_text = isinstance(x, str) and not Path(x).is_file()
    side = "text" if is_text else "motion"
    capability = f"encodes_{side}"
    kinds = kinds_with(capability)
    if model is None or isinstance(model, (str, Path)):
        model = load_model(model or ("l2m" if is_text else "m2l"), kind=kinds)
    kind = getattr(model, "kind", None)
    fam = families().get(kind) if isinstance(kind, str) else None
    spec = None if fam is None else getattr(fam, capability)
    if spec is None:
        raise MotionlangError(f"a {kind or type(model).__name__} model does not encode "
                              f"{side}s (models that do: {', '.join(kinds)})")
    return load_object(spec)(model, x if is_text else _motion(x, joint_map))


def fill_in(frames: np.ndarray, known: np.ndarray, model: Any, *, n_gibbs: int = 30,
            seed: int = 0) -> np.ndarray:
    """Fill in lost values of a motion with a CRBM (Taylor et al. 2006, sec. 5).

    frames: (T, D) in the model's own frame space (the channels it was trained on, e.g.
    ``datasets.cmu35.model_frames`` of CMU subject 35's AMC channels); entries
    where ``known`` is False are ignored and filled. known: (T, D) bool; the first
    ``order`` frames must be complete. model: a CRBM, its ``.npz`` or a run folder.
    Returns (T, D): the known values kept, the rest filled frame by frame by Gibbs sampling
    given the past and the known values of each frame.
    """
    if model is None or isinstance(model, (str, Path)):
        if model is None:
            raise MotionlangError("fill_in needs a CRBM (train one: motionlang train crbm)")
        model = load_model(model, kind="crbm")
    frames, known = np.asarray(frames, dtype=np.float64), np.asarray(known, dtype=bool)
    if frames.ndim != 2 or frames.shape != known.shape:
        raise MotionlangError(f"frames {frames.shape} and known {known.shape} must be the "
                              "same (T, D) shape")
    if frames.shape[1] != model.n_visible:
        raise MotionlangError(f"frames have {frames.shape[1]} values a frame; this CRBM "
                              f"models {model.n_visible}")
    return model.fill_in(frames, known, n_gibbs=n_gibbs, seed=seed)[0]   # one sample


def train(kind: str, data: str | Path | list, out: str | Path, *, resume: bool = False,
          **options: Any) -> Path:
    """Train a ``kind`` model (``"m2l"``, ``"l2m"``, any family with a recipe) on ``data``
    (a ``--data`` value such as ``"corpus"`` or ``"bandai:DIR@1"``, or a list of them) into
    the run folder ``out``, as ``motionlang train KIND``; ``options`` are the fields of the
    model's config, the trainer's (``epochs``, ``lr``, ...) and the recipe's data options
    (``features``, ``offsets``, ...). Returns the trained model's path (``out/model.pt``).
    """
    return run_recipe(kind, data, out, resume=resume, **options)


def index(folder: str | Path, out: str | Path, model: Any = None, **options: Any):
    """Index every motion file under ``folder`` (recursively, any rig) into the file ``out``,
    as ``motionlang index``: each take cut into overlapping windows, each window embedded by
    ``model`` (a name, checkpoint or loaded model whose family encodes sentences and
    motions; default the packaged ``retrieval`` model). A second run embeds only new or
    changed files. ``options``: ``window``, ``hop`` (seconds), ``rebuild``
    (``library.options.IndexOptions``). Returns a ``library.index.IndexSummary``; files that
    do not read are in its ``failed``, with their reasons."""
    return build_index(folder, out, model, **options)


def search(query: str, index: Any, k: int | None = None, *, model: Any = None,
           render: str | Path | None = None, **options: Any) -> list:
    """The best matches of ``query`` in an index file (or an open ``library.search.Library``),
    as ``motionlang search``: ``[(file, start, end, score, why)]`` (``library.search.Hit``),
    best first; ``k`` (10) and ``options`` (``where``, ``min_duration``, ``rig``,
    ``path_glob``, ``grounded``): ``library.options.SearchOptions``; ``render``: a .png."""
    return run_search(query, index, k, model=model, render=render, **options)


__all__ = ["read_motion", "write_motion", "read_mapped", "load_model", "describe",
           "describe_many", "timeline",
           "generate", "encode", "fill_in", "body21", "retarget", "render", "body_motion",
           "load_rig", "first_frame", "check_map", "train", "text_to_motion",
           "generate_hypotheses", "write_result", "index", "search"]
