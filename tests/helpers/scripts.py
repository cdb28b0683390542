"""The project's scripts (``scripts/``: data tools and the packaged-model recipe) and research
probes (``experiments/probes/``), loaded as modules so that tests can call their functions
and ``main``."""
from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[2]
SCRIPTS = ROOT / "scripts"
PROBES = ROOT / "experiments" / "probes"


def load_script(path: Path) -> ModuleType:
    """The Python file at ``path`` as a module named after it (not added to ``sys.modules``)."""
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
