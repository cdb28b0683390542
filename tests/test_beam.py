"""Word beam search and greedy decoding on hand-made log-probability tables, no model."""
from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import torch

from motionlang.models.seq2seq.decode.beam import Hypothesis, beam_search, greedy_search

torch.set_num_threads(1)
EOS = 0
SOS = 4          # never generated (banned), only fed as the first input
V = 5            # words 1, 2, 3 plus EOS = 0 and SOS = 4


class Table:
    """Next-word log probabilities that depend on (input id, prefix): random but fixed."""

    def __init__(self, seed: int, n_inputs: int, temperature: float = 1.0):
        self.rng = np.random.default_rng(seed)
        self.t = temperature
        self.cache: dict[tuple, np.ndarray] = {}

    def log_probs(self, key: tuple) -> np.ndarray:
        if key not in self.cache:
            logits = self.rng.normal(size=V) * self.t
            logits[SOS] = -np.inf
            self.cache[key] = logits - np.logaddexp.reduce(logits[np.isfinite(logits)])
        return self.cache[key]

    def step(self, state, prev: torch.Tensor):
        """state: ((N, 1 + t) long = input id then the prefix so far, started flag)."""
        rows, started = state if isinstance(state, tuple) else (state, False)
        if started:
            rows = torch.cat([rows, prev.unsqueeze(1)], dim=1)
        lp = np.stack([self.log_probs(tuple(r)) for r in rows.tolist()])
        return torch.tensor(lp, dtype=torch.float32), (rows, True)

    def score(self, b: int, tokens: tuple[int, ...]) -> float:
        return float(sum(self.log_probs((b,) + tokens[:i])[tok] for i, tok in enumerate(tokens)))


def brute_force(table: Table, b: int, max_len: int, min_len: int = 0) -> list[Hypothesis]:
    """Every word sequence of length min_len..max_len-1 followed by EOS, best first."""
    out = []
    for n in range(min_len, max_len):
        for words in itertools.product((1, 2, 3), repeat=n):
            toks = words + (EOS,)
            out.append(Hypothesis(toks, table.score(b, toks)))
    return sorted(out, key=lambda h: -h.score)


def run_beam(table: Table, B: int, width: int, max_len: int, min_len: int = 0):
    state = torch.arange(B).unsqueeze(1)
    return beam_search(table.step, state, batch_size=B, width=width, sos=SOS, eos=EOS,
                       max_len=max_len, banned=(SOS,), min_len=min_len)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("max_len", [1, 2, 4])
def test_wide_beam_equals_brute_force(seed, max_len):
    # With W >= 3^(max_len-1) live prefixes nothing is ever pruned, so the beam's W best
    # must be exactly the W best of all sequences.
    table = Table(seed, 2, temperature=2.0)
    W = 3 ** (max_len - 1) + 2
    beams = run_beam(table, 2, W, max_len)
    for b in range(2):
        ref = brute_force(table, b, max_len)[:W]
        got = beams[b]
        assert [h.tokens for h in got] == [h.tokens for h in ref]
        np.testing.assert_allclose([h.score for h in got], [h.score for h in ref], rtol=1e-5)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("min_len", [1, 2])
def test_min_len_equals_brute_force(seed, min_len):
    table = Table(50 + seed, 1, temperature=2.0)
    W = 3 ** 3 + 1
    got = run_beam(table, 1, W, 4, min_len=min_len)[0]
    ref = brute_force(table, 0, 4, min_len=min_len)[:W]
    assert [h.tokens for h in got] == [h.tokens for h in ref]
    g = greedy_search(table.step, torch.zeros(1, 1, dtype=torch.long), batch_size=1, sos=SOS,
                      eos=EOS, max_len=4, banned=(SOS,), min_len=min_len)[0]
    assert len(g.tokens) >= min_len + 1


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("width", [1, 2, 3])
def test_narrow_beam_is_consistent(seed, width):
    table = Table(100 + seed, 3, temperature=1.5)
    max_len = 4
    for b, hyps in enumerate(run_beam(table, 3, width, max_len)):
        allseq = brute_force(table, b, max_len)
        assert 1 <= len(hyps) <= width
        assert len({h.tokens for h in hyps}) == len(hyps)            # no duplicates
        assert [h.score for h in hyps] == sorted((h.score for h in hyps), reverse=True)
        for h in hyps:
            assert h.tokens[-1] == EOS and EOS not in h.tokens[:-1]
            assert len(h.tokens) <= max_len and SOS not in h.tokens
            assert h.score == pytest.approx(table.score(b, h.tokens), abs=1e-5)
        # never better than the true optimum; the best of W is never worse than greedy-ish
        assert hyps[0].score <= allseq[0].score + 1e-6


