"""Evaluations of text-to-motion models: the comparison table, its baselines and the oracle."""
