"""The package's design, measured: these tests fail when it regresses.

Run it as a script for a report, one line per metric with its value and limit
(`.venv/bin/python tests/test_design.py`, `-v` to list the offenders as well).

Everything is static analysis (`ast`, `json`, `tomllib`) of the source tree, except the
names of the registered shading models, shadow methods and orderings (measure 4), which
are read from `hairjax` itself. Each measure is a small pure function taking the
repository root and returning its offenders (empty: it holds); the real tests run it on
this repository, the self-tests on a synthetic tree written to `tmp_path`, to show that
the measure can fail.

1. No import cycles between the modules of `hairjax/`. The graph: one node per module
   (a package is its `__init__`), an edge A → B when A's code imports B: module-level
   imports and imports inside functions (a lazy import that closes a cycle is still a
   cycle), not those under `if TYPE_CHECKING:` (they never run). Relative imports are
   resolved; `from pkg import name` is an edge to `pkg.name` when that is a module,
   else to `pkg`. Importing a submodule also runs its parent packages' `__init__`, as
   Python always does; that implicit edge is not drawn (it would put every package in a
   cycle with its own submodules). A cycle is a strongly connected component of more
   than one module. One kind is allowed: a package's `__init__` that imports its
   submodules, where a submodule takes a name back from that `__init__` (the `__init__`
   re-exporting it) — i.e. an SCC of one `__init__` and its own submodules in which
   every edge into the `__init__` comes from one of those submodules. (No such SCC
   exists in hairjax today; the rule keeps the re-export idiom legal.)
1b. No import cycles between the packages of `hairjax/`: the same graph with each module
   replaced by its top-level part (`hairjax._geometry._shadows._exact` is
   `hairjax._geometry`; a top-level module is its own part), edges inside a part dropped.
   Layers read one way (docs/architecture.md, "Layers"): a package never imports a
   package that imports it back, at run time.
2. No module over 400 physical lines in `hairjax/`, and no function over 80 (from its `def`
   line to its last, the functions nested in it included).
3. No private name taken across modules of `hairjax/`: `from X import _name`, X another
   hairjax module, `_name` not itself a module. A private *module* (`from . import
   _opacity_maps`, `from ._shading import point_colors`) is fine; dunders are not private.
4. No string dispatch on model/method names: no comparison (`==`, `!=`, `is`, `in`, …,
   and `match`/`case`) in `hairjax/` with a string constant that is a registered shading
   model, shadow method or ordering name, nor an `in` test against a literal
   tuple/list/set/dict holding one. Declarations (`name = "kajiya-kay"` in a class body),
   registry keys and defaults are not comparisons, so they are allowed. The old API's
   identifiers (`shading_model`, `lookup_size`, `scheuermann_maps`, `SHADING_MODEL_IDS`,
   `LOOKUP_MODELS`) appear nowhere in `hairjax/` as a name, attribute, argument, keyword,
   definition or imported name.
5. Every `experiments/*.py` is named `NN_name.py` (two digits, no number twice) and is
   named in `experiments/README.md`; the README names no `NN_name.py` that does not exist.
6. Experiments (`experiments/*.py`) and notebooks (code cells of `notebooks/*.ipynb`) use
   the public API only: no `import hairjax._x`, `from hairjax._x import …`, `from hairjax
   import _x`, nor `hairjax._x` as an attribute (any private component: `hairjax.gl._y`).
7. No issue numbers in `hairjax/` (`.py` and the shaders and scenes): `issue 12`,
   `issue #12`, any case.
8. `import hairjax` loads no tools, matplotlib or rich: tests/test_import.py.
9. The tooling is wired: `make test` runs `ruff check`, `ruff format --check` and a type
   checker (`mypy` or `basedpyright`) before pytest; pytest's addopts hold
   `--jaxtyping-packages=hairjax,beartype.beartype`; pyproject's `test` extra lists ruff
   and the type checker.
"""

from __future__ import annotations

import ast
import importlib
import json
import re
import sys
import tomllib
from collections.abc import Iterable, Iterator
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGE = "hairjax"

MAX_MODULE_LINES = 400
MAX_FUNCTION_LINES = 80
OLD_NAMES = frozenset(
    {"shading_model", "lookup_size", "scheuermann_maps", "SHADING_MODEL_IDS", "LOOKUP_MODELS"}
)
ISSUE_SUFFIXES = (".py", ".glsl", ".vert", ".frag", ".comp", ".geom", ".toml")
ISSUE_RE = re.compile(r"\bissues?\s*#?\s*\d+", re.IGNORECASE)
EXPERIMENT_RE = re.compile(r"^\d{2}_[a-z0-9_]+\.py$")
README_EXPERIMENT_RE = re.compile(r"(?<![\w/.-])(?:experiments/)?(\d{2}_\w+\.py)\b")
TYPE_CHECKERS = ("mypy", "basedpyright")
JAXTYPING_OPT = "--jaxtyping-packages=hairjax,beartype.beartype"