def test_beam_finds_what_greedy_misses():
    # p(1)=0.5, p(2)=0.4 first; after 1 everything is flat (bad), after 2 EOS is certain.
    flat = math.log(1 / 4)
    table = {(): [math.log(0.1), math.log(0.5), math.log(0.4), -30.0],
             (1,): [flat] * 4, (2,): [0.0, -30.0, -30.0, -30.0]}

    def step(state, prev):
        rows, started = state if isinstance(state, tuple) else (state, False)
        if started:
            rows = torch.cat([rows, prev.unsqueeze(1)], dim=1)
        lp = [table.get(tuple(r[1:]), [flat] * 4) + [-math.inf] for r in rows.tolist()]
        return torch.tensor(lp), (rows, True)

    state = torch.zeros(1, 1, dtype=torch.long)
    greedy = greedy_search(step, state, batch_size=1, sos=SOS, eos=EOS, max_len=3,
                           banned=(SOS,))[0]
    beam = beam_search(step, state, batch_size=1, width=2, sos=SOS, eos=EOS, max_len=3,
                       banned=(SOS,))[0]
    assert greedy.tokens[0] == 1
    assert beam[0].tokens == (2, EOS)
    assert beam[0].score == pytest.approx(math.log(0.4), abs=1e-5)
    assert beam[0].score > greedy.score


@pytest.mark.parametrize("seed", range(5))
def test_greedy_follows_argmax_and_caps_length(seed):
    table = Table(200 + seed, 2, temperature=0.3)   # flat tables: long sentences
    for max_len in (1, 3, 6):
        hyps = greedy_search(table.step, torch.arange(2).unsqueeze(1), batch_size=2, sos=SOS,
                             eos=EOS, max_len=max_len, banned=(SOS,))
        for b, h in enumerate(hyps):
            assert h.tokens[-1] == EOS and len(h.tokens) <= max_len
            for i, tok in enumerate(h.tokens[:-1]):
                assert tok == int(np.argmax(table.log_probs((b,) + h.tokens[:i])))
            assert h.score == pytest.approx(table.score(b, h.tokens), abs=1e-5)


def test_width_one_beam_never_worse_than_greedy():
    for seed in range(10):
        table = Table(300 + seed, 1)
        g = greedy_search(table.step, torch.zeros(1, 1, dtype=torch.long), batch_size=1,
                          sos=SOS, eos=EOS, max_len=4, banned=(SOS,))[0]
        b = run_beam(table, 1, 1, 4)[0][0]
        assert b.score >= g.score - 1e-6


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("alpha", [0.5, 1.0])
def test_length_penalty_wide_beam_equals_brute_force(seed, alpha):
    # nothing pruned (W >= all prefixes): the W best by total / length**alpha of all sequences
    table = Table(200 + seed, 1, temperature=2.0)
    max_len = 4
    W = 3 ** (max_len - 1) + 2
    state = torch.arange(1).unsqueeze(1)
    got = beam_search(table.step, state, batch_size=1, width=W, sos=SOS, eos=EOS,
                      max_len=max_len, banned=(SOS,), length_penalty=alpha)[0]
    ref = sorted(brute_force(table, 0, max_len), key=lambda h: -h.score / len(h.tokens) ** alpha)[:W]
    assert [h.tokens for h in got] == [h.tokens for h in ref]
    np.testing.assert_allclose([h.score for h in got], [h.score for h in ref], rtol=1e-5)


def test_length_penalty_prefers_longer_sentences():
    # every word costs log probability, so the total picks the shortest sentence; per
    # token, the longest of confident words wins (log .6 > the mean with EOS's log .35)
    def step(state, prev):
        lp = torch.log(torch.tensor([[0.35, 0.6, 0.03, 0.02, 1e-9]] * len(prev)))
        return lp, state
    state = torch.zeros(1, 1)
    total = beam_search(step, state, batch_size=1, width=2, sos=SOS, eos=EOS, max_len=5,
                        banned=(SOS,), min_len=1)[0]
    norm = beam_search(step, state, batch_size=1, width=2, sos=SOS, eos=EOS, max_len=5,
                       banned=(SOS,), min_len=1, length_penalty=1.0)[0]
    assert total[0].tokens == (1, EOS)
    assert len(norm[0].tokens) == 5 and norm[0].tokens[:4] == (1, 1, 1, 1)
    assert norm[0].score < total[0].score          # scores stay totals


def test_a_forced_prefix_starts_every_hypothesis_and_is_scored():
    # exhaustive beam (width >= every sequence) with the prefix (2, 3): the same hypotheses
    # as brute force over all sequences that start with it, at their full scores
    table = Table(seed=7, n_inputs=1)
    state = torch.arange(1).unsqueeze(1)
    got = beam_search(table.step, state, batch_size=1, width=40, sos=SOS, eos=EOS,
                      max_len=5, banned=(SOS,), prefix=(2, 3))[0]
    want = [h for h in brute_force(table, 0, 5) if h.tokens[:2] == (2, 3)][:40]
    assert [h.tokens for h in got] == [h.tokens for h in want]
    assert [h.score for h in got] == pytest.approx([h.score for h in want], abs=1e-5)
