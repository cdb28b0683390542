"""The two-stream text-to-motion model (Ghosh et al. 2021): joint embedding of sentences and
pose sequences with upper- and lower-body streams, a shared hierarchical decoder and a pose
discriminator; losses as a dict of named terms weighted by ``config.lambdas``.

The model reads the *positions* features (``features.positions.PositionFeatures``): the
fitted feature set travels in its checkpoint, and everything about their layout and frame
rate (decoding to global positions, encoding positions, the foot term's metres and
seconds) goes through it.

Batch (see :meth:`TwoStreamModel.loss`): ``motion`` (B, T, F) normalised features,
optional ``lengths`` (B,), and either ``sentences`` (list of B strings; features come from
the frozen, cached text encoder) or ``text`` (B, L, D) + ``text_lengths`` (B,).

Adversarial training in one optimiser: the generator's term scores generated poses with a
*detached copy* of the discriminator's parameters, and the discriminator's term scores
detached generated poses, so each term only moves its own side; the shared trainer (one
optimiser over all parameters) can therefore train both at once.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any, cast

import numpy as np
import torch
from torch import nn
from torch.func import functional_call

from motionlang.errors import MotionlangError
from motionlang.features.base import FeatureSet
from motionlang.features.collate import pad_batch
from motionlang.features.joint_map import TOES
from motionlang.features.normalizer import Normalizer
from motionlang.features.positions import PositionFeatures
from motionlang.models.checkpoint import (
    Checkpointed,
    pack_features,
    pack_normalizer,
    unpack_features,
    unpack_normalizer,
)
from motionlang.models.length import SentenceLength
from motionlang.models.schema import FEATURES, LENGTH_MODEL, NORMALIZER
from motionlang.models.twostream import losses as L
from motionlang.models.twostream.config import TwoStreamConfig
from motionlang.models.twostream.discriminator import PoseDiscriminator
from motionlang.models.twostream.pose import PoseDecoder, PoseEncoder
from motionlang.models.twostream.sentence import SentenceEncoder
from motionlang.models.twostream.sources import SCHEMA as SOURCES
from motionlang.models.twostream.sources import SourceOutput
from motionlang.models.twostream.start import SCHEMA as START_POSE
from motionlang.models.twostream.start import StartPose, decoder_start
from motionlang.models.twostream.text import build_text_encoder

STAGES = ("joint", "pose", "text")
#: the length of a generation without a length model, in seconds
DEFAULT_SECONDS = 10.0


def position_features(features: Any = None) -> PositionFeatures:
    """What a two-stream model reads, from what it is given: a fitted ``PositionFeatures``
    as is; a bare normaliser (a ``Normalizer``, or a dict with ``mean`` and ``std``: the
    models and checkpoints from before features were stored) inside default positions
    features; None: default positions features, not fitted."""
    if isinstance(features, FeatureSet):
        if not isinstance(features, PositionFeatures):
            raise MotionlangError(f"the two-stream model reads positions features, not "
                                  f"{features.kind!r}")
        return features
    out = PositionFeatures()
    if isinstance(features, dict):
        features = Normalizer.from_dict({"mean": features["mean"], "std": features["std"]})
    out.normalizer = features
    return out


class TwoStreamModel(Checkpointed, nn.Module):
    """Sentence / pose-sequence joint embedding and hierarchical pose decoder.

    Args:
        config: sizes and flags; ``config.text_dim == 0`` is filled in from the text encoder.
        features: the fitted ``PositionFeatures`` the model reads (travel in the
            checkpoint), or just their normaliser (:func:`position_features`); optional.
        text_encoder: token-feature source (``text.CachedTokens``); built from the config
            on first use when None.
    """

    kind = "twostream"
    config_cls = TwoStreamConfig
    rest_pose: torch.Tensor   # buffer, registered in __init__

    def __init__(self, config: TwoStreamConfig, features: Any = None, text_encoder=None):
        super().__init__()
        self._text = text_encoder
        self.config = config
        self.features = position_features(features)
        if config.text_dim <= 0:  # a copy: the caller's config is left as given
            config = self.config = replace(config, text_dim=self.text_encoder.dim)
        self.pose_encoder = PoseEncoder(config)
        self.sentence_encoder = SentenceEncoder(config)
        self.decoder = PoseDecoder(config)
        self.discriminator = PoseDiscriminator(config.n_features, config.disc_hidden)
        # where generation starts when no initial pose is given and no start_pose: normalised
        # as the decoder reads (by source in a by-source model, not by ``normalizer``)
        self.register_buffer("rest_pose", torch.zeros(config.n_features))
        #: probability of feeding the true previous frame while training (a schedule,
        #: e.g. annealed to 0 by the training loop; never used in eval mode)
        self.teacher_forcing = 0.0
        #: sentence -> frames for generation without a given length (``SentenceLength``,
        #: fitted by the trainer; None: :data:`DEFAULT_SECONDS`)
        self.length_model: SentenceLength | None = None
        #: trained with one normaliser per source: each sentence's source (``sources``)
        self.sources: SourceOutput | None = None
        #: the first pose from the sentence (``start``); None: ``rest_pose`` for all
        self.start_pose: StartPose | None = None
        self.set_stage("joint" if config.joint_training else "pose")

    # ------------------------------------------------------------------ parts
    @property
    def normalizer(self) -> Normalizer | None:
        """The features' normaliser (None before they are fitted)."""
        return self.features.normalizer

    @normalizer.setter
    def normalizer(self, norm: Any) -> None:
        # new features of the same options: a feature set shared with a dataset stays as it is
        features = PositionFeatures(self.features.config)
        features.normalizer = position_features(norm).normalizer
        self.features = features

    @property
    def fps(self) -> float:
        """Frame rate of the model's frames (its features'), Hz."""
        return self.features.fps

    @property
    def text_encoder(self):
        if self._text is None:
            self._text = build_text_encoder(self.config)
        return self._text

    def set_stage(self, stage: str) -> None:
        """Select the trained parts: stage "joint" (default), or for the no-joint-training
        ablation "pose" (autoencoder and discriminator) then "text" (sentence encoder only,
        the rest frozen)."""
        if stage not in STAGES:
            raise MotionlangError(f"stage must be one of {STAGES}, not {stage!r}")
        self.stage = stage
        frozen = (self.pose_encoder, self.decoder, self.discriminator) if stage == "text" else ()
        for module in (self.pose_encoder, self.decoder, self.discriminator,
                       self.sentence_encoder):
            for p in module.parameters():
                p.requires_grad_(module not in frozen and
                                 not (stage == "pose" and module is self.sentence_encoder))

    def _tokens(self, batch: dict) -> tuple[torch.Tensor, torch.Tensor]:
        if "text" in batch:
            return batch["text"], batch["text_lengths"]
        return self.text_encoder.batch(batch["sentences"])

    def encode_motion(self, motion: torch.Tensor, lengths: torch.Tensor | None = None
                      ) -> dict[str, torch.Tensor]:
        """(B, T, F) -> {stream: (B, H)} pose embeddings (Z_ub, Z_lb or one whole-body Z)."""
        return self.pose_encoder(motion, lengths)

    def encode_text(self, sentences: Sequence[str]) -> dict[str, torch.Tensor]:
        """B sentences -> {stream: (B, H)} sentence embeddings (Z_ub^s, Z_lb^s or Z^s)."""
        return self.sentence_encoder(*self.text_encoder.batch(list(sentences)))

    @staticmethod
    def joint(z: dict[str, torch.Tensor]) -> torch.Tensor:
        """{stream: (B, H)} -> (B, 2h) the concatenated embedding (for CEE / SEE)."""
        return torch.cat(list(z.values()), dim=-1)

    # ------------------------------------------------------------------ training
    @staticmethod
    def collate(items: Sequence[dict]) -> dict:
        """Items ``{"motion": (T_i, F) normalised features, "sentence": str}`` -> the batch
        :meth:`loss` takes: ``motion`` (B, T, F) float32 zero-padded, ``lengths`` (B,),
        ``sentences``."""
        if not items:
            raise MotionlangError("cannot collate an empty batch")
        motion, mask = pad_batch([torch.as_tensor(np.asarray(it["motion"]), dtype=torch.float32)
                                  for it in items])
        return {"motion": motion, "lengths": mask.sum(dim=1),
                "sentences": [str(it["sentence"]) for it in items]}

    def _disc(self, poses, lengths, frozen: bool) -> torch.Tensor:
        if not frozen:
            return self.discriminator(poses, lengths)
        params = {k: v.detach() for k, v in self.discriminator.named_parameters()}
        return functional_call(self.discriminator, params, (poses, lengths))

    def _forcing(self) -> float:
        return self.teacher_forcing if self.training else 0.0

    def _unroll(self, embeddings: dict[str, dict[str, torch.Tensor]], x: torch.Tensor,
                lengths: torch.Tensor | None) -> dict[str, torch.Tensor]:
        """{name: {stream: (B, H)}} -> {name: (B, T, F)}: each embedding decoded from the
        batch's first frames, teacher-forced towards ``x`` (B, T, F), all in ONE unroll over
        the stacked batch: the T-step Python loop is most of a training step, and one
        unroll of 2B rows costs little more than one of B."""
        k, (B, T, _) = len(embeddings), x.shape
        z = {s: torch.cat([e[s] for e in embeddings.values()]) for s in self.decoder.cells}
        q = self.decoder(z, x[:, 0].repeat(k, 1), T, x.repeat(k, 1, 1), self._forcing(),
                         None if lengths is None else lengths.repeat(k))
        return dict(zip(embeddings, q.split(B)))

    def loss(self, batch: dict) -> dict[str, torch.Tensor]:
        """-> {"loss": weighted sum, and each named term (detached)}.

        Terms: ``pose`` (smooth-L1 of the poses decoded from the pose and from the sentence
        embedding), ``manifold`` (re-encoded decoded poses vs their embedding), ``velocity``,
        ``embedding`` (sentence vs pose embedding), ``adversarial`` (generator),
        ``discriminator``, ``energy`` (local speeds) and ``foot`` (toe speed where the
        reference's toe is down, m/s), the last two only with a weight > 0. Which
        terms exist depends on the stage and ``extra_losses``; the text stage with pose and
        energy weights 0 has the embedding term only (nothing is decoded).
        """
        c, stage = self.config, self.stage
        x = batch["motion"]
        lengths = batch.get("lengths")
        if x.ndim != 3 or x.shape[-1] != c.n_features:
            raise MotionlangError(f"motion batch must be (B, T, {c.n_features}), got "
                                  f"{tuple(x.shape)}")
        B, T, _ = x.shape
        mask = L.frame_mask(lengths, B, T).to(x)
        extra = c.extra_losses
        energy = c.lambdas["energy"] > 0
        foot = c.lambdas["foot"] > 0
        terms: dict[str, torch.Tensor] = {}
        with torch.set_grad_enabled(stage != "text" and torch.is_grad_enabled()):
            zp = self.pose_encoder(x, lengths)
        zs = None
        if stage in ("joint", "text"):
            zs = self.sentence_encoder(*self._tokens(batch))
            terms["embedding"] = L.embedding_loss(zs, zp)
        # the text stage with neither pose, energy nor foot weight fits the embedding alone: no
        # decoding (a refit of the sentence encoder onto the pose embeddings: no unroll)
        decode_s = zs is not None and (stage == "joint" or c.lambdas["pose"] > 0 or energy
                                       or foot)
        todo = {"pose": zp} if stage != "text" else {}
        if decode_s:
            todo["sentence"] = zs
        q = self._unroll(todo, x, lengths) if todo else {}
        fake = None
        if "pose" in q:
            qp = fake = q["pose"]
            terms["pose"] = L.masked_smooth_l1(qp, x, mask)
            if extra:
                terms["manifold"] = L.embedding_loss(self.pose_encoder(qp, lengths), zp)
                terms["velocity"] = L.velocity_loss(qp, x, mask)
            if energy:
                terms["energy"] = L.energy_loss(qp, x, mask)
            if foot:
                terms["foot"] = self._foot_term(qp, x, mask)
        if "sentence" in q:
            qs = fake = q["sentence"]   # what generation produces
            terms["pose"] = terms.get("pose", 0.0) + L.masked_smooth_l1(qs, x, mask)
            if extra and stage == "joint":  # the text stage fits embeddings + poses only
                terms["velocity"] = terms.get("velocity", 0.0) + L.velocity_loss(qs, x, mask)
            if energy:
                terms["energy"] = terms.get("energy", 0.0) + L.energy_loss(qs, x, mask)
            if foot:
                terms["foot"] = terms.get("foot", 0.0) + self._foot_term(qs, x, mask)
        if extra and stage != "text":
            assert fake is not None   # outside the text stage the pose embedding is decoded
            terms["adversarial"] = L.bce_logits(self._disc(fake, lengths, frozen=True), True)
            terms["discriminator"] = (
                L.bce_logits(self._disc(x, lengths, frozen=False), True)
                + L.bce_logits(self._disc(fake.detach(), lengths, frozen=False), False))
        total = sum(c.lambdas[k] * v for k, v in terms.items())
        return {"loss": total, **{k: v.detach() for k, v in terms.items()}}

    def _foot_term(self, q: torch.Tensor, x: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """``foot_contact_loss`` of decoded frames q against x (both (B, T, F), normalised),
        read in metres and seconds through the model's features; mask (B, T)."""
        norm = cast(Normalizer, self._fitted_features("the foot loss").normalizer)
        mean = torch.as_tensor(np.asarray(norm.mean), dtype=x.dtype, device=x.device)
        std = torch.as_tensor(np.asarray(norm.std), dtype=x.dtype, device=x.device)
        return L.foot_contact_loss(q * std + mean, x * std + mean, mask, TOES, self.fps)

    def _fitted_features(self, what: str) -> PositionFeatures:
        fs = self.features
        if not fs.fitted or fs.dim != self.config.n_features:
            raise MotionlangError(f"{what} needs a model of the {fs.dim} positions features "
                                  f"with their normaliser (this one: {self.config.n_features} "
                                  f"features{'' if fs.fitted else ', no normaliser'})")
        return fs

    # ------------------------------------------------------------------ generation
    def set_rest_pose(self, first_frames) -> None:
        """Default initial pose of :meth:`generate`: the mean of training sequences' first
        frames (N, F), normalised features."""
        x = torch.as_tensor(np.asarray(first_frames), dtype=torch.float32).reshape(
            -1, self.config.n_features)
        with torch.no_grad():
            self.rest_pose.copy_(x.mean(dim=0))

    @torch.no_grad()
    def generate(self, sentence: str | Sequence[str], n_frames: int,
                 start: torch.Tensor | None = None) -> torch.Tensor:
        """Sentence(s) -> normalised features (T, F), or (B, T, F) for a list.

        ``start`` (F,) or (B, F) is the initial pose (normalised); default the one
        ``start_pose`` reads from each sentence, else ``rest_pose`` (``start.decoder_start``).
        """
        if n_frames < 1:
            raise MotionlangError(f"n_frames must be >= 1, got {n_frames}")
        single = isinstance(sentence, str)
        sentences = [sentence] if isinstance(sentence, str) else list(sentence)
        z = self.encode_text(sentences)
        p = None if self.sources is None else self.sources.probabilities(self.joint(z))
        out = self.decoder(z, decoder_start(self, z, start, p), n_frames)
        if self.sources is not None and p is not None:   # written in the model's one space
            out = self.sources.to_output(out, p, self.normalizer).float()
        return out[0] if single else out

    @torch.no_grad()
    def reconstruct(self, motion: torch.Tensor) -> torch.Tensor:
        """The autoencoder path: normalised features (T, F) -> the same motion decoded from
        its own pose embedding and its own first frame, (T, F). A reference for the sentence
        path (which starts from ``rest_pose``): when the decoder cannot bring a sequence back
        from the motion's own embedding, the sentence embedding, trained to match it, is
        unlikely to."""
        x = torch.as_tensor(motion, dtype=torch.float32)
        if x.ndim != 2 or x.shape[1] != self.config.n_features or len(x) < 1:
            raise MotionlangError(f"motion must be (T >= 1, {self.config.n_features}), got "
                                  f"{tuple(x.shape)}")
        z = self.encode_motion(x[None], torch.tensor([len(x)]))
        return self.decoder(z, x[None, 0], len(x))[0]

    def generate_positions(self, sentence: str, n_frames: int,
                           start=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Sentence -> global 21-joint positions (T, 21, 3) metres, Y up, for models trained
        on the *positions* features (``features.positions`` layout and normaliser)."""
        return self.positions(self.generate(sentence, n_frames), start)

    def frames_for(self, sentence: str) -> int:
        """The length to generate ``sentence`` for when none is given: the length model's
        prediction, else :data:`DEFAULT_SECONDS` at the model's frame rate."""
        if self.length_model is None:
            return int(round(DEFAULT_SECONDS * self.fps))
        return self.length_model.frames(sentence)

    def positions(self, x: torch.Tensor, start=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Normalised features (T, F) of this model -> global 21-joint positions (T, 21, 3)
        metres, Y up, frame 0 at ``start`` (x0, z0, yaw0); the root's local x and z, 0 by
        construction, are set to 0 (``PositionFeatures.decode(pin_root=True)``)."""
        fs = self._fitted_features("positions")
        return fs.decode(torch.as_tensor(x), start, pin_root=True)

    def features_from_positions(self, p21: np.ndarray) -> np.ndarray:
        """Global 21-joint positions (T, 21, 3) metres at :attr:`fps` -> the model's
        normalised features (T, F) (float32: the features' dtype), the body as it stands (the inverse of
        :meth:`positions` up to frame 0's placement): what :meth:`reconstruct`, the
        ``start`` of :meth:`generate` and :meth:`encode_motion` read."""
        return self._fitted_features("features").encode_positions(p21)

    @property
    def caption_words(self) -> list[str] | None:
        """The words of the training captions (its length model was fitted on them)."""
        return None if self.length_model is None else list(self.length_model.words)

    # ------------------------------------------------------------------ persistence
    state_schema = {"stage": str, "features": FEATURES, "normalizer": NORMALIZER,
                    "length_model": LENGTH_MODEL, "sources": SOURCES,
                    "start_pose": START_POSE}

    def checkpoint_state(self) -> dict[str, Any]:
        fitted = self.features.fitted
        return {"stage": self.stage,
                "features": pack_features(self.features) if fitted else None,
                # the features' normaliser again: what releases before features were stored read
                "normalizer": pack_normalizer(self.normalizer) if fitted else None,
                "length_model": (None if self.length_model is None
                                 else self.length_model.to_dict()),
                "sources": None if self.sources is None else self.sources.to_dict(),
                "start_pose": None if self.start_pose is None else self.start_pose.to_dict()}

    @classmethod
    def from_state(cls, config: TwoStreamConfig, state: dict[str, Any],
                   text_encoder=None) -> TwoStreamModel:
        # checkpoints before features were stored carry their normaliser alone
        features = unpack_features(state.get("features"))
        if features is None:
            features = unpack_normalizer(state.get("normalizer"))
        return cls(config, features, text_encoder)

    def restore_state(self, state: dict[str, Any]) -> None:
        self.set_stage(state.get("stage", "joint"))
        if state.get("length_model"):   # checkpoints before it have none
            self.length_model = SentenceLength.from_dict(state["length_model"])
        d, f = 2 * self.config.h, self.config.n_features   # the joint embedding is 2h
        if state.get("sources"):
            self.sources = SourceOutput.from_dict(state["sources"]).checked(d, f)
        if state.get("start_pose"):
            self.start_pose = StartPose.from_dict(state["start_pose"]).checked(d, f)

