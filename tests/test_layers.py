"""The package's layers: imports only point down the README's layout list.

Every ``import`` and ``from … import`` in ``exact_khk/`` is read from the source
(deferred imports inside functions too, which a run-time check would miss), and
its target's layer — the first folder under ``exact_khk/`` or the top-level
module — must not stand above the importing module's layer.  ``from exact_khk
import NAME`` is resolved through the package's table of public names, so the
lazy façade cannot hide an upward import.  Modules of one layer may import each
other.
"""

from __future__ import annotations

import ast
from pathlib import Path

import exact_khk

PACKAGE = Path(exact_khk.__file__).parent

#: bottom to top, as in the README's "Layout"
LAYERS = ("errors", "parsing", "arith", "linalg", "systems", "kahan", "certification", "studies", "diagnostics",
          "sweep", "testing", "cli", "__main__")


def layer_of(module: str) -> str:
    """``exact_khk.linalg.dense`` → ``linalg``; the package itself → ``exact_khk``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def imported_modules(source: str, module: str, is_package: bool):
    """``(line, target module)`` for every import of an exact_khk module in ``source``."""
    package = module.split(".") if is_package else module.split(".")[:-1]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = ".".join(package[:len(package) - node.level + 1] + [node.module or ""]).strip(".") \
                if node.level else node.module or ""
            if base == "exact_khk":  # the façade: each name's own module
                targets = [exact_khk._WHERE.get(a.name, "exact_khk") for a in node.names]
            else:
                targets = [base]
        else:
            continue
        for target in targets:
            if target == "exact_khk" or target.startswith("exact_khk."):
                yield node.lineno, target


def upward_imports(source: str, module: str, is_package: bool = False) -> list:
    """The imports in ``source`` (of ``module``) that point to a higher layer."""
    own = LAYERS.index(layer_of(module)) if layer_of(module) in LAYERS else len(LAYERS)
    out = []
    for line, target in imported_modules(source, module, is_package):
        name = layer_of(target)
        if name == "exact_khk":  # the package root: only its own data (__version__)
            continue
        assert name in LAYERS, f"{module}:{line} imports {target}, which is in no layer of LAYERS"
        if LAYERS.index(name) > own:
            out.append(f"{module}:{line} imports {target} ({layer_of(module)} → {name})")
    return out


def package_modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        is_package = parts[-1] == "__init__"
        yield ".".join(parts[:-1] if is_package else parts), path, is_package


def test_every_module_has_a_layer():
    names = {layer_of(m) for m, _, _ in package_modules()} - {"exact_khk"}
    assert names <= set(LAYERS), names - set(LAYERS)


def test_imports_only_point_down():
    found = []
    for module, path, is_package in package_modules():
        found += upward_imports(path.read_text(encoding="utf-8"), module, is_package)
    assert found == []


def test_nothing_imports_the_command_line():
    for module, path, is_package in package_modules():
        if layer_of(module) in ("cli", "__main__"):
            continue
        for line, target in imported_modules(path.read_text(encoding="utf-8"), module, is_package):
            assert layer_of(target) != "cli", f"{module}:{line} imports {target}"


def test_the_check_finds_upward_imports():
    """Negative controls: upward imports in every form the package uses are reported."""
    deferred = "def f():\n    from exact_khk.kahan.map import KahanMap\n    return KahanMap\n"
    assert upward_imports(deferred, "exact_khk.systems.lie_poisson.system") == [
        "exact_khk.systems.lie_poisson.system:2 imports exact_khk.kahan.map (systems → kahan)"]
    assert upward_imports("from ...linalg.dense import solve\n", "exact_khk.arith.ball.x") != []
    assert upward_imports("from ..linalg import dense\n", "exact_khk.arith.dual") != []
    assert upward_imports("import exact_khk.certification.records\n", "exact_khk.linalg.dense") != []
    assert upward_imports("from exact_khk import KahanMap\n", "exact_khk.systems.base") != []  # via the façade
    assert upward_imports("from exact_khk import __version__\n", "exact_khk.arith") == []
    # the same imports pointing down are fine
    assert upward_imports(deferred, "exact_khk.certification.engine") == []
    assert upward_imports("from ..arith import get_arith\n", "exact_khk.linalg.dense") == []


def import_graph(modules):
    """``{module: {imported module}}`` over ``modules`` (``(name, source, is_package)``), every
    import counted (deferred ones too); ``from pkg import sub`` names the submodule ``pkg.sub``.
    The package root is left out: its façade imports lazily what it re-exports, and a module
    imports from it only its own data (``__version__``)."""
    names = {m for m, _, _ in modules}

    def resolve(target):
        while target not in names and "." in target:
            target = target.rsplit(".", 1)[0]
        return target if target in names else None

    graph = {}
    for module, source, is_package in modules:
        package = module.split(".") if is_package else module.split(".")[:-1]
        edges = set()
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.ImportFrom):
                base = ".".join(package[:len(package) - node.level + 1] + [node.module or ""]).strip(".") \
                    if node.level else node.module or ""
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in names else base for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                continue
            edges |= {t for t in map(resolve, targets) if t and t != module and t != "exact_khk"}
        graph[module] = edges
    graph.pop("exact_khk", None)
    return graph


def import_circles(graph) -> list:
    """The import circles of ``graph``: its strongly connected components of more than one module."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_circles():
    """No module imports itself through others, deferred imports inside functions counted."""
    modules = [(m, p.read_text(encoding="utf-8"), pkg) for m, p, pkg in package_modules()]
    assert import_circles(import_graph(modules)) == []


