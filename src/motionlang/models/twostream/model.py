"""The two-stream text-to-motion model (Ghosh et al. 2021): joint embedding of sentences and
pose sequences with upper- and lower-body streams, a shared hierarchical decoder and a pose
discriminator; losses as a dict of named terms weighted by ``config.lambdas``.

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
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn
from torch.func import functional_call

from motionlang.errors import MotionlangError
from motionlang.features.joint_map import TOES
from motionlang.models.checkpoint import (
    FORMAT_VERSION,
    pack_normalizer,
    read_model_dict,
    unpack_normalizer,
    write_checkpoint,
)
from motionlang.models.length import SentenceLength
from motionlang.models.twostream import losses as L
from motionlang.models.twostream.config import TwoStreamConfig
from motionlang.models.twostream.discriminator import PoseDiscriminator
from motionlang.models.twostream.pose import PoseDecoder, PoseEncoder
from motionlang.models.twostream.sentence import SentenceEncoder
from motionlang.models.twostream.text import build_text_encoder

STAGES = ("joint", "pose", "text")
#: the length of a generation without a length model (frames at 12.5 Hz: 10 s)
DEFAULT_FRAMES = 125
#: frame rate of the model's position features (Ghosh et al. 2021: KIT-ML at 12.5 Hz)
FPS = 12.5


class TwoStreamModel(nn.Module):
    """Sentence / pose-sequence joint embedding and hierarchical pose decoder.

    Args:
        config: sizes and flags; ``config.text_dim == 0`` is filled in from the text encoder.
        normalizer: the features' Normalizer (travels in the checkpoint), optional.
        text_encoder: token-feature source (``text.CachedTokens``); built from the config
            on first use when None.
    """

    kind = "twostream"

    def __init__(self, config: TwoStreamConfig, normalizer: Any = None, text_encoder=None):
        super().__init__()
        self._text = text_encoder
        self.config, self.normalizer = config, normalizer
        if config.text_dim <= 0:  # a copy: the caller's config is left as given
            config = self.config = replace(config, text_dim=self.text_encoder.dim)
        self.pose_encoder = PoseEncoder(config)
        self.sentence_encoder = SentenceEncoder(config)
        self.decoder = PoseDecoder(config)
        self.discriminator = PoseDiscriminator(config.n_features, config.disc_hidden)
        # where generation starts when no initial pose is given (normalised features)
        self.register_buffer("rest_pose", torch.zeros(config.n_features))
        #: probability of feeding the true previous frame while training (a schedule,
        #: e.g. annealed to 0 by the training loop; never used in eval mode)
        self.teacher_forcing = 0.0
        #: sentence -> frames for generation without a given length (``SentenceLength``,
        #: fitted by the trainer; None: :data:`DEFAULT_FRAMES`)
        self.length_model = None
        self.set_stage("joint" if config.joint_training else "pose")

    # ------------------------------------------------------------------ parts
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
        from motionlang.features.collate import pad_batch
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
            terms["adversarial"] = L.bce_logits(self._disc(fake, lengths, frozen=True), True)
            terms["discriminator"] = (
                L.bce_logits(self._disc(x, lengths, frozen=False), True)
                + L.bce_logits(self._disc(fake.detach(), lengths, frozen=False), False))
        total = sum(c.lambdas[k] * v for k, v in terms.items())
        return {"loss": total, **{k: v.detach() for k, v in terms.items()}}

    def _foot_term(self, q: torch.Tensor, x: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """``foot_contact_loss`` of decoded frames q against x (both (B, T, 66), normalised),
        read in metres through the model's normaliser; mask (B, T)."""
        norm = self.normalizer
        mean = norm.get("mean") if isinstance(norm, dict) else getattr(norm, "mean", None)
        std = norm.get("std") if isinstance(norm, dict) else getattr(norm, "std", None)
        if mean is None or std is None or self.config.n_features != 66:
            raise MotionlangError("the foot loss needs the 66 position features and their "
                                  "normaliser (mean and std)")
        mean = torch.as_tensor(np.asarray(mean), dtype=x.dtype, device=x.device)
        std = torch.as_tensor(np.asarray(std), dtype=x.dtype, device=x.device)
        return L.foot_contact_loss(q * std + mean, x * std + mean, mask, TOES, FPS)

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

        ``start`` (F,) or (B, F) is the initial pose (normalised); default ``rest_pose``.
        """
        if n_frames < 1:
            raise MotionlangError(f"n_frames must be >= 1, got {n_frames}")
        single = isinstance(sentence, str)
        sentences = [sentence] if single else list(sentence)
        z = self.encode_text(sentences)
        x0 = self.rest_pose if start is None else torch.as_tensor(start, dtype=torch.float32)
        x0 = x0.expand(len(sentences), -1) if x0.ndim == 1 else x0
        if x0.shape != (len(sentences), self.config.n_features):
            raise MotionlangError(f"start pose must be ({self.config.n_features},) or "
                                  f"({len(sentences)}, {self.config.n_features}), got "
                                  f"{tuple(x0.shape)}")
        out = self.decoder(z, x0, n_frames)
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
        prediction, else :data:`DEFAULT_FRAMES` (10 s at 12.5 Hz)."""
        if self.length_model is None:
            return DEFAULT_FRAMES
        return self.length_model.frames(sentence)

    def positions(self, x: torch.Tensor, start=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Normalised features (T, F) of this model -> global 21-joint positions (T, 21, 3)
        metres, Y up (models of the 66 *positions* features with their normaliser)."""
        from motionlang.features.positions import join_global
        if self.normalizer is None or self.config.n_features != 66:
            raise MotionlangError("positions need a model of the 66 positions "
                                  "features with its normaliser")
        raw = self.normalizer.inverse(torch.as_tensor(x).detach().double().numpy())
        # the local frame's origin is the root projected on the ground: the root's local
        # x and z are 0 by construction (constant columns the model only approximates)
        raw[:, [0, 2]] = 0.0
        return join_global(raw[:, :63].reshape(-1, 21, 3), raw[:, 63:65], raw[:, 65], start)

    # ------------------------------------------------------------------ persistence
    def to_checkpoint(self) -> dict:
        return {"kind": self.kind, "format": FORMAT_VERSION, "config": self.config.to_dict(),
                "stage": self.stage,
                "normalizer": pack_normalizer(self.normalizer), "state_dict": self.state_dict(),
                "length_model": (None if self.length_model is None
                                 else self.length_model.to_dict())}

    @classmethod
    def from_checkpoint(cls, d: dict, text_encoder=None) -> TwoStreamModel:
        model = cls(TwoStreamConfig.from_dict(d["config"]),
                    unpack_normalizer(d.get("normalizer")), text_encoder)
        model.load_state_dict(d["state_dict"])
        model.set_stage(d.get("stage", "joint"))
        if d.get("length_model"):   # checkpoints before it have none
            model.length_model = SentenceLength.from_dict(d["length_model"])
        return model.eval()

    def save(self, path: str | Path) -> None:
        """One self-describing file: config, stage, normaliser, weights (atomic write)."""
        write_checkpoint(self.to_checkpoint(), path)

    @classmethod
    def load(cls, path: str | Path, text_encoder=None) -> TwoStreamModel:
        """Rebuild from :meth:`save` or a trainer checkpoint; in eval mode."""
        return cls.from_checkpoint(read_model_dict(path, cls.kind), text_encoder)