# --- the package's modules -------------------------------------------------------------


def package_modules(root: Path, package: str = PACKAGE) -> dict[str, Path]:
    """Module name → file, for every `.py` below `root/package` (a package is its
    `__init__.py`)."""
    base = root / package
    modules = {}
    for path in sorted(base.rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        modules[".".join(parts)] = path
    return modules


def _is_package(path: Path) -> bool:
    return path.name == "__init__.py"


def _resolve_from(module: str, is_package: bool, level: int, target: str | None) -> str:
    """The absolute module name of `from <level dots><target> import …` in `module`."""
    if level == 0:
        return target or ""
    parts = module.split(".") if is_package else module.split(".")[:-1]
    parts = parts[: len(parts) - (level - 1)] if level > 1 else parts
    return ".".join(parts + ([target] if target else []))


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _walk_running(tree: ast.AST) -> Iterator[ast.AST]:
    """`ast.walk` without the bodies of `if TYPE_CHECKING:` (their `else:` runs)."""
    stack = [tree]
    while stack:
        node = stack.pop()
        yield node
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            stack.extend(reversed(node.orelse))
            stack.append(node.test)
            continue
        stack.extend(reversed(list(ast.iter_child_nodes(node))))


def _parse(path: Path) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"), filename=str(path))


def _imports(
    module: str, path: Path, modules: dict[str, Path], *, running_only: bool
) -> Iterator[tuple[int, str, str | None]]:
    """(line, imported module, name) for each import in `module`: the module that the
    import loads (`pkg.name` when that is a module, else `pkg`), and for `from … import
    name` the name. `running_only`: skip `if TYPE_CHECKING:` blocks."""
    tree = _parse(path)
    nodes = _walk_running(tree) if running_only else ast.walk(tree)
    for node in nodes:
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name, None
        elif isinstance(node, ast.ImportFrom):
            target = _resolve_from(module, _is_package(path), node.level, node.module)
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                yield node.lineno, (sub if sub in modules else target), alias.name


# --- 1. import cycles ------------------------------------------------------------------


def import_graph(root: Path, package: str = PACKAGE) -> dict[str, dict[str, list[int]]]:
    """Module → {imported module of the package: lines}, as measure 1 draws it."""
    modules = package_modules(root, package)
    graph: dict[str, dict[str, list[int]]] = {m: {} for m in modules}
    for module, path in modules.items():
        for line, imported, _ in _imports(module, path, modules, running_only=True):
            if imported in modules and imported != module:
                graph[module].setdefault(imported, []).append(line)
    return graph


def strongly_connected(graph: dict[str, dict[str, list[int]]]) -> list[list[str]]:
    """Tarjan's strongly connected components of `graph`, each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    components: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
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
            components.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return components


def _is_reexport_cycle(
    component: list[str], graph: dict[str, dict[str, list[int]]], packages: set[str]
) -> bool:
    """One package `__init__` and its own submodules, which have no cycle among them once
    the `__init__` is left out: the only way back is through the `__init__` re-exporting
    what they take from it."""
    inits = [m for m in component if m in packages]
    if len(inits) != 1:
        return False
    init = inits[0]
    rest = [m for m in component if m != init]
    if not all(m.startswith(init + ".") for m in rest):
        return False
    inner = {m: {b: lines for b, lines in graph[m].items() if b in rest} for m in rest}
    return all(len(c) == 1 for c in strongly_connected(inner))


def import_cycles(root: Path, package: str = PACKAGE) -> list[str]:
    graph = import_graph(root, package)
    modules = package_modules(root, package)
    packages = {m for m, p in modules.items() if _is_package(p)}
    offenders = []
    for component in strongly_connected(graph):
        if len(component) < 2 or _is_reexport_cycle(component, graph, packages):
            continue
        members = set(component)
        edges = "; ".join(
            f"{a} -> {b} (line {', '.join(map(str, sorted(set(lines))))})"
            for a in component
            for b, lines in sorted(graph[a].items())
            if b in members
        )
        offenders.append(f"cycle of {len(component)} modules {component}: {edges}")
    return offenders


def _part(module: str, package: str = PACKAGE) -> str:
    """The top-level part of `package` that `module` belongs to (itself if top-level)."""
    return ".".join(module.split(".")[:2])


def package_graph(root: Path, package: str = PACKAGE) -> dict[str, dict[str, list[str]]]:
    """Top-level part → {imported part: the module edges behind it}, as measure 1b draws it."""
    graph: dict[str, dict[str, list[str]]] = {}
    for module, imported in import_graph(root, package).items():
        a = _part(module, package)
        graph.setdefault(a, {})
        for target, lines in imported.items():
            b = _part(target, package)
            if a != b:
                where = ", ".join(map(str, sorted(set(lines))))
                graph[a].setdefault(b, []).append(f"{module} -> {target} (line {where})")
    return graph


def package_cycles(root: Path, package: str = PACKAGE) -> list[str]:
    graph = package_graph(root, package)
    offenders = []
    for component in strongly_connected(graph):  # type: ignore[arg-type]
        if len(component) < 2:
            continue
        members = set(component)
        edges = "; ".join(e for a in component for b in sorted(graph[a]) if b in members for e in graph[a][b])
        offenders.append(f"cycle of {len(component)} packages {component}: {edges}")
    return offenders


# --- 2. module size --------------------------------------------------------------------


def module_lines(root: Path, package: str = PACKAGE) -> dict[str, int]:
    return {
        str(p.relative_to(root)): len(p.read_text(encoding="utf-8").splitlines())
        for p in package_modules(root, package).values()
    }


def long_modules(root: Path, package: str = PACKAGE, limit: int = MAX_MODULE_LINES) -> list[str]:
    return [
        f"{path}: {n} lines (limit {limit})"
        for path, n in sorted(module_lines(root, package).items(), key=lambda kv: -kv[1])
        if n > limit
    ]


def long_functions(root: Path, package: str = PACKAGE, limit: int = MAX_FUNCTION_LINES) -> list[str]:
    offenders = []
    for path in sorted(package_modules(root, package).values()):
        for node in ast.walk(_parse(path)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = (node.end_lineno or node.lineno) - node.lineno + 1
                if n > limit:
                    offenders.append(
                        f"{path.relative_to(root)}:{node.lineno} {node.name}: {n} lines (limit {limit})"
                    )
    return offenders


# --- 3. private names across modules ---------------------------------------------------


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_imports(root: Path, package: str = PACKAGE) -> list[str]:
    modules = package_modules(root, package)
    offenders = []
    for module, path in modules.items():
        for line, imported, name in _imports(module, path, modules, running_only=False):
            internal = imported == package or imported.startswith(package + ".")
            if (
                name is not None
                and _is_private(name)
                and internal
                and imported != module
                and not imported.endswith("." + name)
            ):
                offenders.append(f"{path.relative_to(root)}:{line}: from {imported} import {name}")
    return offenders


# --- 4. string dispatch ----------------------------------------------------------------

# (kind, function returning the registered names, where to look: `hairjax` first).
NAME_SOURCES = (
    (
        "shading models",
        "shading_model_names",
        ("hairjax", "hairjax._shading", "hairjax._shading._model", "hairjax._geometry._shading"),
    ),
    (
        "shadow methods",
        "shadow_method_names",
        (
            "hairjax",
            "hairjax._geometry._shadows",
            "hairjax._geometry._shadows._base",
            "hairjax._geometry._shadows",
            "hairjax._geometry",
        ),
    ),
    (
        "orderings",
        "ordering_names",
        (
            "hairjax",
            "hairjax._geometry._ordering",
            "hairjax._geometry._ordering._base",
            "hairjax._geometry._ordering",
            "hairjax._geometry",
        ),
    ),
)


def declared_names(root: Path, package: str = PACKAGE) -> set[str]:
    """The fallback: every `name = "…"` / `method = "…"` in a class body of the package
    (how models, shadow methods and orderings declare their registered names)."""
    names = set()
    for path in package_modules(root, package).values():
        for cls in ast.walk(_parse(path)):
            if not isinstance(cls, ast.ClassDef):
                continue
            for stmt in cls.body:
                targets = (
                    stmt.targets
                    if isinstance(stmt, ast.Assign)
                    else [stmt.target]
                    if isinstance(stmt, ast.AnnAssign)
                    else []
                )
                value = getattr(stmt, "value", None)
                if (
                    isinstance(value, ast.Constant)
                    and isinstance(value.value, str)
                    and any(isinstance(t, ast.Name) and t.id in ("name", "method") for t in targets)
                ):
                    names.add(value.value)
    return names


def registered_names(root: Path = REPO) -> dict[str, tuple[str, ...]]:
    """The registered names by kind, from `hairjax`; where a lookup function cannot be
    found, the class-body declarations of the source instead."""
    found: dict[str, tuple[str, ...]] = {}
    for kind, function, places in NAME_SOURCES:
        for place in places:
            try:
                names = getattr(importlib.import_module(place), function)
            except (ImportError, AttributeError):
                continue
            found[kind] = tuple(names())
            break
    if len(found) < len(NAME_SOURCES):
        found["declared (fallback)"] = tuple(sorted(declared_names(root)))
    return found


def _string(node: ast.AST) -> str | None:
    return node.value if isinstance(node, ast.Constant) and isinstance(node.value, str) else None


def _literal_strings(node: ast.AST) -> list[str]:
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        elts = node.elts
    elif isinstance(node, ast.Dict):
        elts = [k for k in node.keys if k is not None]
    else:
        return []
    return [s for s in map(_string, elts) if s is not None]


def _identifiers(node: ast.AST) -> list[str]:
    if isinstance(node, ast.Name):
        return [node.id]
    if isinstance(node, ast.Attribute):
        return [node.attr]
    if isinstance(node, ast.arg | ast.keyword):
        return [node.arg] if node.arg else []
    if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
        return [node.name]
    if isinstance(node, ast.alias):
        return [node.name.rsplit(".", 1)[-1]] + ([node.asname] if node.asname else [])
    return []


def string_dispatch(
    root: Path, names: Iterable[str], package: str = PACKAGE, old_names: Iterable[str] = OLD_NAMES
) -> list[str]:
    names, old_names = set(names), set(old_names)
    offenders = []
    for path in package_modules(root, package).values():
        where = path.relative_to(root)
        source = path.read_text(encoding="utf-8")
        for node in ast.walk(ast.parse(source, filename=str(path))):
            hits: list[str] = []
            if isinstance(node, ast.Compare):
                operands = [node.left, *node.comparators]
                hits = [s for s in map(_string, operands) if s in names]
                for op, right in zip(node.ops, operands[1:], strict=True):
                    if isinstance(op, ast.In | ast.NotIn):
                        hits += [s for s in _literal_strings(right) if s in names]
            elif isinstance(node, ast.MatchValue):
                hits = [s for s in [_string(node.value)] if s in names]
            if hits:
                text = ast.get_source_segment(source, node) or ast.dump(node)
                offenders.append(
                    f"{where}:{node.lineno}: compares with {sorted(set(hits))}: {' '.join(text.split())}"
                )
            old = [i for i in _identifiers(node) if i in old_names]
            if old:
                offenders.append(f"{where}:{getattr(node, 'lineno', 0)}: old name {old[0]}")
    return sorted(offenders, key=_by_place)


def _by_place(offender: str) -> tuple[str, int]:
    path, line, _ = offender.split(":", 2)
    return path, int(line)


# --- 5. experiments numbered and indexed -----------------------------------------------


def experiment_index(root: Path) -> list[str]:
    folder = root / "experiments"
    scripts = sorted(p.name for p in folder.glob("*.py"))
    offenders = [f"experiments/{s}: not named NN_name.py" for s in scripts if not EXPERIMENT_RE.match(s)]
    numbers: dict[str, list[str]] = {}
    for s in scripts:
        if EXPERIMENT_RE.match(s):
            numbers.setdefault(s[:2], []).append(s)
    offenders += [f"experiments/: number {n} used by {same}" for n, same in numbers.items() if len(same) > 1]
    readme = folder / "README.md"
    if not readme.is_file():
        return offenders + ["experiments/README.md: missing"]
    text = readme.read_text(encoding="utf-8")
    offenders += [f"experiments/README.md: does not name {s}" for s in scripts if s not in text]
    named = sorted(set(README_EXPERIMENT_RE.findall(text)))
    offenders += [
        f"experiments/README.md: names {s}, which does not exist" for s in named if s not in scripts
    ]
    return offenders


# --- 6. public API in experiments and notebooks ----------------------------------------


def _private_uses(tree: ast.AST, package: str = PACKAGE) -> Iterator[tuple[int, str]]:
    def private(dotted: str) -> bool:
        parts = dotted.split(".")
        return parts[0] == package and any(_is_private(p) for p in parts[1:])

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from ((node.lineno, f"import {a.name}") for a in node.names if private(a.name))
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if private(node.module):
                yield node.lineno, f"from {node.module} import …"
            else:
                yield from (
                    (node.lineno, f"from {node.module} import {a.name}")
                    for a in node.names
                    if private(f"{node.module}.{a.name}")
                )
        elif isinstance(node, ast.Attribute) and _is_private(node.attr):
            chain, inner = [node.attr], node.value
            while isinstance(inner, ast.Attribute):
                chain.append(inner.attr)
                inner = inner.value
            if isinstance(inner, ast.Name) and inner.id == package:
                dotted = ".".join([package, *reversed(chain)])
                # Report the outermost private step only once (the innermost attribute).
                if not any(_is_private(p) for p in reversed(chain[1:])):
                    yield node.lineno, dotted


def _cell_source(cell: dict) -> str:
    source = cell.get("source", "")
    return "".join(source) if isinstance(source, list) else source


_MAGIC_RE = re.compile(r"^(\s*)([%!]|\w+\s*=\s*[%!])", re.MULTILINE)
_PRIVATE_TEXT_RE = re.compile(rf"\b{PACKAGE}(?:\.\w+)*\._(?!_)\w*|from\s+{PACKAGE}\S*\s+import\s+.*\b_\w")


def public_api(root: Path) -> list[str]:
    offenders = []
    for path in sorted((root / "experiments").glob("*.py")):
        offenders += [
            f"{path.relative_to(root)}:{line}: {what}" for line, what in _private_uses(_parse(path))
        ]
    for path in sorted((root / "notebooks").glob("*.ipynb")):
        notebook = json.loads(path.read_text(encoding="utf-8"))
        for number, cell in enumerate(notebook.get("cells", []), 1):
            if cell.get("cell_type") != "code":
                continue
            source = _cell_source(cell)
            # IPython magics and shell escapes are not Python: comment them out.
            python = _MAGIC_RE.sub(lambda m: m.group(1) + "#" + m.group(2), source)
            where = f"{path.relative_to(root)} cell {number}"
            try:
                uses = [f"{where} line {line}: {what}" for line, what in _private_uses(ast.parse(python))]
            except SyntaxError:
                uses = [f"{where}: {m.group(0)}" for m in _PRIVATE_TEXT_RE.finditer(source)]
            offenders += uses
    return offenders


# --- 7. issue numbers ------------------------------------------------------------------


def issue_numbers(root: Path, package: str = PACKAGE) -> list[str]:
    offenders = []
    for path in sorted((root / package).rglob("*")):
        if path.suffix not in ISSUE_SUFFIXES or "__pycache__" in path.parts or not path.is_file():
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            offenders += [
                f"{path.relative_to(root)}:{number}: {m.group(0)!r}" for m in ISSUE_RE.finditer(line)
            ]
    return offenders


# --- 9. tooling ------------------------------------------------------------------------


def _make_rules(text: str) -> dict[str, tuple[list[str], list[str]]]:
    """Target → (prerequisites, recipe commands) of a Makefile (continuations joined)."""
    text = re.sub(r"\\\n\s*", " ", text)
    rules: dict[str, tuple[list[str], list[str]]] = {}
    current: list[str] | None = None
    for line in text.splitlines():
        if line.startswith("\t"):
            if current is not None:
                current.append(line.strip())
            continue
        match = re.match(r"^([^\s:#=][^:=]*?)\s*:(?!=)\s*([^=;#]*)", line)
        if match and not line.lstrip().startswith("#"):
            prereqs = [p for p in match.group(2).replace("|", " ").split()]
            current = []
            for target in match.group(1).split():
                rules[target] = (prereqs, current)
        elif line.strip() and not line.lstrip().startswith("#"):
            current = None
    return rules


def _recipe(
    rules: dict[str, tuple[list[str], list[str]]], target: str, seen: set[str] | None = None
) -> list[str]:
    """The commands `make target` runs, in order: its prerequisites' first."""
    seen = set() if seen is None else seen
    if target in seen or target not in rules:
        return []
    seen.add(target)
    prereqs, commands = rules[target]
    return [c for p in prereqs for c in _recipe(rules, p, seen)] + commands


def _requirement_name(requirement: str) -> str:
    match = re.match(r"\s*([A-Za-z0-9][A-Za-z0-9._-]*)", requirement)
    return match.group(1).lower().replace("_", "-") if match else ""


def tooling(root: Path) -> list[str]:
    offenders = []
    makefile = root / "Makefile"
    commands = (
        _recipe(_make_rules(makefile.read_text(encoding="utf-8")), "test") if makefile.is_file() else []
    )
    if not commands:
        offenders.append("Makefile: no `test` target")

    def first(pattern: str) -> int | None:
        return next((i for i, c in enumerate(commands) if re.search(pattern, c)), None)

    pytest_at = first(r"\bpytest\b")
    steps = {
        "ruff check": r"\bruff\s+check\b",
        "ruff format --check": r"\bruff\s+format\b.*--check",
        "a type checker (mypy or basedpyright)": r"\b(mypy|basedpyright)\b",
    }
    if pytest_at is None and commands:
        offenders.append("Makefile: `make test` does not run pytest")
    for step, pattern in steps.items():
        at = first(pattern)
        if at is None:
            offenders.append(f"Makefile: `make test` does not run {step}")
        elif pytest_at is not None and at > pytest_at:
            offenders.append(f"Makefile: `make test` runs {step} after pytest")

    pyproject = tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))
    addopts = pyproject.get("tool", {}).get("pytest", {}).get("ini_options", {}).get("addopts", "")
    addopts = addopts.split() if isinstance(addopts, str) else list(addopts)
    if JAXTYPING_OPT not in addopts:
        offenders.append(f"pyproject.toml: pytest addopts lack {JAXTYPING_OPT}")
    extra = {
        _requirement_name(r)
        for r in pyproject.get("project", {}).get("optional-dependencies", {}).get("test", [])
    }
    if "ruff" not in extra:
        offenders.append("pyproject.toml: the `test` extra does not list ruff")
    if not extra & set(TYPE_CHECKERS):
        offenders.append("pyproject.toml: the `test` extra lists no type checker (mypy or basedpyright)")
    return offenders


