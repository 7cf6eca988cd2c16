"""The import graph of the mjtouch package: no cycles, no private names
crossing modules, and the deprecated alias modules stay leaves.

The graph is read from the source (ast), so imports inside functions count as
much as those at the top. Nodes are the package's Python modules (a package is
its ``__init__``); an arrow A -> B is an import statement in A naming B, or
naming a module inside package B while A is not inside B (importing
``mjtouch.x.y`` runs ``mjtouch/x/__init__`` first; a module's own packages are
already running when it runs, so those arrows are left out). The top package
``mjtouch`` is treated as every module's own package, so its re-exports
(``mjtouch.attach``) are not arrows back; importing it by name from inside the
package is (``from mjtouch import attach`` in a submodule is a cycle).

Deprecated aliases (``mjtouch/scenes.py`` re-exporting ``mjtouch.scene.scenes``,
...) are nodes like any other, and no module of the package may import one:
they only point into the real modules, so they cannot close a cycle.
"""

from __future__ import annotations

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2] / "mjtouch"
# compiled extension modules: leaves with no Python source
EXTENSIONS = {"mjtouch._core"}
ALIASES = {
    "mjtouch.scenes",
    "mjtouch.textures",
    "mjtouch.meshes",
    "mjtouch.sensor",
    "mjtouch.robot",
    "mjtouch.rollout",
    "mjtouch.stimuli",
    "mjtouch.tuning",
    "mjtouch.sweep",
    "mjtouch.figures",
    "mjtouch.testing",
    "mjtouch.oracles",
}


def modules(root: pathlib.Path = ROOT) -> dict[str, pathlib.Path]:
    out = {}
    for path in root.rglob("*.py"):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _ancestors(name: str) -> list[str]:
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def imports(mods: dict[str, pathlib.Path]):
    """Yield (importer, imported module, imported name or None, line) for every
    import of an mjtouch module."""
    for name, path in mods.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.name.split(".")[0] == "mjtouch":
                        yield name, a.name, None, node.lineno
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                if target.split(".")[0] != "mjtouch":
                    continue
                for a in node.names:
                    sub = f"{target}.{a.name}"
                    if sub in mods or sub in EXTENSIONS:
                        yield name, sub, None, node.lineno
                    else:
                        yield name, target, a.name, node.lineno


def graph(mods: dict[str, pathlib.Path]) -> dict[str, set[str]]:
    edges: dict[str, set[str]] = {m: set() for m in mods}
    for src, target, _, _ in imports(mods):
        if target in EXTENSIONS:
            continue
        own = set(_ancestors(src)) | {src}
        for t in [*_ancestors(target)[1:], target]:  # the top package is everyone's own
            if t not in own and t in mods:
                edges[src].add(t)
        if target == "mjtouch" and src != "mjtouch":
            edges[src].add("mjtouch")
    return edges


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan),
    each as one cycle through it."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(edges[v]):
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
            if len(comp) > 1 or v in edges[v]:
                found.append(_cycle_in(sorted(comp), edges))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def _cycle_in(comp: list[str], edges: dict[str, set[str]]) -> list[str]:
    """One cycle through comp[0] inside the component (breadth-first)."""
    inside, start = set(comp), comp[0]
    prev, frontier = {start: None}, [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(edges[v] & inside):
                if w == start:
                    path = [v]
                    while prev[path[-1]] is not None:
                        path.append(prev[path[-1]])
                    return [*reversed(path), start]
                if w not in prev:
                    prev[w] = v
                    nxt.append(w)
        frontier = nxt
    return comp


def test_no_import_cycle():
    found = cycles(graph(modules()))
    assert not found, "import cycles in mjtouch:\n" + "\n".join(" -> ".join(c) for c in found)


def test_cycle_detection_finds_a_planted_cycle(tmp_path):
    pkg = tmp_path / "mjtouch"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from mjtouch.sub import a\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "a.py").write_text("def f():\n    from mjtouch import b\n")
    (pkg / "b.py").write_text("from mjtouch.sub.a import f\nfrom mjtouch import _core\n")
    (pkg / "c.py").write_text("from mjtouch.sub import a\n")
    found = cycles(graph(modules(pkg)))
    assert found == [["mjtouch.b", "mjtouch.sub.a", "mjtouch.b"]]


def test_aliases_are_leaves():
    mods = modules()
    missing = ALIASES - set(mods)
    assert not missing, f"alias modules listed here but absent: {sorted(missing)}"
    bad = [
        f"{src} (line {line}) imports {t}"
        for src, t, _, line in imports(mods)
        if t in ALIASES and src not in ALIASES
    ]
    assert not bad, "modules importing a deprecated alias:\n" + "\n".join(bad)
    for alias in ALIASES:
        text = mods[alias].read_text()
        assert "Deprecated alias" in text, f"{alias}: docstring must say it is a deprecated alias"


def test_no_private_names_across_modules():
    mods = modules()
    bad = []
    for src, target, name, line in imports(mods):
        if name and name.startswith("_") and not name.startswith("__"):
            bad.append(f"{src}:{line} imports {target}.{name}")
    for src, path in mods.items():
        tree = ast.parse(path.read_text())
        aliases = {}
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("mjtouch"):
                for a in node.names:
                    if f"{node.module}.{a.name}" in mods:
                        aliases[a.asname or a.name] = f"{node.module}.{a.name}"
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name)
                and node.value.id in aliases
                and node.attr.startswith("_")
                and not node.attr.startswith("__")
            ):
                bad.append(f"{src}:{node.lineno} uses {aliases[node.value.id]}.{node.attr}")
    assert not bad, "private names used across modules:\n" + "\n".join(bad)


@pytest.mark.parametrize("alias", sorted(ALIASES))
def test_alias_reexports_the_public_names(alias):
    import importlib

    old = importlib.import_module(alias)
    new_name = next(line.split("`")[1] for line in old.__doc__.splitlines() if ":mod:" in line)
    new = importlib.import_module(new_name)
    public = getattr(new, "__all__", [n for n in vars(new) if not n.startswith("_")])
    assert public
    missing = [n for n in public if getattr(old, n, None) is not getattr(new, n)]
    assert not missing, f"{alias} lacks {missing} of {new_name}"
