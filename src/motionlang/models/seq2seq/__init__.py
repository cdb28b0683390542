"""The sequence-to-sequence models of Plappert, Mandery & Asfour (2018): motion to language
(:mod:`.m2l`) and language to motion with a mixture density output (:mod:`.l2m`, :mod:`.mdn`),
their shared configuration (:mod:`.config`), recurrent layers (:mod:`.layers`), losses
(:mod:`.losses`) and the L2M's coarse plan (:mod:`.plan`)."""
