"""Search an index by text: the takes and time spans whose windows best match a sentence.

The sentence is embedded by the index's model and compared with every window by cosine
similarity. Windows are taken best first. A window that overlaps (or touches) a hit of its
own take joins that hit, widening its span, when it scores at least half-way from the
typical window (the median score) to the hit's best: a span is where the take matches
about as well as at its peak, as a peak's width is read at half its height. Any other
window starts a new hit, until ``k`` hits exist. A hit runs from the start of its first
window to the end of its last; its score is its best window's.

Where the query names actions the analysis finds (``library.grounded``) and the index holds
its findings, the takes that show them come first: a hit for each group of such findings,
ordered by how many of the query's actions it shows, then by its best window's cosine plus
the findings' confidence, each saying why (``sits: 12.4-15.0 s``); the learned hits follow.
Filters (``SearchOptions``: ``where``, ``min_duration``, ``rig``, ``path_glob``) decide
which takes and spans may give hits at all.

Scores come from one matrix product in numpy; where ``faiss`` is installed and the index is
large, an exact inner-product index of faiss gives the same hits behind the same call (it
is optional, not a dependency) for a search that neither filters nor matches actions.
"""
from __future__ import annotations

import importlib.util
import warnings
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from motionlang.analysis.words import actions_named
from motionlang.errors import MotionlangError
from motionlang.library import ann
from motionlang.library.embedder import Embedder
from motionlang.library.grounded import (
    matches,
    path_allowed,
    query_actions,
    verb,
    where_actions,
)
from motionlang.library.options import BACKENDS, SearchOptions
from motionlang.library.scan import read_takes
from motionlang.library.sheet import contact_sheet
from motionlang.library.store import Entry, IndexData, load_index

#: windows from which faiss, when installed, is used instead of numpy (exact both)
FAISS_MIN_ROWS = 200_000
#: windows from which ``auto`` takes the approximate graph (``library.ann``), when usearch is
#: installed: below it exact search is fast enough (benchmarks/bench_search_ann.py)
ANN_MIN_ROWS = 1_000_000
EPS = 1e-6   # seconds: windows that touch are one span
#: windows whose median score is the typical one (a sample: the median of millions costs)
TYPICAL_SAMPLE = 4096
#: decimals of the cosines that rank windows (float32 sums differ in the 7th or 8th)
RANK_DECIMALS = 5
#: windows past the m best that the exact search orders too (ties at the cut)
TIE_MARGIN = 16


class Hit(NamedTuple):
    """One result: a take (its path relative to the indexed folder, ``#N`` after a file of
    several sequences), a span in seconds, the best window's cosine similarity, and what
    the analysis saw there of the query's actions (empty for a hit of the learned model
    alone) with the span, seconds, of the findings that show them (``None``: the learned
    model alone)."""

    file: str
    start: float
    end: float
    score: float
    why: str = ""
    shows: tuple[float, float] | None = None

    def line(self, rank: int) -> str:
        """How ``motionlang search`` prints the hit ranked ``rank``."""
        span = f"{self.start:.1f}-{self.end:.1f} s"   # one column, its unit beside it
        return (f"{rank:3d}. {self.score:6.3f}  {span:>15}  {self.file}"
                + (f"  ({self.why})" if self.why else ""))


def unit_rows(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=np.float32)
    return x / np.maximum(np.linalg.norm(x, axis=-1, keepdims=True), 1e-12)


def merge_windows(rows: np.ndarray, scores: np.ndarray, entry_of: np.ndarray,
                  spans: np.ndarray, k: int, typical: float) -> tuple[list[list], bool]:
    """Hits from windows taken best first (module docstring).

    Args:
        rows: window indices, best first (a prefix of the full order is enough).
        scores: (N,) every window's score; entry_of: (N,) its take; spans: (N, 2) seconds.
        typical: the score of a typical window (the median).
    Returns:
        ``[[take, start, end, score, cut], ...]`` best first (``cut``: the least score a
        window needs to join the hit), and whether they are final (``k`` hits and a window
        below every cut: no later window changes anything).
    """
    hits: list[list] = []
    for r in rows:
        score = float(scores[r])
        if len(hits) == k and score < min(h[4] for h in hits):
            return hits, True
        e, (s, t) = int(entry_of[r]), spans[r]
        near = [h for h in hits if h[0] == e and s <= h[2] + EPS and t >= h[1] - EPS]
        if near:
            best = near[0]   # hits are kept best first
            if score >= best[4]:
                best[1] = min([float(s)] + [h[1] for h in near])
                best[2] = max([float(t)] + [h[2] for h in near])
                hits = [h for h in hits if h is best or all(h is not x for x in near)]
        elif len(hits) < k:
            hits.append([e, float(s), float(t), score, score - 0.5 * (score - typical)])
    return hits, False


