"""The conditional RBM of Taylor, Hinton & Roweis (2006): one level (:mod:`.model`), the
two-level stack (:mod:`.stack`) and the linear autoregressive baseline (:mod:`.ar`)."""
