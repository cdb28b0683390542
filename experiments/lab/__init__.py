"""Code only the experiments use (run-state snapshots, the planner fit, the CRBM settings
search, the procedural corpus's quality checks): importable as ``experiments.lab`` from the
project root, tested like the package, not shipped with it."""
