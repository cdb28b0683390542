"""The conditional RBM of Taylor, Hinton & Roweis (2006): its config (:mod:`.config`), one
level (:mod:`.model`, with its learning in :mod:`.training` and inference in
:mod:`.generation`), the two-level stack (:mod:`.stack`), the linear autoregressive baseline
(:mod:`.ar`) and the training sequences both read (:mod:`.sequences`)."""
