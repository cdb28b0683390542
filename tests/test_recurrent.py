"""The seq2seq models' bidirectional encoder: unpacked, it computes what a packed GRU does."""
import pytest
import torch
from torch.nn.utils.rnn import pack_padded_sequence, pad_packed_sequence

from motionlang.models.seq2seq.layers import BiGRUEncoder, reverse_within_lengths

torch.set_num_threads(1)


def test_reverse_within_lengths_by_hand():
    x = torch.arange(8.0).reshape(2, 4, 1)            # rows 0 1 2 3 and 4 5 6 7
    out = reverse_within_lengths(x, torch.tensor([3, 4]))
    assert out[..., 0].tolist() == [[2, 1, 0, 3], [7, 6, 5, 4]]
    assert torch.equal(reverse_within_lengths(out, torch.tensor([3, 4])), x)


def packed_reference(gru: torch.nn.GRU, x, lengths):
    """What the encoder computed before: the GRU over the packed batch."""
    packed = pack_padded_sequence(x, lengths, batch_first=True, enforce_sorted=False)
    out, h_n = gru(packed)
    out, _ = pad_packed_sequence(out, batch_first=True, total_length=x.shape[1])
    return torch.cat([h_n[-2], h_n[-1]], dim=-1), out


@pytest.mark.parametrize("layers", [1, 2, 3])
def test_encoder_matches_the_packed_gru_with_gradients(layers):
    torch.manual_seed(layers)
    enc = BiGRUEncoder(4, 6, layers, dropout=0.3).eval()     # eval: dropout off in both
    x = torch.randn(5, 9, 4, requires_grad=True)
    lengths = torch.tensor([9, 3, 7, 1, 5])
    context, out, mask = enc(x, lengths)
    ref_context, ref_out = packed_reference(enc.gru, x, lengths)
    assert context.shape == (5, 12) and out.shape == (5, 9, 12)
    assert mask.sum(1).tolist() == lengths.tolist()
    torch.testing.assert_close(context, ref_context)
    torch.testing.assert_close(out, ref_out)
    assert (out[1, 3:] == 0).all()                           # past the end: zeros
    w = torch.randn(12)
    got = torch.autograd.grad((context * w).sum() + out.square().sum(),
                              [x, *enc.gru.parameters()])
    want = torch.autograd.grad((ref_context * w).sum() + ref_out.square().sum(),
                               [x, *enc.gru.parameters()])
    for g, r in zip(got, want):
        torch.testing.assert_close(g, r)
    assert (got[0][1, 3:] == 0).all()                        # padding gets no gradient


def test_encoder_ignores_padding_and_draws_like_a_plain_gru():
    torch.manual_seed(0)
    enc = BiGRUEncoder(4, 6, 2).eval()
    after_enc = torch.rand(3)
    torch.manual_seed(0)
    torch.nn.GRU(4, 6, num_layers=2, batch_first=True, bidirectional=True)
    assert torch.equal(torch.rand(3), after_enc)     # seeded runs build the same models
    x = torch.randn(2, 5, 4)
    lengths = torch.tensor([3, 5])
    bad = x.clone()
    bad[0, 3:] = float("nan")                              # whatever fills the padding
    for a, b in zip(enc(x, lengths), enc(bad, lengths)):
        assert torch.equal(a, b)


def test_encoder_keeps_the_checkpoint_layout_and_refuses_long_lengths():
    enc = BiGRUEncoder(4, 6, 2)
    assert set(enc.state_dict()) == {f"gru.{n}" for n, _ in enc.gru.named_parameters()}
    assert sum(p.numel() for p in enc.parameters()) == \
        sum(p.numel() for p in enc.gru.parameters())
    with pytest.raises(ValueError, match="at most 3"):
        enc(torch.zeros(2, 3, 4), torch.tensor([2, 4]))
