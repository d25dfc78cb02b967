"""Structural rules read from the AST (never grep): no import cycles between
the package's modules (imports inside functions included), and imports
inside functions stay rare (optional dependencies, import time)."""

from __future__ import annotations

import ast

from helpers.modules import PACKAGE, imported_modules, package_modules

#: the most imports inside functions, as a share of all imports
MAX_FUNCTION_LEVEL_SHARE = 0.10


def import_graph(sources: dict) -> dict:
    """``{module: {module it imports, ...}}`` over ``sources`` (module -> (source, is_package)),
    edges only between modules in ``sources``; ``from pkg import sub`` counts as ``pkg.sub``."""
    graph = {}
    for module, (source, is_package) in sources.items():
        names = imported_modules(ast.parse(source), module, is_package)
        edges = set()
        for name in names:
            if name in sources and name != module:
                edges.add(name)
        graph[module] = edges
    return graph


def find_cycles(graph: dict) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan), each sorted."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
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
    return sorted(out)


def _sources(packages: bool = True):
    """Every module of the package, the ``__init__`` modules included (``web`` and
    ``bench`` are whole modules; the lazy ones import little)."""
    return {m: (p.read_text(encoding="utf-8"), pkg) for p, m, pkg in package_modules() if packages or not pkg}


def test_the_cycle_finder_finds_a_cycle_through_a_function_level_import():
    sources = {
        "axialdeform.core.a": ("from .b import x\n", False),
        "axialdeform.core.b": ("def f():\n    from .c import y\n", False),
        "axialdeform.core.c": ("import axialdeform.core.a\n", False),
        "axialdeform.core.d": ("from . import a\n", False),
    }
    assert find_cycles(import_graph(sources)) == [["axialdeform.core.a", "axialdeform.core.b", "axialdeform.core.c"]]


def test_no_import_cycles():
    assert find_cycles(import_graph(_sources())) == []


def function_level_share(sources: dict) -> tuple[int, int]:
    """(imports inside a function, all imports) of the package's own modules."""
    inside = total = 0
    for source, _ in sources.values():
        tree = ast.parse(source)
        funcs = [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
        in_funcs = {id(n) for f in funcs for n in ast.walk(f) if isinstance(n, (ast.Import, ast.ImportFrom))}
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)) and not (
                    isinstance(node, ast.ImportFrom) and node.module == "__future__"):
                total += 1
                inside += id(node) in in_funcs
    return inside, total


def test_imports_inside_functions_are_rare():
    inside, total = function_level_share(_sources())
    assert total > 100 and PACKAGE.is_dir()
    assert inside / total < MAX_FUNCTION_LEVEL_SHARE, f"{inside} of {total} imports are inside functions"


def _public_signatures():
    """(where, name, parameter count) of every public function, method and constructor of the package;
    ``**fields`` (a value object's fields as keywords) is not counted."""
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in tree.body:
            funcs = [(node.name, node)] if isinstance(node, ast.FunctionDef) else []
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                funcs = [(f"{node.name}.{f.name}", f) for f in node.body if isinstance(f, ast.FunctionDef)
                         and (not f.name.startswith("_") or f.name == "__init__")]
            for name, f in funcs:
                if name.startswith("_"):
                    continue
                a = f.args
                names = [x.arg for x in (*a.posonlyargs, *a.args, *a.kwonlyargs)] + ([a.vararg.arg] if a.vararg else [])
                yield path.relative_to(PACKAGE.parent), name, len([n for n in names if n not in ("self", "cls")])


def test_no_public_function_takes_more_than_eight_parameters():
    """Option groups are values (Variation, Placement, RenderOptions, Look, PageOptions, ...), not long
    keyword lists."""
    long = [f"{where}: {name} ({n})" for where, name, n in _public_signatures() if n > 8]
    assert long == [], long
    assert any(n == 8 for *_, n in _public_signatures())  # the walk sees the signatures


def test_no_module_imports_another_modules_private_names():
    """A name another module needs is public in its home (in its ``__all__``), not reached for."""
    reached = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("axialdeform")):
                reached += [f"{path.relative_to(PACKAGE.parent)}: {node.module}.{a.name}" for a in node.names
                            if a.name.startswith("_") and not a.name.startswith("__")]
    assert reached == [], reached


def test_no_source_file_is_too_long_to_read():
    """At most 600 lines a module of the package, 400 a file of the npm module (js/src; the files build.mjs
    generates from glsl/ aside): a longer one holds more than one concern."""
    js = PACKAGE.parent / "js" / "src"
    written = [p for p in js.rglob("*.js") if not p.read_text(encoding="utf-8").startswith("// GENERATED by js/build.mjs")]
    assert len(written) < len(list(js.rglob("*.js"))) - 1  # webgl/glsl.js and webgpu/glsl_*nodes.js are the generated ones
    long = [f"{p.relative_to(PACKAGE.parent)}: {n}" for p, limit in
            [*((p, 600) for p in PACKAGE.rglob("*.py")), *((p, 400) for p in written)]
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > limit]
    assert long == [], long


def test_no_test_module_imports_another():
    """Helpers the tests share live in tests/conftest.py and tests/helpers/, never in a test module another
    imports (importing one runs its module-level set-up and ties the suites together)."""
    tests = PACKAGE.parent / "tests"
    modules = {p.stem for p in tests.rglob("test_*.py")}
    found = []
    for path in sorted(tests.rglob("*.py")):
        for name in imported_modules(ast.parse(path.read_text(encoding="utf-8")), path.stem, False):
            if name.split(".")[0] in modules:
                found.append(f"{path.relative_to(tests)} imports {name}")
    assert found == []
    # and the rule can fail: a test module's import is seen, inside a function too
    names = imported_modules(ast.parse("def f():\n    from test_three import make_site\n"), "x", False)
    assert "test_three" in {n.split(".")[0] for n in names}
