"""Text-motion retrieval (TMR-style): a motion encoder over the 21-joint position features
and a projection of frozen MiniLM sentence vectors, trained contrastively into one space
(:mod:`.model`), its configuration (:mod:`.config`) and sentence vectors (:mod:`.text`)."""
