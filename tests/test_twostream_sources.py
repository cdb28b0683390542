"""Each sentence's motion in its source's statistics (``models.twostream.sources``: the
regression, the change of normaliser and its inverse) and from a first pose read from the
sentence (``models.twostream.start``): the model's generation with them, and the checkpoint."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from helpers.twostream import HashTokens, tiny
from motionlang.errors import MotionlangError
from motionlang.features.normalizer import Normalizer
from motionlang.models.twostream.model import TwoStreamModel
from motionlang.models.twostream.sources import SourceOutput, fit_source_output
from motionlang.models.twostream.start import StartPose, fit_start_pose

torch.set_num_threads(1)


def normalizers(seed=0):
    rng = np.random.default_rng(seed)
    return [Normalizer().fit(rng.normal(loc, scale, size=(40, 66)))
            for loc, scale in ((0.0, 1.0), (3.0, 0.2))]


def test_fit_tells_separable_sources_apart():
    rng = np.random.default_rng(0)
    z = np.concatenate([rng.normal(-1, 0.3, (50, 4)), rng.normal(1, 0.3, (50, 4))])
    labels = [0] * 50 + [1] * 50
    out = SourceOutput.fit(normalizers(), z, labels)
    p = out.probabilities(torch.as_tensor(z))
    torch.testing.assert_close(p.sum(-1), torch.ones(100, dtype=p.dtype))
    assert (p.argmax(-1).numpy() == labels).all()
    assert p[:50, 0].min() > 0.9 and p[50:, 1].min() > 0.9
    # a point halfway between reads like both
    assert 0.2 < float(out.probabilities(torch.zeros(1, 4))[0, 0]) < 0.8
    with pytest.raises(MotionlangError, match="each of the 2 sources"):
        SourceOutput.fit(normalizers(), z[:50], labels[:50])
    with pytest.raises(MotionlangError, match=r"reads \(4,\)"):
        out.probabilities(torch.zeros(2, 5))


def test_to_output_is_the_sources_normaliser_then_the_models_inverse():
    norms = normalizers()
    out = SourceOutput(np.stack([n.mean for n in norms]), np.stack([n.std for n in norms]),
                       np.zeros((2, 3)), np.zeros(2))
    model_norm = norms[1]
    x = torch.randn(2, 5, 66, dtype=torch.float64)
    p = torch.tensor([[1.0, 0.0], [0.25, 0.75]], dtype=torch.float64)
    y = out.to_output(x, p, model_norm)
    # a sentence all of source 0: its frames decoded by source 0's normaliser
    np.testing.assert_allclose(model_norm.inverse(y[0].numpy()), norms[0].inverse(x[0].numpy()),
                               atol=1e-9)
    # a mix: the means and spreads weighed by the probabilities
    mean = 0.25 * norms[0].mean + 0.75 * norms[1].mean
    std = 0.25 * norms[0].std + 0.75 * norms[1].std
    np.testing.assert_allclose(model_norm.inverse(y[1].numpy()), x[1].numpy() * std + mean,
                               atol=1e-9)
    torch.testing.assert_close(out.from_output(y, p, model_norm), x)
    back = SourceOutput.from_dict(out.to_dict())
    torch.testing.assert_close(back.to_output(x, p, model_norm), y)
    with pytest.raises(MotionlangError, match="2 sources need"):
        SourceOutput(out.means, out.stds, np.zeros((3, 3)), np.zeros(2))


def test_model_generates_in_each_sentences_source_and_saves_it(tmp_path):
    m = tiny()
    norms = normalizers()
    m.normalizer = norms[1]
    with torch.no_grad():
        m.rest_pose.normal_()
    m.eval()
    sentences = ["a person walks forward", "someone waves twice", "a man jumps high",
                 "she turns left", "he kicks", "walk slowly"]
    plain = m.generate(sentences, 6)
    m.sources = fit_source_output(m, sentences, [0, 0, 0, 1, 1, 1], norms)
    p = m.sources.probabilities(m.joint(m.encode_text(sentences)))
    assert (p.argmax(-1).numpy() == [0, 0, 0, 1, 1, 1]).all()
    got = m.generate(sentences, 6)
    # the decoder's frames, read in the sentence's source, then written in the model's
    torch.testing.assert_close(got, m.sources.to_output(plain.double(), p, norms[1]).float())
    # a first pose given in the model's normalisation reaches the decoder in the source's
    start = torch.randn(66)
    first = m.generate(sentences[:1], 4, start=start)
    np.testing.assert_allclose(m.normalizer.inverse(first[0, 0].numpy()),
                               m.normalizer.inverse(start.numpy()), atol=1e-4)
    m.save(tmp_path / "ts.pt")
    m2 = TwoStreamModel.load(tmp_path / "ts.pt", text_encoder=HashTokens())
    torch.testing.assert_close(m2.generate(sentences, 6), got, rtol=0, atol=0)
    m.sources = None   # models trained with one normaliser generate as before
    torch.testing.assert_close(m.generate(sentences, 6), plain)


def test_start_pose_fits_a_linear_map_and_predicts_its_shape():
    rng = np.random.default_rng(1)
    z = rng.normal(size=(60, 5))
    a, b = rng.normal(size=(5, 66)), rng.normal(size=66)
    fit = StartPose.fit(z, z @ a + b, ridge=1e-9)
    got = fit.predict(torch.as_tensor(z[:3]))
    np.testing.assert_allclose(got.numpy(), z[:3] @ a + b, atol=1e-6)
    # the penalty shrinks the weights, never the bias
    flat = StartPose.fit(z, np.tile(b, (60, 1)), ridge=1e3)
    np.testing.assert_allclose(flat.weights[-1], b, atol=1e-6)
    np.testing.assert_allclose(StartPose.from_dict(fit.to_dict()).weights, fit.weights)
    with pytest.raises(MotionlangError, match=r"reads \(5,\)"):
        fit.predict(torch.zeros(1, 4))
    with pytest.raises(MotionlangError, match="need"):
        StartPose.fit(z, z[:10])


def test_generation_starts_from_the_sentences_pose_unless_given_one(tmp_path):
    m = tiny()
    m.normalizer = normalizers()[1]
    m.eval()
    sentences = ["a person walks forward", "someone waves twice", "she turns left"]
    rng = np.random.default_rng(2)
    poses = rng.normal(size=(3, 66))
    m.start_pose = fit_start_pose(m, sentences, poses)
    assert m.start_pose.weights.shape == (33, 66)   # 2h + 1 rows
    out = m.generate(sentences, 5)
    z = m.joint(m.encode_text(sentences))
    torch.testing.assert_close(out[:, 0], m.start_pose.predict(z))
    # sentences' poses differ as their embeddings do (not one rest pose for all)
    assert not torch.allclose(out[0, 0], out[1, 0])
    given = torch.randn(66)
    torch.testing.assert_close(m.generate(sentences[0], 4, start=given)[0], given)
    m.save(tmp_path / "ts.pt")
    m2 = TwoStreamModel.load(tmp_path / "ts.pt", text_encoder=HashTokens())
    torch.testing.assert_close(m2.generate(sentences, 5), out, rtol=0, atol=0)
    # with sources, the pose is read in the sentence's source's normalisation
    m.sources = fit_source_output(m, sentences * 2, [0, 0, 1, 0, 0, 1], normalizers())
    p = m.sources.probabilities(z)
    first = m.generate(sentences, 5)[:, 0]
    torch.testing.assert_close(first, m.sources.to_output(
        m.start_pose.predict(z)[:, None].double(), p, m.normalizer)[:, 0].float())
    # first poses given per sentence (B, F), in the model's normalisation, come back as given
    given = torch.randn(3, 66)
    torch.testing.assert_close(m.generate(sentences, 4, start=given)[:, 0], given,
                               atol=1e-4, rtol=1e-4)
    # without a start pose the rest pose goes to the decoder as it is (the decoder's space)
    m.start_pose = None
    torch.testing.assert_close(m.generate(sentences, 3)[:, 0], m.sources.to_output(
        m.rest_pose.expand(3, -1)[:, None].double(), p, m.normalizer)[:, 0].float())
    # the fits read the embeddings in eval mode and leave the model's mode as it was
    m.train()
    again = fit_start_pose(m, sentences, poses)
    assert m.training
    np.testing.assert_allclose(again.weights, m2.start_pose.weights, atol=1e-6)


@pytest.mark.parametrize("entry, value, message", [
    ("start_pose", {"weights": [[0.0] * 66] * 10}, "do not fit the model's"),
    ("start_pose", {"weights": [[1.0, 2.0]]}, r"must be \(D \+ 1, F\)"),
    ("sources", {"means": [[0.0] * 66] * 2, "stds": [[1.0] * 66] * 2,
                 "weights": [[0.0] * 5] * 2, "bias": [0.0, 0.0]}, "do not fit the model's"),
    ("sources", {"means": [[0.0] * 66] * 2, "stds": [[1.0] * 66] * 2,
                 "weights": [[0.0] * 32] * 2, "bias": [0.0]}, "2 sources need"),
    ("sources", {"means": [[0.0] * 66] * 2, "stds": [[1.0] * 65 + [0.0]] * 2,
                 "weights": [[0.0] * 32] * 2, "bias": [0.0, 0.0]}, "positive spreads"),
])
def test_a_damaged_start_pose_or_sources_entry_is_named_on_load(tmp_path, entry, value, message):
    m = tiny()
    m.normalizer = normalizers()[1]
    m.save(tmp_path / "ts.pt")
    state = torch.load(tmp_path / "ts.pt", weights_only=False)
    state[entry] = value
    torch.save(state, tmp_path / "bad.pt")
    with pytest.raises(MotionlangError, match=f"bad.pt: a damaged twostream checkpoint.*{message}"):
        TwoStreamModel.load(tmp_path / "bad.pt", text_encoder=HashTokens())
