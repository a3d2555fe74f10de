"""The layout's import rules, read from the source with ``ast`` and ``tokenize`` (nothing is
imported, so it takes well under a second): the core ``jax3dc/`` imports nothing of the packages
built on it, also inside functions or by name through ``importlib``; no two files import each
other, directly or round a longer loop; and an import inside a function says why it is not at the
top of its file. Importing ``a.b.c`` from outside ``a.b`` runs ``a/b/__init__.py`` too, so that
counts as an import of the package file as well."""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CORE = "jax3dc"
ABOVE_CORE = ("data_pipeline", "train", "eval", "recipes", "bench", "tests", "scripts")
PRODUCT = (CORE, "data_pipeline", "train", "eval", "recipes", "bench")  # held to the top-of-file rule
LAZY_REASON = re.compile(r"\blazy:\s*\S")  # "# lazy: <the measured cost, or the optional dependency>"


def module_files(root: Path, packages: tuple[str, ...]) -> dict[str, Path]:
    """Dotted module name -> file, for every .py file of ``packages`` under ``root``."""
    modules = {}
    for package in packages:
        for path in (root / package).rglob("*.py"):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            modules[".".join(parts)] = path
    return modules


def imported_names(module: str, path: Path) -> list[tuple[str, int]]:
    """(dotted name, line) of every import in the file, wherever it stands, and of every
    ``importlib.import_module("constant")``."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package[:len(package) - node.level + 1] + ([base] if base else []))
            names += [(f"{base}.{alias.name}", node.lineno) for alias in node.names]
            names.append((base, node.lineno))
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "import_module"
              and node.args and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)):
            names.append((node.args[0].value, node.lineno))
    return names


def import_graph(root: Path, packages: tuple[str, ...]) -> tuple[dict[str, set[str]], dict[tuple[str, str], int]]:
    """Module -> the project modules it imports (package ``__init__`` files it runs included), and
    the line of each edge."""
    modules = module_files(root, packages)
    graph: dict[str, set[str]] = {m: set() for m in modules}
    lines: dict[tuple[str, str], int] = {}
    for module, path in modules.items():
        for name, line in imported_names(module, path):
            parts = name.split(".")
            targets = [".".join(parts[:i]) for i in range(1, len(parts) + 1) if ".".join(parts[:i]) in modules]
            for target in targets:  # the module and each package file that importing it runs
                if target != module and not module.startswith(target + "."):
                    graph[module].add(target)
                    lines.setdefault((module, target), line)
    return graph, lines


def back_edges(graph: dict[str, set[str]], lines: dict[tuple[str, str], int]) -> list[str]:
    return [f"{m} (line {lines[m, t]}) imports {t}" for m, targets in sorted(graph.items())
            if m.split(".")[0] == CORE for t in sorted(targets) if t.split(".")[0] != CORE]


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))
            elif child not in index:
                index[child] = low[child] = len(index)
                stack.append(child)
                on_stack.add(child)
                work.append((child, iter(sorted(graph[child]))))
            elif child in on_stack:
                low[node] = min(low[node], index[child])
    return found


def _comments(text: str) -> dict[int, str]:
    """Line -> the comment on it (a ``#`` inside a string is none)."""
    tokens = tokenize.generate_tokens(io.StringIO(text).readline)
    return {t.start[0]: t.string for t in tokens if t.type == tokenize.COMMENT}


def _previous_statement(tree: ast.AST) -> dict[ast.stmt, ast.stmt | None]:
    """Statement -> the one before it in the same block (None for a block's first)."""
    previous = {}
    for node in ast.walk(tree):
        for field in ("body", "orelse", "finalbody"):
            block = getattr(node, field, None)
            if isinstance(block, list):
                previous.update(zip(block, [None, *block]))
    return previous


def unexplained_lazy_imports(root: Path, packages: tuple[str, ...]) -> list[str]:
    """``path:line`` of each import inside a function body that no ``# lazy: why`` explains: on
    its own lines, on the comment lines just above it, or above the run of imports it closes (one
    statement per line, blank lines between groups allowed), so one reason covers a block."""
    found = []
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            text = path.read_text(encoding="utf-8")
            lines = text.splitlines()
            comments = _comments(text)
            tree = ast.parse(text, str(path))
            previous = _previous_statement(tree)

            def reason_above(line: int) -> bool:
                while line >= 1 and lines[line - 1].lstrip().startswith("#"):
                    if LAZY_REASON.search(comments.get(line, "")):
                        return True
                    line -= 1
                return False

            def explained_above(node: ast.stmt) -> bool:
                """By the comment above it or above the run of imports it closes."""
                before = previous.get(node)
                return reason_above(node.lineno - 1) or (
                    isinstance(before, (ast.Import, ast.ImportFrom))
                    and not any(line.strip() for line in lines[before.end_lineno:node.lineno - 1])
                    and explained_above(before))

            def explained(node: ast.stmt) -> bool:
                own = range(node.lineno, node.end_lineno + 1)
                return any(LAZY_REASON.search(comments.get(n, "")) for n in own) or explained_above(node)

            lazy = {node for func in ast.walk(tree) if isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef))
                    for node in ast.walk(func) if isinstance(node, (ast.Import, ast.ImportFrom))}
            found += [f"{path.relative_to(root)}:{node.lineno}"
                      for node in sorted(lazy, key=lambda n: (n.lineno, n.col_offset)) if not explained(node)]
    return found


