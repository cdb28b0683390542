"""How the seq2seq models decode: beam search over words, sampled beams and mean decoding
over frames, minimum-Bayes-risk ranking, reranking by an M2L, and ``describe`` checked
against what the body does."""
