"""Replacing a function for a test wherever the package holds it.

Modules import the names they use at their top (``from motionlang.models.registry import
load_model``), so replacing ``registry.load_model`` alone leaves every caller's own binding
as it was. :func:`patch_everywhere` replaces the object in its module and in every loaded
``motionlang`` module that holds that same object, under any name; ``monkeypatch`` undoes it.
"""
from __future__ import annotations

import sys
from types import ModuleType
from typing import Any

#: the attribute a replacement carries: the object it replaced
PATCHED = "__patched_original__"


def patch_everywhere(monkeypatch, module: ModuleType, name: str, value: Any) -> int:
    """Set ``module.name`` to ``value`` and each loaded motionlang module's reference to the
    original object; returns how many modules were changed (at least 1)."""
    original = getattr(module, name)
    original = getattr(original, PATCHED, original)   # (already patched: what it replaced)
    try:
        setattr(value, PATCHED, original)
    except (AttributeError, TypeError):   # an object that takes no attributes
        pass
    count = 0
    for mod_name, mod in list(sys.modules.items()):
        if not (mod_name == "motionlang" or mod_name.startswith("motionlang.")) or mod is None:
            continue
        for attr, obj in list(vars(mod).items()):
            # a module first imported while an earlier test's replacement was in place keeps
            # that replacement after the test: it stands for the original too
            if obj is original or getattr(obj, PATCHED, None) is original:
                monkeypatch.setattr(mod, attr, value)
                count += 1
    if count == 0:   # a module outside the package (a test helper)
        monkeypatch.setattr(module, name, value)
        count = 1
    return count