# --- the tests on this repository ------------------------------------------------------


def _message(what: str, offenders: list[str]) -> str:
    return f"{what}:\n  " + "\n  ".join(offenders)


def test_no_import_cycles():
    offenders = import_cycles(REPO)
    assert not offenders, _message("import cycles between modules of hairjax/", offenders)


def test_no_package_cycles():
    offenders = package_cycles(REPO)
    assert not offenders, _message("import cycles between packages of hairjax/", offenders)


def test_no_long_modules():
    offenders = long_modules(REPO)
    assert not offenders, _message(f"modules over {MAX_MODULE_LINES} lines", offenders)


def test_no_long_functions():
    offenders = long_functions(REPO)
    assert not offenders, _message(f"functions over {MAX_FUNCTION_LINES} lines", offenders)


def test_no_private_names_across_modules():
    offenders = private_imports(REPO)
    assert not offenders, _message("private names imported from another hairjax module", offenders)


def test_no_string_dispatch():
    names = {n for group in registered_names().values() for n in group}
    assert names, "found no registered model, shadow method or ordering names"
    offenders = string_dispatch(REPO, names)
    assert not offenders, _message("string dispatch on registered names, or old API names", offenders)


def test_experiments_numbered_and_indexed():
    offenders = experiment_index(REPO)
    assert not offenders, _message("experiments/ and its README disagree", offenders)