def test_the_check_finds_import_circles():
    """Negative control: a circle through a deferred import and ``from pkg import sub`` is found."""
    modules = [("exact_khk.studies", "", True),
               ("exact_khk.studies.a", "def f():\n    from exact_khk.studies import b\n", False),
               ("exact_khk.studies.b", "from .a import f\n", False),
               ("exact_khk.studies.c", "from exact_khk.studies.a import f\n", False)]
    assert import_circles(import_graph(modules)) == [["exact_khk.studies.a", "exact_khk.studies.b"]]
    assert import_circles(import_graph(modules[:1] + modules[2:])) == []


def test_no_family_is_named_outside_its_folder():
    """A system declares what it knows and generic code asks: no test of a system's family
    (``kind == "lie-poisson"``, ``isinstance(..., LiePoissonSystem)``) outside ``systems/``.
    certification/verify.py is left out: the verifier is rewritten separately (issue 40, item 3)."""
    import re

    pattern = re.compile(r"""(kind\s*[!=]=\s*["']lie-poisson["'])|isinstance\([^)]*LiePoissonSystem""")
    assert pattern.search('if system.kind == "lie-poisson":') and pattern.search("isinstance(s, (LiePoissonSystem,))")
    found = [f"{module}:{source.count(chr(10), 0, m.start()) + 1}"
             for module, path, _ in package_modules() if layer_of(module) != "systems"
             and module != "exact_khk.certification.verify"
             for source in [path.read_text(encoding="utf-8")] for m in pattern.finditer(source)]
    assert found == []


#: what only the Lie–Poisson family knows (its fast steps and their table of rules live in its folder)
FAMILY = "exact_khk.systems.lie_poisson"


def family_imports(source: str, module: str, is_package: bool = False) -> list:
    """The imports of the family's modules in ``source`` (of ``module``)."""
    return [f"{module}:{line} imports {target}" for line, target in imported_modules(source, module, is_package)
            if target == FAMILY or target.startswith(FAMILY + ".")]


def test_linear_algebra_and_the_kahan_map_know_no_family():
    """linalg/ keeps rings and solvers and kahan/ asks the field for its fast steps
    (``field.structured_steps``): neither imports the family, deferred imports included."""
    found = [hit for module, path, is_package in package_modules() if layer_of(module) in ("linalg", "kahan")
             for hit in family_imports(path.read_text(encoding="utf-8"), module, is_package)]
    assert found == []
    # negative controls: a deferred import of the family's steps, and one through its package
    assert family_imports("def f():\n    from exact_khk.systems.lie_poisson import circulant\n",
                          "exact_khk.kahan.map") != []
    assert family_imports("from ..systems.lie_poisson.paths import SPLIT_N\n", "exact_khk.kahan.map") != []
    assert family_imports("from ..systems.quadratic import QuadraticField\n", "exact_khk.kahan.map") == []