class Library:
    """An open index and its model, ready for queries.

    Args:
        data: the index (``store.load_index``).
        embedder: its model (checked against the index's identity).
        where: the index's name for messages.
    """

    def __init__(self, data: IndexData, embedder: Embedder, where: str = "index"):
        try:
            embedder.check(data.model, where)
        except MotionlangError as exc:   # a model file that changed since: say how to go on
            raise MotionlangError(f"{exc}; run 'motionlang index {data.root} -o {where} "
                                  f"--rebuild' to embed its takes with this model") from None
        self.data, self.embedder, self.where = data, embedder, where
        self.unit = unit_rows(data.vectors)
        self.entry_of = data.entry_of_rows()
        self._faiss: Any = None
        self._ann: ann.Approximate | None = None
        #: where an approximate graph of this index is kept (beside its file)
        self.cache: Path | None = None

    @classmethod
    def open(cls, index: str | Path, model: Any = None) -> Library:
        """Open an index file with its own model (the one it names) or ``model``.

        Raises:
            MotionlangError: a missing or damaged index, or a model other than its own.
        """
        data = load_index(index)
        if model is None:
            try:
                model = Embedder.load(data.model["name"])
            except MotionlangError as exc:
                raise MotionlangError(f"{index}: its model {data.model['name']!r} does not "
                                      f"load ({exc}); pass the model") from None
        lib = cls(data, Embedder.load(model), str(index))
        lib.cache = Path(f"{index}.usearch")
        return lib

    def search(self, query: str, k: int | None = None, backend: str | None = None,
               **options: Any) -> list[Hit]:
        """The best hits for ``query``, best first (module docstring); ``k``, ``backend``
        and ``options``: the fields of :class:`~motionlang.library.options.SearchOptions`.
        """
        given: dict[str, Any] = {n: v for n, v in (("k", k), ("backend", backend)) if v is not None}
        opts = SearchOptions(**given, **options)
        if not isinstance(query, str) or not query.split():
            raise MotionlangError(f"the query has no words: {query!r}")
        vector = self.embedder.text(query)
        if not actions_named(query):   # gibberish scores as high as anything: say so
            warnings.warn(f"{query!r} names no action motionlang reads: the hits are the "
                          "learned model's nearest, which need not mean anything",
                          UserWarning, stacklevel=2)
        actions = query_actions(query) if opts.grounded else []
        unanalysed = any(e.findings is None for e in self.data.entries)
        if opts.where and unanalysed:
            raise MotionlangError(f"{self.where}: made before indexes held the analysis; run "
                                  "'motionlang index' on its folder again to search it with "
                                  "--where (the vectors are kept)")
        if actions and unanalysed:
            warnings.warn(f"{self.where}: made before indexes held the analysis, so only the "
                          "learned model answers; run 'motionlang index' on its folder again "
                          "(the vectors are kept)", UserWarning, stacklevel=2)
            actions = []
        plain = not (actions or opts.where or opts.rig or opts.path_glob or opts.min_duration)
        if plain:
            return self.rank(vector, opts.k, opts.backend)
        return self._filtered(vector, actions, opts)

    def _filtered(self, vector: np.ndarray, actions: list[str], opts: SearchOptions
                  ) -> list[Hit]:
        """Hits of a search with filters or actions to match (numpy only)."""
        data, k, least = self.data, opts.k, float(opts.min_duration)
        where = where_actions(opts.where) if opts.where else []
        first = data.first_rows
        allowed = np.zeros(len(self.unit), dtype=bool)
        spans_of: dict[int, list[tuple[float, float]]] = {}   # --where: where each take may hit
        for i, e in enumerate(data.entries):
            if (opts.rig and e.rig.get("map") != opts.rig) or not path_allowed(e.path,
                                                                               opts.path_glob):
                continue
            rows = slice(first[i], first[i + 1])
            if not where:
                allowed[rows] = True
                continue
            spans = [(m.start, m.end) for m in matches(e.findings or [], where, e.duration,
                                                       min_duration=least)]
            if spans:
                spans_of[i] = spans
                allowed[rows] = _overlapping(data.spans[rows], spans)
        hits: list[Hit] = []
        if not allowed.any():
            return hits
        q = unit_rows(vector)
        scores = np.full(len(self.unit), -np.inf, dtype=np.float32)
        scores[allowed] = self.unit[allowed] @ q
        names = [e.name for e in data.entries]
        shown: list[tuple[int, float, float]] = []
        if actions:
            found = []
            for i, e in enumerate(data.entries):
                if not allowed[first[i]:first[i + 1]].any():
                    continue
                for m in matches(e.findings or [], actions, e.duration,
                                 min_duration=least):
                    if i in spans_of and not _overlapping(np.array([[m.start, m.end]]),
                                                          spans_of[i]).any():
                        continue
                    own = np.arange(first[i], first[i + 1])
                    near = own[_overlapping(data.spans[own], [(m.start, m.end)])]
                    best = float(scores[near].max()) if near.size else float(
                        scores[own].max())
                    found.append((len(m.actions), m.direct, best + m.confidence, i, m, best))
            found.sort(key=lambda x: (-x[0], -x[1], -round(x[2], RANK_DECIMALS), x[3],
                                      x[4].start))
            for *_, i, m, best in found[:k]:
                hits.append(Hit(names[i], m.start, m.end, best, m.why, m.shows))
                shown.append((i, m.start, m.end))
            unseen = [a for a in actions if not any(a in m.actions for *_, m, _ in found)]
            if unseen:
                among = " among those the filters allow" if (
                    where or opts.rig or opts.path_glob or least) else ""
                warnings.warn(f"{self.where}: the analysis sees no take{among} that "
                              f"{' or '.join(verb(a) for a in unseen)}; the hits without a "
                              "reason are the learned model's nearest", UserWarning,
                              stacklevel=3)
        if len(hits) < k:
            order = np.flatnonzero(allowed)
            order = order[np.argsort(-ranked(scores[order]), kind="stable")]
            typical = float(np.median(scores[order[::max(1, len(order) // TYPICAL_SAMPLE)]]))
            merged, _ = merge_windows(order, scores, self.entry_of, data.spans,
                                      k + len(shown), typical)
            for e, s, t, score, _ in merged:
                if len(hits) >= k:
                    break
                if t - s < least or any(
                        i == e and s < b and t > a for i, a, b in shown):
                    continue
                hits.append(Hit(names[e], s, t, score))
        return hits

    def rank(self, vector: np.ndarray, k: int = 10, backend: str = "auto") -> list[Hit]:
        """The ``k`` best hits for a query vector (D,) of the index's space."""
        if isinstance(k, bool) or not isinstance(k, int) or k < 1:
            raise MotionlangError(f"k must be an integer >= 1, got {k!r}")
        if backend not in BACKENDS:
            raise MotionlangError(f"backend must be one of {', '.join(BACKENDS)}, got "
                                  f"{backend!r}")
        n = len(self.unit)
        if n == 0:
            return []
        if vector.shape != (self.unit.shape[1],):
            raise MotionlangError(f"{self.where}: a query vector of shape {vector.shape}, "
                                  f"the index holds vectors of {self.unit.shape[1]}")
        q = unit_rows(vector)
        # a fixed sample of the windows, so that every backend sees the same typical score
        typical = float(np.median(self.unit[::max(1, n // TYPICAL_SAMPLE)] @ q))
        hits = self._grown(self._best_rows(backend, n), q, k, typical)
        names = [e.name for e in self.data.entries]
        return [Hit(names[h[0]], h[1], h[2], h[3]) for h in hits]

    def _best_rows(self, backend: str, n: int):
        """``best(q, m) -> (rows, scores)``: about the ``m`` best windows, best first, by the
        backend ``auto`` picks for ``n`` windows or the one named."""
        if backend == "auto":
            backend = ("usearch" if n >= ANN_MIN_ROWS and ann.available() else
                       "faiss" if n >= FAISS_MIN_ROWS and importlib.util.find_spec("faiss")
                       else "numpy")
        if backend == "usearch":
            if self._ann is None:
                self._ann = ann.Approximate(self.unit, self.cache)
            graph = self._ann

            def by_graph(q: np.ndarray, m: int):
                return in_rank_order(*graph.best(q, m))
            return by_graph
        if backend == "faiss":
            if self._faiss is None:
                try:
                    import faiss
                except ImportError:
                    raise MotionlangError("backend 'faiss' needs the faiss-cpu package "
                                          "(pip install faiss-cpu)") from None
                self._faiss = faiss.IndexFlatIP(self.unit.shape[1])
                self._faiss.add(self.unit)

            def by_faiss(q: np.ndarray, m: int):
                got, rows = self._faiss.search(q[None], m)
                keep = rows[0] >= 0
                return in_rank_order(rows[0][keep], got[0][keep])
            return by_faiss

        def by_numpy(q: np.ndarray, m: int):
            scores = self.unit @ q
            # a margin past m, so that windows tied at the cut are ordered by row too
            wide = m + m // 2 + TIE_MARGIN
            top = np.argpartition(-ranked(scores), wide - 1)[:wide] if wide < len(scores) \
                else np.arange(len(scores))
            top = in_rank_order(top, scores[top])[0][:m]
            return top, scores[top]
        return by_numpy

    def _grown(self, best, q: np.ndarray, k: int, typical: float) -> list[list]:
        """Hits merged from the best windows ``best`` gives: more of them until the hits
        are final (or every window was taken)."""
        n, m = len(self.unit), 8 * k
        scores = np.zeros(n, dtype=np.float32)
        while True:
            m = min(m, n)
            rows, got = best(q, m)
            scores[rows] = got
            hits, final = merge_windows(rows, scores, self.entry_of, self.data.spans, k,
                                        typical)
            if final or m == n:
                return hits
            m *= 4

    def take(self, hit: Hit):
        """The motion of a hit's take, read again from the indexed folder."""
        return self.take_named(hit.file)

    def entry_named(self, name: str) -> Entry:
        """The index's entry of the take ``name`` (as hits name it)."""
        entry = next((e for e in self.data.entries if e.name == name), None)
        if entry is None:
            raise MotionlangError(f"{self.where}: no take {name!r}")
        return entry

    def take_named(self, name: str):
        """The motion of the take ``name`` (as hits name it), read again from the indexed
        folder at the rate the index read it at (its body's or its export's,
        ``library.rates``)."""
        entry = self.entry_named(name)
        return read_takes(Path(self.data.root) / entry.path,
                          fps=entry.fps)[entry.sequence - 1]


def nothing_found(index: str | Path, options: dict) -> str:
    """The line for a search with no hits: the filters of ``options`` (the fields of
    :class:`SearchOptions` given) that left nothing, and for ``rig`` the rigs the index
    holds."""
    given = [f"--{k.replace('_', '-')} {v}" for k, v in options.items()
             if k in ("where", "rig", "path_glob", "min_duration") and v]
    line = f"no take of {index} matches" + (f" {', '.join(given)}" if given else "")
    if options.get("rig"):
        rigs = sorted({e.rig.get("map", "?") for e in load_index(index).entries})
        line += f" (the rigs of its takes: {', '.join(rigs) or 'none'})"
    return line


def ranked(scores: np.ndarray) -> np.ndarray:
    """Scores as they are ranked: rounded to :data:`RANK_DECIMALS`, so that two windows
    whose cosines differ only by float32 rounding (which the thread count changes) nearly
    always tie (unless the noise straddles a rounding step), and ties keep the index's
    order."""
    return np.round(scores.astype(np.float64), RANK_DECIMALS)


def in_rank_order(rows: np.ndarray, scores: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(rows, scores)`` best first by :func:`ranked` score, ties by row."""
    order = np.lexsort((rows, -ranked(scores)))
    return rows[order], scores[order]


def _overlapping(spans: np.ndarray, allowed: list[tuple[float, float]]) -> np.ndarray:
    """(N,) whether each span (N, 2) seconds overlaps one of ``allowed``."""
    out = np.zeros(len(spans), dtype=bool)
    for a, b in allowed:
        out |= (spans[:, 0] < b) & (spans[:, 1] > a)
    return out


def search(query: str, index: str | Path | Library, k: int | None = None, *,
           model: Any = None, render: str | Path | None = None, **options: Any) -> list[Hit]:
    """The best hits for ``query`` in ``index`` (a file or an open :class:`Library`), best
    first; ``k`` and ``options``: the fields of ``SearchOptions`` (``where``,
    ``min_duration``, ``rig``, ``path_glob``, ``grounded``, ``backend``); ``render``: also
    write a contact sheet of the hits there (``.png``)."""
    if render is not None and Path(render).suffix.lower() != ".png":
        raise MotionlangError(f"{render}: a contact sheet is written as .png")
    lib = index if isinstance(index, Library) else Library.open(index, model)
    hits = lib.search(query, k, **options)
    if render is not None:
        contact_sheet([(f"{h.file}  {h.start:.1f}-{h.end:.1f} s  ({h.why or f'{h.score:.3f}'})",
                        lib.take(h).between(h.start, h.end)) for h in hits], render,
                      title=f'"{query}"')
    return hits