def test_core_imports_nothing_above_it():
    graph, lines = import_graph(ROOT, (CORE, *ABOVE_CORE))
    assert back_edges(graph, lines) == []


def test_no_import_cycle_between_files():
    graph, _ = import_graph(ROOT, (CORE, *ABOVE_CORE))
    assert cycles(graph) == []


def test_only_tests_build_on_recipes():
    """The recipes make the shipped weights through every other package, so none of those may need
    them: a recipe stays a top layer that can change without moving the product."""
    graph, lines = import_graph(ROOT, (CORE, *ABOVE_CORE))
    assert [f"{m} (line {lines[m, t]}) imports {t}" for m, targets in sorted(graph.items())
            if m.split(".")[0] not in ("recipes", "tests") for t in sorted(targets) if t.split(".")[0] == "recipes"] == []


def test_every_import_inside_a_function_says_why():
    assert unexplained_lazy_imports(ROOT, PRODUCT) == []


def test_lazy_import_check_finds_the_unexplained(tmp_path: Path):
    (tmp_path / "train").mkdir()
    (tmp_path / "train" / "a.py").write_text(
        "import json\n"
        "def f():\n"
        "    import torch  # lazy: optional, the test extra only\n"
        "    # lazy: mujoco (0.1 s) only for the physics path\n"
        "    import mujoco\n"
        "    from pxr import Usd\n"
        "    x = '# lazy: a string, not a comment'; import scipy\n"
        "    # measured nothing\n"
        "    import tqdm\n"
        "    def g():\n"
        "        import PIL  # noqa\n"
        "class C:\n"
        "    def m(self):\n"
        "        # lazy:\n"
        "        import jax\n"
        "def h():\n"
        "    # lazy: optax (0.1 s) for training only\n"
        "    import optax\n"
        "\n"
        "    from train.loop import run\n"
        "    run()\n"
        "    import orbax\n")
    assert unexplained_lazy_imports(tmp_path, ("train",)) == ["train/a.py:7", "train/a.py:9", "train/a.py:11",
                                                              "train/a.py:15", "train/a.py:22"]


@pytest.fixture
def bad_tree(tmp_path: Path) -> Path:
    """A core file importing evaluation inside a function, and a loop through a package file."""
    for name, text in {
        "jax3dc/__init__.py": "",
        "jax3dc/cli.py": "import importlib\ndef load():\n    importlib.import_module('eval.cli')\n",
        "jax3dc/a/__init__.py": "from jax3dc.a.one import f\n",
        "jax3dc/a/one.py": "def f():\n    from jax3dc.b import g\n",
        "jax3dc/b.py": "from jax3dc.a.two import h\n",
        "jax3dc/a/two.py": "h = 1\n",
        "eval/__init__.py": "",
        "eval/cli.py": "from ..jax3dc import cli\n",
    }.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    return tmp_path


def test_checks_find_a_back_edge_and_a_loop(bad_tree: Path):
    graph, lines = import_graph(bad_tree, ("jax3dc", "eval"))
    assert back_edges(graph, lines) == ["jax3dc.cli (line 3) imports eval", "jax3dc.cli (line 3) imports eval.cli"]
    assert cycles(graph) == [["eval.cli", "jax3dc.cli"], ["jax3dc.a", "jax3dc.a.one", "jax3dc.b"]]
