"""The package's layering, read from its source with ``ast`` (nothing is imported).

* the core (robot, IK, chain, rendering, catalogue, loaders, errors, checks) imports
  neither the papers nor the apps; the papers do not import the apps;
* no module imports another's private names (private modules such as ``_validate`` and
  ``papers._planar`` are shared on purpose and may be imported);
* no import cycle between the toolkit's modules, function-level imports included;
* modules stay under ~400 lines and functions under 60, unless a ``# long:`` comment on
  the ``def`` line says why.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "toolkit"
CORE = {
    "toolkit._shared",
    "toolkit._task",
    "toolkit._check_kernels",
    "toolkit._validate",
    "toolkit._version",
    "toolkit._ik_kernels",
    "toolkit._kernels",
    "toolkit._numba",
    "toolkit.batch",
    "toolkit.cache",
    "toolkit.catalogue",
    "toolkit.collision",
    "toolkit._collide",
    "toolkit._scene",
    "toolkit._bounds",
    "toolkit._bound_states",
    "toolkit._bound_kernels",
    "toolkit.calibration",
    "toolkit.calibration._model",
    "toolkit.calibration._measure",
    "toolkit.calibration._jacobian",
    "toolkit.calibration._identify",
    "toolkit.calibration._urdf",
    "toolkit.calibration._arm",
    "toolkit.calibration._select",
    "toolkit.calibration._xacro",
    "toolkit.descriptions",
    "toolkit.engine",
    "toolkit.errors",
    "toolkit.ik",
    "toolkit.joints",
    "toolkit.loaders",
    "toolkit.options",
    "toolkit.render",
    "toolkit.robot",
    "toolkit.visuals",
}
APPS = {
    "toolkit.cli",
    "toolkit.viz",
    "toolkit._meshcat_server",
    "toolkit._apidoc",
    "toolkit._warmup",
    "toolkit._cli_input",
    "toolkit._cli_calibrate",
}


def _name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES = {_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _layer(module: str) -> str:
    if module in CORE:
        return "core"
    if module.startswith("toolkit.papers"):
        return "papers"
    if module.startswith("toolkit.maps"):
        return "maps"
    if module in APPS or module.startswith("toolkit.report"):
        return "apps"
    return "facade" if module == "toolkit" else "unknown"


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(module: str) -> list[tuple[str, list[str]]]:
    """(imported toolkit module, names taken from it) for every runtime import."""
    path = MODULES[module]
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    out: list[tuple[str, list[str]]] = []

    def visit(node: ast.AST) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child):
                continue
            if isinstance(child, ast.Import):
                out.extend((a.name, []) for a in child.names if a.name.startswith("toolkit"))
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = package.split(".")[: len(package.split(".")) - child.level + 1]
                    target = ".".join(base + ([child.module] if child.module else []))
                else:
                    target = child.module or ""
                if target.startswith("toolkit"):
                    names = [a.name for a in child.names]
                    subs = [n for n in names if f"{target}.{n}" in MODULES]
                    out.extend((f"{target}.{n}", []) for n in subs)
                    rest = [n for n in names if n not in subs]
                    if rest or not subs:
                        out.append((target, rest))
            visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8")))
    return out


def test_every_module_has_a_layer():
    unknown = [m for m in MODULES if _layer(m) == "unknown"]
    assert not unknown, f"modules outside core/papers/apps: {unknown}"


@pytest.mark.parametrize("module", sorted(MODULES))
def test_layering(module):
    mine = _layer(module)
    for target, _ in _imports(module):
        theirs = _layer(target)
        if mine == "core":
            assert theirs not in ("papers", "maps", "apps", "facade"), f"{module} imports {target}"
        if mine == "papers":
            assert theirs not in ("maps", "apps", "facade"), f"{module} imports {target}"
        if mine == "maps":  # maps build on the core and the papers (backlash)
            assert theirs not in ("apps", "facade"), f"{module} imports {target}"


@pytest.mark.parametrize("module", sorted(MODULES))
def test_no_private_names_from_other_modules(module):
    for target, names in _imports(module):
        if target == module:
            continue
        private = [n for n in names if n.startswith("_") and n != "__version__"]
        assert not private, f"{module} imports private {private} from {target}"


def test_no_import_cycle():
    graph = {m: {t for t, _ in _imports(m) if t in MODULES and t != m} for m in MODULES}
    state: dict[str, int] = {}
    path: list[str] = []

    def walk(node: str) -> None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                cycle = [*path[path.index(nxt) :], nxt]
                raise AssertionError("import cycle: " + " -> ".join(cycle))
            if nxt not in state:
                walk(nxt)
        path.pop()
        state[node] = 2

    for module in sorted(graph):
        if module not in state:
            walk(module)


@pytest.mark.parametrize("module", sorted(MODULES))
def test_sizes(module):
    source = MODULES[module].read_text(encoding="utf-8")
    lines = source.splitlines()
    assert len(lines) <= 420, f"{module} has {len(lines)} lines"
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            length = (node.end_lineno or node.lineno) - node.lineno + 1
            reason = "# long:" in lines[node.lineno - 1]
            assert length <= 60 or reason, f"{module}.{node.name} has {length} lines"


@pytest.mark.parametrize("module", sorted(m for m in MODULES if _layer(m) == "core"))
def test_the_core_cites_no_paper(module):
    """The core knows no paper: [P1]..[P4] (their equations, their models) live in
    toolkit.papers; a core module citing one is paper code in the wrong layer."""
    import re

    source = MODULES[module].read_text(encoding="utf-8")
    cited = sorted(set(re.findall(r"\[P[1-4]\]", source)))
    assert not cited, f"{module} cites {cited}"


def test_the_short_paper_names_have_stubs_for_type_checkers():
    """``toolkit.backlash`` is ``toolkit.papers.backlash`` at run time (a sys.modules
    alias); a stub beside each short name gives type checkers its real types, not Any."""
    import sys

    import toolkit

    aliases = sorted(
        name[len("toolkit.") :]
        for name, module in sys.modules.items()
        if name.startswith("toolkit.")
        and name.count(".") == 1
        and getattr(module, "__name__", "").startswith("toolkit.papers.")
    )
    assert {"arm5dof", "backlash", "bending", "katana", "structures"} <= set(aliases)
    for name in aliases:
        stub = PACKAGE / f"{name}.pyi"
        assert stub.is_file(), f"toolkit.{name} has no stub"
        assert f"from .papers.{name} import *" in stub.read_text()
        assert getattr(toolkit, name) is sys.modules[f"toolkit.papers.{name}"]


def test_mypy_sees_the_short_names_typed(tmp_path):
    api = pytest.importorskip("mypy.api")
    probe = tmp_path / "probe.py"
    probe.write_text(
        "from toolkit.backlash import Backlash\n"
        "from toolkit.katana import closed_form_fk\n"
        "reveal_type(Backlash)\nreveal_type(closed_form_fk)\n"
    )
    out, err, status = api.run([str(probe), "--no-incremental", "--follow-imports=silent"])
    assert status == 0, out + err
    revealed = [line for line in out.splitlines() if "Revealed type" in line]
    assert len(revealed) == 2 and not any('"Any"' in line for line in revealed), out
