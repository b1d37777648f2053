"""The package's shape: its modules import one another one way (no import cycle), no file is over 400 lines and
no function over 60 (from `def` to its last line, docstring included)."""
from __future__ import annotations

import ast
import graphlib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "cyberdog"
MAX_FILE_LINES = 400
MAX_FUNCTION_LINES = 60


def modules(package: Path) -> dict[str, Path]:
    """{dotted module name: file} of every module of `package` (a package's own name for its __init__.py)."""
    out = {}
    for path in sorted(package.rglob("*.py")):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _base(module: str, is_package: bool, level: int, target: str | None) -> str:
    """The absolute name `from <level dots><target> import ...` means in `module`."""
    if level == 0:
        return target or ""
    parts = module.split(".") if is_package else module.split(".")[:-1]
    parts = parts[:len(parts) - (level - 1)]
    return ".".join(parts + ([target] if target else []))


def imports(module: str, path: Path, known: dict[str, Path]) -> set[str]:
    """The modules of `known` that `module` imports, anywhere in its file (a function's import too): `import a.b`
    is an edge to a.b; `from p import n` to p.n where that is a module, else to p (n is an attribute of p)."""
    is_package = path.name == "__init__.py"
    out = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out |= {alias.name for alias in node.names if alias.name in known}
        elif isinstance(node, ast.ImportFrom):
            base = _base(module, is_package, node.level, node.module)
            for alias in node.names:
                if f"{base}.{alias.name}" in known:
                    out.add(f"{base}.{alias.name}")
                elif base in known:
                    out.add(base)
    out.discard(module)
    return out


