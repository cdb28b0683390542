"""A real-motion judge: an action (content) and style classifier over 21-joint positions,
trained on real mocap (the Bandai Namco takes), independent of the text models it judges.

:mod:`.config` (sizes, label lists), :mod:`.model` (the network, its features and its
self-describing checkpoint, kind ``"judge"``), :mod:`.fit` (the labelled takes, a fresh
judge for them, its batches, accuracy). Its recipe (on the shared trainer):
``recipes.judge``. Measures built on it: ``evaluation.judge``.
"""
