"""The text-motion evaluator of Guo et al. 2022 (the field's yardstick): configuration
(:mod:`.config`), text input and part-of-speech tagger (:mod:`.text`), the public encoders
(:mod:`.layers`) and the model with its loss and checkpoints (:mod:`.model`)."""