def import_graph(package: Path) -> dict[str, set[str]]:
    known = modules(package)
    return {name: imports(name, path, known) for name, path in known.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of `graph` with more than one module, each sorted (Tarjan's algorithm)."""
    index, low, stack, on_stack, components = {}, {}, [], set(), []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                components.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(components)


def loop(graph: dict[str, set[str]], component: list[str]) -> list[str]:
    """A shortest closed walk from the component's first module back to it, through modules of the component."""
    start, members = component[0], set(component)
    paths, frontier = {start: [start]}, [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(graph[v] & members):
                if w == start:
                    return paths[v] + [start]
                if w not in paths:
                    paths[w] = paths[v] + [w]
                    nxt.append(w)
        frontier = nxt
    raise ValueError(f"{component} is not a strongly connected component of the graph")


def describe_cycles(graph: dict[str, set[str]]) -> str:
    return "\n".join(f"{', '.join(c)}: e.g. {' -> '.join(loop(graph, c))}" for c in cycles(graph))


def long_functions(path: Path, limit: int = MAX_FUNCTION_LINES) -> list[str]:
    """'<file>::<function> (line N): M lines' of every function (method, nested one) of `path` over `limit` lines."""
    name = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            n = node.end_lineno - node.lineno + 1
            if n > limit:
                found.append(f"{name}::{node.name} (line {node.lineno}): {n} lines")
    return found


def test_the_package_imports_one_way_without_a_cycle():
    graph = import_graph(PACKAGE)
    found = len(cycles(graph))
    assert found == 0, f"{found} group(s) of modules import one another in a circle:\n{describe_cycles(graph)}"


def test_no_file_over_400_lines_and_no_function_over_60():
    long_files = [f"{p.relative_to(ROOT)}: {n} lines" for p in sorted(PACKAGE.rglob("*.py"))
                  if (n := len(p.read_text().splitlines())) > MAX_FILE_LINES]
    functions = [f for p in sorted(PACKAGE.rglob("*.py")) for f in long_functions(p)]
    assert not long_files and not functions, "\n".join(long_files + functions)


# ---- the checks themselves, on a package made here ----------------------------------------------------------------

def _package(tmp_path: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = tmp_path / "pkg" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return tmp_path / "pkg"


def test_imports_resolve_absolute_relative_and_lazy_forms_to_modules(tmp_path):
    pkg = _package(tmp_path, {
        "__init__.py": "from pkg.sub import thing\n",
        "sub/__init__.py": "thing = 1\n",
        "sub/a.py": "from . import b\nfrom .b import name\nfrom pkg.sub import thing\nimport pkg.c\n",
        "sub/b.py": "def f():\n    from .. import c\n    from ..c import x\n",
        "c.py": "from pkg import sub\nfrom pkg.sub import a as alias\nimport os\n",
    })
    graph = import_graph(pkg)
    assert graph == {"pkg": {"pkg.sub"}, "pkg.sub": set(), "pkg.sub.a": {"pkg.sub.b", "pkg.sub", "pkg.c"},
                     "pkg.sub.b": {"pkg.c"}, "pkg.c": {"pkg.sub", "pkg.sub.a"}}
    assert cycles(graph) == [["pkg.c", "pkg.sub.a", "pkg.sub.b"]]
    assert loop(graph, cycles(graph)[0]) == ["pkg.c", "pkg.sub.a", "pkg.c"]


def test_a_cycle_through_three_modules_is_named_and_a_chain_is_not(tmp_path):
    pkg = _package(tmp_path, {"__init__.py": "", "a.py": "from pkg import b\n", "b.py": "import pkg.c\n",
                              "c.py": "def later():\n    from pkg.a import x\n", "d.py": "from pkg import a\n"})
    graph = import_graph(pkg)
    assert cycles(graph) == [["pkg.a", "pkg.b", "pkg.c"]]
    assert describe_cycles(graph) == "pkg.a, pkg.b, pkg.c: e.g. pkg.a -> pkg.b -> pkg.c -> pkg.a"
    (pkg / "c.py").write_text("import os\n")
    assert cycles(import_graph(pkg)) == []


def test_a_function_over_the_limit_is_named_with_its_docstring_counted(tmp_path):
    body = "\n".join(f"    x{i} = {i}" for i in range(57))
    path = tmp_path / "m.py"
    path.write_text(f'def fits():\n    """Doc."""\n{body}\n\n\ndef over():\n    """Doc.\n\n    More."""\n{body}\n')
    assert long_functions(path) == [f"{path}::over (line 62): 61 lines"]


# what the code and the presets say is what is; how it came to be is the research log's
HISTORY_WORDS = ("tried", "earlier", "legacy", "retired", "no longer")


def history_words(text: str) -> list[str]:
    """The history words of `text`, as whole words, case-insensitively."""
    import re
    return [m.group(0) for w in HISTORY_WORDS for m in re.finditer(rf"\b{w}\b", text, flags=re.I)]


def test_the_package_and_the_presets_say_what_is_not_how_it_came_to_be():
    found = [f"{p.relative_to(ROOT)}:{i}: {line.strip()[:100]}"
             for p in sorted([*PACKAGE.rglob("*.py"), *(ROOT / "configs").rglob("*.yaml")])
             for i, line in enumerate(p.read_text().splitlines(), 1) if history_words(line)]
    assert not found, "\n".join(found)


def test_history_words_are_found_as_whole_words_only():
    assert history_words("an Earlier run, no longer used; it was tried") == ["tried", "Earlier", "no longer"]
    assert history_words("untried, legacyless") == []


# ---- the learning layer ----
def rl_imports() -> dict[str, set[str]]:
    """Each module of cyberdog/rl (its package `__init__` aside) → the modules of cyberdog/rl it imports (lazily
    or for type checking too); importing the package itself counts as "__init__"."""
    graph = {}
    for path in (PACKAGE / "rl").glob("*.py"):
        if path.name == "__init__.py":
            continue
        names = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module == "cyberdog":
                names |= {f"cyberdog.{a.name}" for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.module:
                names.add(node.module)
            elif isinstance(node, ast.Import):
                names |= {a.name for a in node.names}
        graph[path.stem] = {"__init__" if n == "cyberdog.rl" else n.split(".")[2] for n in names
                            if n == "cyberdog.rl" or n.startswith("cyberdog.rl.")}
    return graph


def test_the_rl_modules_import_one_another_by_module_and_without_a_circle():
    graph = rl_imports()
    assert {"td3", "trainer", "collect"} <= set(graph)
    through_package = sorted(m for m, deps in graph.items() if "__init__" in deps)
    assert not through_package, f"{through_package} import cyberdog.rl itself: import its modules directly"
    order = list(graphlib.TopologicalSorter(graph).static_order())  # raises CycleError on a circle
    assert order.index("td3") < order.index("trainer") and order.index("exploration") < order.index("collect")