def test_experiments_and_notebooks_use_public_api():
    offenders = public_api(REPO)
    assert not offenders, _message("private hairjax API in experiments/ or notebooks/", offenders)


def test_no_issue_numbers():
    offenders = issue_numbers(REPO)
    assert not offenders, _message("issue numbers cited in hairjax/", offenders)


def test_tooling_wired():
    offenders = tooling(REPO)
    assert not offenders, _message("tooling not wired", offenders)


# --- the self-tests: each measure can fail ---------------------------------------------


def _write(root: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return root


def test_cycles_are_found(tmp_path):
    _write(
        tmp_path,
        {
            "hairjax/__init__.py": "",
            "hairjax/_a.py": "from ._b import f\n",
            "hairjax/_b.py": "def f():\n    from . import _a\n",  # lazy, still a cycle
            "hairjax/_c.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from ._d import X\n",
            "hairjax/_d.py": "from hairjax import _c\n",  # the TYPE_CHECKING edge back does not run
            # A package re-exporting its submodules, which take names back: allowed.
            "hairjax/sub/__init__.py": "from ._x import x as x\nfrom ._y import y as y\n",
            "hairjax/sub/_x.py": "x = 1\n",
            "hairjax/sub/_y.py": "from . import x\ny = x\n",
            # ... but not when its submodules have a cycle of their own.
            "hairjax/bad/__init__.py": "from ._u import u as u\n",
            "hairjax/bad/_u.py": "from ._v import v\nfrom . import w\nu = 1\n",
            "hairjax/bad/_v.py": "from ._u import u\nv = w = 1\n",
            # Another package's module taking from that __init__, which imports it: a cycle.
            "hairjax/pkg/__init__.py": "from ._p import p as p\n",
            "hairjax/pkg/_p.py": "from .._q import q\np = q\n",
            "hairjax/_q.py": "from .pkg import p\nq = 1\n",
        },
    )
    offenders = import_cycles(tmp_path)
    assert len(offenders) == 3, offenders
    assert any("'hairjax.bad._u', 'hairjax.bad._v'" in o for o in offenders), offenders
    assert "hairjax._a" in offenders[0] or "hairjax._a" in offenders[1]
    assert any("'hairjax._q'" in o and "'hairjax.pkg'" in o for o in offenders), offenders
    assert not any("hairjax.sub" in o or "hairjax._c" in o for o in offenders), offenders


def test_package_cycles_are_found(tmp_path):
    _write(
        tmp_path,
        {
            "hairjax/__init__.py": "",
            # _scene's values module is read by _stage, and _scene's file reader reads
            # _stage's options: no module cycle, but the two packages import each other.
            "hairjax/_scene/__init__.py": "",
            "hairjax/_scene/_values.py": "x = 1\n",
            "hairjax/_scene/_file.py": "from .._stage._options import o\n",
            "hairjax/_stage/__init__.py": "",
            "hairjax/_stage/_options.py": "o = 1\n",
            "hairjax/_stage/_run.py": "from .._scene._values import x\n",
            # One way only, through a top-level module: fine.
            "hairjax/_io/__init__.py": "from .._top import t\n",
            "hairjax/_top.py": "t = 1\n",
            # A type-only import back does not run: fine.
            "hairjax/_low/__init__.py": (
                "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .._io import t\n"
            ),
        },
    )
    assert import_cycles(tmp_path) == []  # every module cycle is absent ...
    offenders = package_cycles(tmp_path)  # ... yet the packages form one
    assert len(offenders) == 1, offenders
    assert "['hairjax._scene', 'hairjax._stage']" in offenders[0], offenders
    assert "hairjax._stage._run -> hairjax._scene._values" in offenders[0], offenders
    assert "hairjax._scene._file -> hairjax._stage._options" in offenders[0], offenders


def test_long_modules_are_found(tmp_path):
    _write(
        tmp_path,
        {"hairjax/__init__.py": "", "hairjax/_long.py": "x = 1\n" * 401, "hairjax/_ok.py": "x = 1\n" * 400},
    )
    assert long_modules(tmp_path) == ["hairjax/_long.py: 401 lines (limit 400)"]


def test_long_functions_are_found(tmp_path):
    body = "    x = 1\n"
    _write(
        tmp_path,
        {
            "hairjax/__init__.py": "",
            # 1 def line + 79 body lines: at the limit; the nested one makes the outer 82.
            "hairjax/_ok.py": "def ok():\n" + body * 79,
            "hairjax/_long.py": "def outer():\n" + body * 79 + "    def inner():\n        pass\n",
        },
    )
    assert long_functions(tmp_path) == ["hairjax/_long.py:1 outer: 82 lines (limit 80)"]


def test_private_imports_are_found(tmp_path):
    _write(
        tmp_path,
        {
            "hairjax/__init__.py": "from . import _x\nfrom ._x import public, __version__\n",
            "hairjax/_x.py": "from ._y import _private\n__version__ = public = 1\n",
            "hairjax/_y.py": "def f():\n    from hairjax._x import _lazy\n_private = 1\n",
            "hairjax/_z.py": "from __future__ import annotations\nfrom numpy import _core\n",
        },
    )
    offenders = private_imports(tmp_path)
    assert offenders == [
        "hairjax/_x.py:1: from hairjax._y import _private",
        "hairjax/_y.py:2: from hairjax._x import _lazy",
    ], offenders


def test_string_dispatch_is_found(tmp_path):
    _write(
        tmp_path,
        {
            "hairjax/__init__.py": "",
            "hairjax/_m.py": (
                "REGISTRY = {'kajiya-kay': 1}\n"
                "class KajiyaKay:\n    name = 'kajiya-kay'\n"
                "def f(model, method='exact'):\n"
                "    if model == 'kajiya-kay':\n        pass\n"
                "    if method in ('exact', 'other'):\n        pass\n"
                "    if model == 'something-else':\n        pass\n"
                "    match method:\n        case 'exact':\n            pass\n"
                "    return scene.shading_model\n"
            ),
        },
    )
    offenders = string_dispatch(tmp_path, {"kajiya-kay", "exact"})
    lines = [o.split(":")[1] for o in offenders]
    assert lines == ["5", "7", "12", "14"], offenders
    assert "old name shading_model" in offenders[-1]


def test_registered_names_are_found():
    names = registered_names()
    assert "kajiya-kay" in {n for group in names.values() for n in group}, names


def test_experiment_index_is_checked(tmp_path):
    _write(
        tmp_path,
        {
            "experiments/01_a.py": "",
            "experiments/02_b.py": "",
            "experiments/c.py": "",
            "experiments/02_d.py": "",
            "experiments/README.md": "`01_a.py`, `experiments/03_gone.py`, `c.py`, "
            "`02_d.py`, tests/test_experiments_04_x.py",
        },
    )
    assert sorted(experiment_index(tmp_path)) == sorted(
        [
            "experiments/c.py: not named NN_name.py",
            "experiments/: number 02 used by ['02_b.py', '02_d.py']",
            "experiments/README.md: does not name 02_b.py",
            "experiments/README.md: names 03_gone.py, which does not exist",
        ]
    )


def test_private_api_is_found(tmp_path):
    cells = [
        {"cell_type": "markdown", "source": ["import hairjax._fit\n"]},
        {
            "cell_type": "code",
            "source": [
                "%matplotlib inline\n",
                "import hairjax\n",
                "from hairjax._shading import KajiyaKay\n",
            ],
        },
        {"cell_type": "code", "source": "from hairjax.gl import GLRenderer\nhairjax.gl._x.y\n"},
        {"cell_type": "code", "source": "from hairjax import _fit, fit, __version__\n"},
    ]
    _write(
        tmp_path,
        {
            "experiments/01_a.py": (
                "import hairjax._io as io\nimport hairjax.tools\nfrom hairjax import render\n"
            ),
            "notebooks/01_n.ipynb": json.dumps({"cells": cells}),
        },
    )
    assert public_api(tmp_path) == [
        "experiments/01_a.py:1: import hairjax._io",
        "notebooks/01_n.ipynb cell 2 line 3: from hairjax._shading import …",
        "notebooks/01_n.ipynb cell 3 line 2: hairjax.gl._x",
        "notebooks/01_n.ipynb cell 4 line 1: from hairjax import _fit",
    ]


def test_issue_numbers_are_found(tmp_path):
    _write(
        tmp_path,
        {
            "hairjax/__init__.py": '"""See issue #12."""\n',
            "hairjax/gl/shaders/a.frag": "// fixes Issue 7\n",
            "hairjax/_ok.py": "# tissue 3, issues resolved\n",
            "hairjax/notes.md": "issue 9 (not a source file)\n",
        },
    )
    assert issue_numbers(tmp_path) == [
        "hairjax/__init__.py:1: 'issue #12'",
        "hairjax/gl/shaders/a.frag:1: 'Issue 7'",
    ]


WIRED_PYPROJECT = f"""
[project]
name = "x"
[project.optional-dependencies]
test = ["pytest>=8", "ruff>=0.5", "mypy>=1.10"]
[tool.pytest.ini_options]
addopts = "-ra {JAXTYPING_OPT}"
"""


def test_tooling_is_checked(tmp_path):
    wired = (
        "test: lint\n\t$(BIN)/python -m pytest -q\nlint:\n\t$(BIN)/ruff check .\n"
        "\t$(BIN)/ruff format --check .\n\t$(BIN)/mypy hairjax\n"
    )
    _write(tmp_path, {"Makefile": wired, "pyproject.toml": WIRED_PYPROJECT})
    assert tooling(tmp_path) == []
    unwired = "test: $(STAMP)\n\t$(BIN)/python -m pytest -q\n\truff check .\n"
    _write(tmp_path, {"Makefile": unwired, "pyproject.toml": '[project]\nname = "x"\n'})
    assert tooling(tmp_path) == [
        "Makefile: `make test` runs ruff check after pytest",
        "Makefile: `make test` does not run ruff format --check",
        "Makefile: `make test` does not run a type checker (mypy or basedpyright)",
        f"pyproject.toml: pytest addopts lack {JAXTYPING_OPT}",
        "pyproject.toml: the `test` extra does not list ruff",
        "pyproject.toml: the `test` extra lists no type checker (mypy or basedpyright)",
    ]


# --- the report ------------------------------------------------------------------------


def report(root: Path = REPO, verbose: bool = False) -> list[str]:
    """One line per metric: its value, its limit, ok or FAIL (offenders below with -v)."""
    lines_by_module = module_lines(root)
    longest = max(lines_by_module.items(), key=lambda kv: kv[1])
    names = {n for group in registered_names(root).values() for n in group}
    metrics = [
        ("import cycles", import_cycles(root), None),
        ("package cycles", package_cycles(root), None),
        (
            f"modules over {MAX_MODULE_LINES} lines",
            long_modules(root),
            f"longest {longest[0]} {longest[1]} lines, limit {MAX_MODULE_LINES}",
        ),
        (f"functions over {MAX_FUNCTION_LINES} lines", long_functions(root), None),
        ("private names across modules", private_imports(root), None),
        ("string dispatch / old names", string_dispatch(root, names), None),
        ("experiments not numbered/indexed", experiment_index(root), None),
        ("private API in experiments/notebooks", public_api(root), None),
        ("issue numbers in hairjax/", issue_numbers(root), None),
        ("tooling not wired (xfail while wiring)", tooling(root), None),
    ]
    out = [f"{'measure':<40} {'value':>5}  limit  status"]
    for what, offenders, note in metrics:
        status = "ok" if not offenders else "FAIL"
        out.append(f"{what:<40} {len(offenders):>5}  {0:>5}  {status}" + (f"  ({note})" if note else ""))
        if verbose:
            out += [f"    {o}" for o in offenders]
    return out


if __name__ == "__main__":
    print("\n".join(report(verbose="-v" in sys.argv[1:])))
