"""Masked-token text-to-motion (MoMask-style): a residual-VQ tokenizer over the 21-joint
position features (:mod:`.tokenizer`), a masked bidirectional transformer over the base
tokens with a residual transformer for the finer codebooks and a length estimator
(:mod:`.transformer`), iterative decoding and in-betweening (:mod:`.sampling`), the model
that holds them (:mod:`.model`) and its configuration (:mod:`.config`)."""
