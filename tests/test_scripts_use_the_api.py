"""The scripts in ``experiments/`` and ``scripts/`` stand on the library and its Python API
(``import motionlang as ml``), never on the command line's modules: a helper a script needs
from ``motionlang.cli`` belongs in the API or the library instead."""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = ("experiments", "scripts")


def cli_imports(source: str) -> list[tuple[int, str]]:
    """``(line, module)`` of every import of ``motionlang.cli`` (or anything under it) in
    ``source``, at any depth: module level, inside functions, ``from motionlang import cli``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        else:
            continue
        hit = [n for n in names if n == "motionlang.cli" or n.startswith("motionlang.cli.")]
        if hit:
            found.append((node.lineno, hit[0]))
    return sorted(found)


def test_the_check_sees_every_form_of_a_cli_import():
    source = ("import motionlang as ml\n"
              "from motionlang.api import generate\n"
              "from motionlang.evaluation.judge import judge_table\n"
              "import motionlang.client_tools\n"
              "def f():\n"
              "    from motionlang.cli.main import main\n"
              "    import motionlang.cli.describe_generate as tc\n"
              "    from motionlang import cli\n"
              "from motionlang.cli import main\n")
    assert [line for line, _ in cli_imports(source)] == [6, 7, 8, 9]


def test_no_script_imports_the_command_line():
    files = sorted(p for folder in FOLDERS for p in (ROOT / folder).rglob("*.py"))
    assert files, "no scripts found"
    offenders = [f"{p.relative_to(ROOT)}:{line}: {name}"
                 for p in files for line, name in cli_imports(p.read_text(encoding="utf-8"))]
    assert not offenders, ("scripts must use the Python API (import motionlang as ml) or the "
                           "library, not motionlang.cli:\n" + "\n".join(offenders))
