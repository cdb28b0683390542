"""The package's shape: imports flow down the layers docs/contributing.md states, no import circles
(at module level or through imports inside functions), no source file over the hard cap."""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "motionlang"
#: a line of docs/contributing.md such as ``utils, errors → kinematics → formats → ... → cli``
LAYER_LINE = re.compile(r"^\s*([a-z_]+(?:, [a-z_]+)*)((?: → [a-z_]+(?:, [a-z_]+)*)+)\s*$")


def readme_layers() -> dict[str, int]:
    """Top-level package/module name -> its layer number, from docs/contributing.md."""
    for line in (ROOT / "docs" / "contributing.md").read_text(encoding="utf-8").splitlines():
        m = LAYER_LINE.match(line)
        if m:
            groups = [g.split(", ") for g in line.strip().split(" → ")]
            return {name: i for i, names in enumerate(groups) for name in names}
    raise AssertionError("docs/contributing.md states no layer order (a line "
                         "'a, b → c → ...')")


def modules() -> dict[str, Path]:
    return {".".join(("motionlang",) + p.relative_to(SRC).with_suffix("").parts)
            .removesuffix(".__init__"): p for p in SRC.rglob("*.py")}


def _is_type_checking(node: ast.AST) -> bool:
    """``if TYPE_CHECKING:`` / ``if typing.TYPE_CHECKING:``"""
    test = getattr(node, "test", None) if isinstance(node, ast.If) else None
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or \
        (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _walk(node: ast.AST, type_checking: bool):
    """``ast.walk`` in source order, leaving out the bodies of ``if TYPE_CHECKING:`` unless
    ``type_checking`` (their ``else`` branches run, so they stay)."""
    yield node
    for child in ast.iter_child_nodes(node):
        if not type_checking and _is_type_checking(child):
            for sub in child.orelse:
                yield from _walk(sub, type_checking)
        else:
            yield from _walk(child, type_checking)


def imports(path: Path, top_level_only: bool, type_checking: bool = True) -> list[str]:
    """motionlang modules imported by a file (at module level only, if asked; without the
    imports under ``if TYPE_CHECKING:`` unless ``type_checking``); ``from X import y``
    counts as X.y when that is a module, else X."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    nodes = tree.body if top_level_only else _walk(tree, type_checking)
    known = modules()
    out = []
    for node in nodes:
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names if a.name.startswith("motionlang")]
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("motionlang"):
            for a in node.names:
                sub = f"{node.module}.{a.name}"
                out.append(sub if sub in known else node.module)
    return out


def layer_of(module: str, layers: dict[str, int]) -> int | None:
    parts = module.split(".")
    return layers.get(parts[1]) if len(parts) > 1 else None


def test_every_top_level_part_has_a_layer():
    layers = readme_layers()
    tops = {p.relative_to(SRC).parts[0].removesuffix(".py") for p in SRC.rglob("*.py")}
    missing = sorted(tops - set(layers) - {"__init__"})
    assert not missing, f"parts of motionlang without a layer in docs/contributing.md: {missing}"


def test_no_module_imports_from_a_higher_layer():
    layers = readme_layers()
    bad = []
    for mod, path in modules().items():
        here = layer_of(mod, layers)
        if here is None:   # motionlang/__init__ re-exports lazily from every layer
            continue
        for dep in imports(path, top_level_only=False):
            there = layer_of(dep, layers)
            if dep == "motionlang":   # the package's __init__ re-exports the api layer
                there = layers["api"]
            if there is not None and there > here:
                bad.append(f"{mod} imports {dep}")
    assert not bad, "\n".join(bad)


def test_no_import_loops_at_module_level():
    known = modules()
    graph = {m: [d for d in imports(p, top_level_only=True) if d in known and d != m]
             for m, p in known.items()}
    state: dict[str, int] = {}
    loops = []

    def visit(m, stack):
        state[m] = 1
        for d in graph[m]:
            if state.get(d) == 1:
                loops.append(" -> ".join(stack[stack.index(d):] + [d]))
            elif d not in state:
                visit(d, stack + [d])
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m, [m])
    # a package importing its own submodules in __init__ is not a loop unless they import
    # the package back; those are reported like any other
    assert not loops, "\n".join(loops)


def import_circles(graph: dict[str, list[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted:
    the sets of modules that import each other round a circle."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles = []

    def strong(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, []):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                circles.append(sorted(comp))

    for v in graph:
        if v not in index:
            strong(v)
    return sorted(circles)


def test_no_import_circles_anywhere():
    """Imports inside functions count too (a circle there is two modules that each need the
    other, whenever it runs); imports under ``if TYPE_CHECKING:`` do not (they never run)."""
    known = modules()
    graph = {m: sorted({d for d in imports(p, top_level_only=False, type_checking=False)
                        if d in known and d != m})
             for m, p in known.items()}
    circles = import_circles(graph)
    assert not circles, "import circles:\n" + "\n".join(
        "  {" + ", ".join(c) + "}: " + "; ".join(
            f"{m} -> {', '.join(d for d in graph[m] if d in c)}" for m in c)
        for c in circles)


#: the hard cap of a source file's lines; that a file does one thing is a review rule
#: (docs/contributing.md), which no reflowed comment can meet
MAX_FILE_LINES = 600


@pytest.mark.parametrize("path", sorted(SRC.rglob("*.py")), ids=lambda p: str(p.relative_to(SRC)))
def test_no_source_file_over_the_hard_cap(path):
    n = len(path.read_text(encoding="utf-8").splitlines())
    assert n <= MAX_FILE_LINES, f"{path.relative_to(ROOT)}: {n} lines (split it)"


def test_the_checks_can_fail(tmp_path):
    """The layer reader finds a violation when one is there."""
    f = tmp_path / "m.py"
    f.write_text("def f():\n    from motionlang.cli.main import main\n")
    assert imports(f, top_level_only=False) == ["motionlang.cli.main"]
    assert imports(f, top_level_only=True) == []
    layers = readme_layers()
    assert layer_of("motionlang.cli.main", layers) > layer_of("motionlang.formats", layers)


def test_the_circle_check_can_fail(tmp_path):
    """Imports inside functions are seen, ``if TYPE_CHECKING:`` ones are not (but their
    ``else`` is), and a circle is reported with all of its members."""
    f = tmp_path / "m.py"
    f.write_text("from typing import TYPE_CHECKING\n"
                 "if TYPE_CHECKING:\n    from motionlang.cli.main import main\n"
                 "else:\n    import motionlang.errors\n"
                 "def f():\n    from motionlang.formats import mmm_model\n")
    assert imports(f, top_level_only=False) == [
        "motionlang.cli.main", "motionlang.errors", "motionlang.formats.mmm_model"]
    assert imports(f, top_level_only=False, type_checking=False) == [
        "motionlang.errors", "motionlang.formats.mmm_model"]
    graph = {"a": ["b"], "b": ["c"], "c": ["a", "d"], "d": [], "e": ["e"]}
    assert import_circles(graph) == [["a", "b", "c"]]


def test_the_command_line_is_a_thin_layer():
    # the CLI parses, calls motionlang.api / recipes / evaluation functions and prints: its
    # size per command is a symptom of logic that belongs in a lower layer (the wall is the
    # average of the 32 commands' 2,000 lines it was set at, so that a new command may take
    # its share and no more)
    from motionlang.cli.main import build_parser, leaf_parsers
    lines = sum(len(p.read_text(encoding="utf-8").splitlines())
                for p in (SRC / "cli").glob("*.py"))
    commands = len(leaf_parsers(build_parser()))
    assert lines / commands < 2000 / 32, f"cli/ has {lines} lines for {commands} commands"


def family_table_problems(path: Path) -> list[str]:
    """The strings of a family table (``models/NAME/family.py``) that name code outside the
    family's own folder: every ``"module:object"`` but the recipe must be under
    ``motionlang.models.NAME``, the recipe under ``motionlang.recipes``, and each must name
    a module that exists."""
    folder = path.parent.name
    known = modules()
    name = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
    bad = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not (isinstance(node, ast.Call) and getattr(node.func, "id", None) == "Family"):
            continue
        for kw in node.keywords:
            if not (isinstance(kw.value, ast.Constant) and isinstance(kw.value.value, str)
                    and kw.value.value.startswith("motionlang.")):
                continue
            module = kw.value.value.split(":")[0]
            home = "motionlang.recipes." if kw.arg == "recipe" else f"motionlang.models.{folder}."
            if not module.startswith(home):
                bad.append(f"{name}: {kw.arg}={kw.value.value!r} is not under "
                           f"{home.rstrip('.')}")
            elif module not in known:
                bad.append(f"{name}: {kw.arg}={kw.value.value!r} names no module")
    return bad


def test_family_tables_name_only_their_folder_and_recipe():
    """A family is its folder: its table's strings (resolved at run time, where the import
    test does not see them) point into it, or to its recipe; none climbs a layer."""
    tables = sorted(SRC.glob("models/*/family.py"))
    assert len(tables) >= 7
    bad = [p for t in tables for p in family_table_problems(t)]
    assert not bad, "\n".join(bad)


def test_the_family_table_check_can_fail(tmp_path):
    f = tmp_path / "models" / "tokens" / "family.py"
    f.parent.mkdir(parents=True)
    f.write_text('FAMILIES = (Family(kind="tokens", model="motionlang.models.tokens.model:M",\n'
                 '  recipe="motionlang.recipes.tokens:T",\n'
                 '  describes="motionlang.library.describe:describe"),)\n')
    bad = family_table_problems(f)
    assert any("describes=" in b and "not under motionlang.models.tokens" in b for b in bad)
    assert any("model=" in b and "names no module" in b for b in bad)


def module_getattrs() -> list[str]:
    """Modules of ``src/`` that hand out names through a module-level ``__getattr__``."""
    return sorted(mod for mod, path in modules().items()
                  if any(isinstance(n, ast.FunctionDef) and n.name == "__getattr__"
                         for n in ast.parse(path.read_text(encoding="utf-8")).body))


def test_only_the_package_face_hands_out_names_lazily():
    """A name is imported from the module that defines it; only ``motionlang/__init__``
    (``import motionlang as ml`` without loading torch) resolves names on first use."""
    assert module_getattrs() == ["motionlang"]


#: the third-party packages whose loading a module may put off to the function that needs
#: them (heavy: torch, pictures, the web server), so that the command line and the API stay
#: quick to start
HEAVY = frozenset({"torch", "matplotlib", "imageio", "fastapi", "uvicorn", "starlette",
                   "sentence_transformers", "transformers", "sklearn", "usearch", "ray"})
#: the lazy doors of docs/contributing.md: the package face, family loading (the registry
#: and each recipe's run) and the CLI's command modules
DOORS = ("motionlang", "motionlang.models.registry", "motionlang.recipes.", "motionlang.cli.")
#: the most function-level imports of motionlang modules the package may hold
MAX_FUNCTION_IMPORTS = 60


def third_party(path: Path) -> set[str]:
    """Top-level names of the non-motionlang packages a file imports at module level
    (``if TYPE_CHECKING:`` left out)."""
    out = set()
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in _walk(tree, type_checking=False):
        if node is tree or not isinstance(node, (ast.Import, ast.ImportFrom)):
            continue
        if _in_function(tree, node):
            continue
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
            [node.module or ""] if node.level == 0 else []
        out |= {n.split(".")[0] for n in names if n and not n.startswith("motionlang")}
    return out


def _in_function(tree: ast.AST, target: ast.AST) -> bool:
    for fn in ast.walk(tree):
        if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)) and \
                any(n is target for n in ast.walk(fn)):
            return True
    return False


def function_imports() -> list[tuple[str, int, str]]:
    """(importing module, line, imported module) for each import of a motionlang module
    inside a function body (``if TYPE_CHECKING:`` left out)."""
    known = modules()
    out = []
    for mod, path in known.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for fn in ast.walk(tree):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(fn):
                if isinstance(node, ast.Import):
                    out += [(mod, node.lineno, a.name) for a in node.names
                            if a.name.startswith("motionlang")]
                elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("motionlang"):
                    for a in node.names:
                        sub = f"{node.module}.{a.name}"
                        out.append((mod, node.lineno, sub if sub in known else node.module))
    return sorted(set(out))


def heavy_loads() -> dict[str, set[str]]:
    """Module -> the HEAVY packages that importing it loads (its module-level imports,
    followed through motionlang modules and the packages above them)."""
    known = modules()
    graph = {}
    for m, p in known.items():
        deps = {d for d in imports(p, top_level_only=True, type_checking=False) if d in known}
        deps |= {".".join(d.split(".")[:i]) for d in set(deps) for i in range(1, d.count(".") + 1)}
        graph[m] = deps & set(known)
    own = {m: third_party(p) & HEAVY for m, p in known.items()}
    out: dict[str, set[str]] = {}

    def loads(m: str, stack: frozenset = frozenset()) -> set[str]:
        if m in out:
            return out[m]
        found = set(own[m])
        for d in graph[m]:
            if d not in stack and d != m:
                found |= loads(d, stack | {m})
        out[m] = found
        return found

    for m in known:
        loads(m)
    return out


def misplaced_function_imports(found=None, heavy=None) -> list[str]:
    """The function-level imports (``function_imports()`` unless given) that are neither at
    a door nor put off a heavy package (``heavy_loads()`` unless given)."""
    heavy = heavy_loads() if heavy is None else heavy
    bad = []
    for mod, line, dep in function_imports() if found is None else found:
        at_door = mod == "motionlang" or any(
            mod == d or (d.endswith(".") and mod.startswith(d)) for d in DOORS)
        puts_off = dep in heavy and heavy[dep] - heavy.get(mod, set())
        if not (at_door or puts_off):
            bad.append(f"{mod}:{line} imports {dep} inside a function; it loads nothing heavy "
                       f"the module does not already load: import it at the top")
    return bad


def test_imports_sit_at_the_top_but_at_the_documented_doors():
    """An import of a motionlang module sits at the top of the file, where a reader sees the
    wiring; inside a function only at a lazy door of docs/contributing.md, or where the
    module imported loads a heavy package (torch, matplotlib, the web server) that the
    importer must not (a command's ``-h``, ``import motionlang.api``)."""
    found = function_imports()
    assert len(found) <= MAX_FUNCTION_IMPORTS, \
        f"{len(found)} function-level imports of motionlang modules (at most " \
        f"{MAX_FUNCTION_IMPORTS}):\n" + "\n".join(f"{m}:{n} {d}" for m, n, d in found)
    bad = misplaced_function_imports()
    assert not bad, "\n".join(bad)


def test_the_door_check_sees_a_light_import_inside_a_function():
    heavy = heavy_loads()
    found = [("motionlang.formats", 1, "motionlang.kinematics.motion"),      # light: moved up
             ("motionlang.formats", 2, "motionlang.models.checkpoint"),      # puts torch off
             ("motionlang.cli.train", 3, "motionlang.kinematics.motion")]    # at a door
    bad = misplaced_function_imports(found, heavy)
    assert len(bad) == 1 and bad[0].startswith("motionlang.formats:1 ")
    assert "torch" in heavy["motionlang.models.checkpoint"]
    assert "torch" not in heavy["motionlang.formats"]
    assert "matplotlib" in heavy["motionlang.rendering.animation"]
    assert not heavy["motionlang.kinematics.motion"]
