"""No run-by-run history in the package's comments, docstrings and help texts.

Dates, issue numbers and work sessions in a comment or a ``--help`` text are stale the day
after; measured figures and history belong in ``docs/results/`` and ``CHANGELOG.md``. This
checks the clearest patterns in every comment and string literal under ``src/motionlang``.
Dates that are facts of the world (the KIT-ML release dates) are allowed by exact text.
"""
from __future__ import annotations

import io
import re
import tokenize
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "motionlang"

#: name -> pattern of the history the package's text must not carry
PATTERNS = {
    "a date": re.compile(r"\b(?:19|20)\d\d-[01]\d-[0-3]\d\b"),
    "an issue number": re.compile(r"\bissues? #?\d+", re.IGNORECASE),
    "a work session": re.compile(r"\bsessions?\b", re.IGNORECASE),
}
#: KIT-ML's releases, as its download page lists them (``datasets.kitml``)
KITML_RELEASES = {"2016-06-14", "2016-09-20", "2016-10-10", "2017-06-22"}
#: file (relative to ``src/motionlang``) -> exact texts allowed there
ALLOWED: dict[str, set[str]] = {
    "datasets/kitml.py": KITML_RELEASES,
    "datasets/download.py": KITML_RELEASES,
    "cli/data_commands.py": {"2016-10-10"},
    # a runtime message: "session" is this process, not a work session
    "features/taylor.py": {"session"},
}
#: token types holding text: comments and string literals (f-string parts from 3.12 on)
TEXT_TOKENS = {tokenize.COMMENT, tokenize.STRING} | (
    {tokenize.FSTRING_MIDDLE} if hasattr(tokenize, "FSTRING_MIDDLE") else set())


def findings(path: Path) -> list[str]:
    """``"file:line: what: text"`` for each pattern found in the comments and strings of
    ``path`` that its entry of :data:`ALLOWED` does not allow."""
    rel = path.relative_to(SRC).as_posix()
    allowed = ALLOWED.get(rel, set())
    source = path.read_text(encoding="utf-8")
    out = []
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type not in TEXT_TOKENS:
            continue
        for what, pattern in PATTERNS.items():
            for m in pattern.finditer(tok.string):
                if m.group(0) in allowed:
                    continue
                line = tok.start[0] + tok.string.count("\n", 0, m.start())
                out.append(f"{rel}:{line}: {what}: {m.group(0)!r}")
    return out


def test_no_dates_issues_or_sessions_in_comments_docstrings_or_help():
    found = [f for p in sorted(SRC.rglob("*.py")) for f in findings(p)]
    assert not found, ("history in comments, docstrings or help texts (say why in words; "
                       "figures and dates go to docs/results/ or CHANGELOG.md):\n"
                       + "\n".join(found))


@pytest.mark.parametrize("text, hit", [
    ("# measured 2026-11-22 on the test set", True),
    ('"""the end flag (issue 6) fires early"""', True),
    ("# before the fifth session", True),
    ("# the 2016-10-10 release", False),        # allowed in the file below
    ("# 12.5 Hz in Ghosh et al. 2021", False),
])
def test_the_check_sees_what_it_should(tmp_path, monkeypatch, text, hit):
    pkg = tmp_path / "motionlang" / "datasets"
    pkg.mkdir(parents=True)
    f = pkg / "kitml.py"
    f.write_text(f"x = 1  {text}\n" if text.startswith("#") else f"{text}\n", encoding="utf-8")
    monkeypatch.setattr(f"{__name__}.SRC", tmp_path / "motionlang")
    assert bool(findings(f)) == hit
