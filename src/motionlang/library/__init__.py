"""Whole motion libraries: overlapping time windows of long takes (:mod:`.windows`), shared by
the search index and by describing long takes as a timeline."""
