"""The package's architecture, read from its folders with ``ast`` (nothing is imported).

Each folder of ``toolkit/`` is a package named by its concept; its layer is its prefix:

* base: ``toolkit.errors``, ``toolkit._version``, ``toolkit.common``;
* core: ``toolkit.kinematics``, ``toolkit.ik`` (two rooms, numeric and analytic, over its
  shared checks), ``toolkit.collision``,
  ``toolkit.descriptions``, ``toolkit.robot``, ``toolkit.calibration``;
* papers: ``toolkit.papers``; maps: ``toolkit.maps``;
* apps: ``toolkit.cli``, ``toolkit.viz``, ``toolkit.report``; the facade: ``toolkit``.

Rules: a module imports nothing of a higher layer; no import cycle between packages,
annotation-only (``TYPE_CHECKING``) imports included, and none between modules; a module
imports another package only through that package's public names (what its ``__init__``
binds without an underscore); no module imports another's private names; modules stay
under ~400 lines and functions under 60 unless a ``# long:`` comment on the ``def`` line
says why.
"""

from __future__ import annotations

import ast
import functools
import re
import shutil
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "toolkit"
LAYERS = {
    "base": ("toolkit.errors", "toolkit._version", "toolkit.common"),
    "core": (
        "toolkit.kinematics",
        "toolkit.ik",
        "toolkit.collision",
        "toolkit.descriptions",
        "toolkit.robot",
        "toolkit.calibration",
        "toolkit.dynamics",
        "toolkit.motion",
        "toolkit.planning",
    ),
    "papers": ("toolkit.papers",),
    "maps": ("toolkit.maps",),
    "apps": ("toolkit.cli", "toolkit.viz", "toolkit.report"),
}
RANK = {"base": 0, "core": 1, "papers": 2, "maps": 3, "apps": 4, "facade": 5}
CORE_ORDER = {
    "toolkit.kinematics": 0,  # joint spaces, frames, the compiled back end
    "toolkit.descriptions": 0,  # URDF, xacro, SRDF and the catalogue
    "toolkit.collision": 1,  # shapes, scenes and the checker, on kinematics
    "toolkit.dynamics": 1,
    "toolkit.ik": 2,  # on kinematics (and a checker for collision-free answers)
    "toolkit.planning": 2,  # on arrays and a checker, below the robot
    "toolkit.robot": 3,  # the face that joins them
    "toolkit.calibration": 4,  # on a robot
    "toolkit.motion": 4,
}
"""The order inside the core: a package imports only packages of a lower rank (annotations
included), never one beside it or above it."""


@functools.cache
def _tree(source: str) -> ast.Module:
    """A module's tree, parsed once per text (many tests read the same modules)."""
    return ast.parse(source)


def _name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules(root: Path = PACKAGE) -> dict[str, Path]:
    return {_name(p, root): p for p in sorted(root.rglob("*.py"))}


def layer(module: str) -> str:
    if module == "toolkit":
        return "facade"
    for name, prefixes in LAYERS.items():
        if any(module == p or module.startswith(p + ".") for p in prefixes):
            return name
    return "unknown"


def package(module: str) -> str:
    """``toolkit.X`` of a module (a top-level module is its own package)."""
    return ".".join(module.split(".")[:2])


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def imports(module: str, mods: dict[str, Path], annotations: bool = False):
    """(imported toolkit module, names taken from it) of every import of ``module``;
    ``annotations`` includes those under ``if TYPE_CHECKING:``."""
    path = mods[module]
    base = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    out: list[tuple[str, list[str]]] = []

    def visit(node: ast.AST) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child) and not annotations:
                continue
            if isinstance(child, ast.Import):
                out.extend((a.name, []) for a in child.names if a.name.startswith("toolkit"))
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    parts = base.split(".")[: len(base.split(".")) - child.level + 1]
                    target = ".".join(parts + ([child.module] if child.module else []))
                else:
                    target = child.module or ""
                if target.startswith("toolkit"):
                    names = [a.name for a in child.names]
                    subs = [n for n in names if f"{target}.{n}" in mods]  # modules by name
                    out.extend((f"{target}.{n}", []) for n in subs)
                    rest = [n for n in names if n not in subs]
                    if rest or not subs:
                        out.append((target, rest))
            visit(child)

    visit(_tree(path.read_text(encoding="utf-8")))
    return out


def public_names(pkg: str, mods: dict[str, Path]) -> set[str]:
    """What a package's ``__init__`` offers: every name it binds without a leading
    underscore (its ``__all__``, what users import, and the API between packages it
    re-exports by ``import x as x``), and the names its ``__all__`` lists (a name it
    binds on first use, as ``toolkit.cli.warmup``)."""
    names: set[str] = set()
    for node in _tree(mods[pkg].read_text(encoding="utf-8")).body:
        if isinstance(node, ast.Import | ast.ImportFrom):
            names.update((a.asname or a.name).split(".")[0] for a in node.names)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
            if any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
                listed = node.value.elts if isinstance(node.value, ast.List) else []
                names.update(e.value for e in listed if isinstance(e, ast.Constant))
        elif isinstance(node, ast.FunctionDef | ast.ClassDef):
            names.add(node.name)
    return {n for n in names if not n.startswith("_")}


def _is_package(name: str, mods: dict[str, Path]) -> bool:
    return name in mods and mods[name].name == "__init__.py"


def layering_violations(mods: dict[str, Path]) -> list[str]:
    bad = []
    for module in mods:
        for target, _ in imports(module, mods, annotations=True):
            if RANK.get(layer(target), 9) > RANK.get(layer(module), -1):
                bad.append(f"{module} ({layer(module)}) imports {target} ({layer(target)})")
    return bad


def core_order_violations(mods: dict[str, Path]) -> list[str]:
    """Imports inside the core that run sideways or up :data:`CORE_ORDER`."""
    bad = []
    for module in mods:
        mine = CORE_ORDER.get(package(module))
        if mine is None:
            continue
        for target, _ in imports(module, mods, annotations=True):
            theirs = CORE_ORDER.get(package(target))
            if theirs is not None and package(target) != package(module) and theirs >= mine:
                bad.append(f"{module} (core rank {mine}) imports {target} (rank {theirs})")
    return bad


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    path: list[str] = []

    def walk(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                return [*path[path.index(nxt) :], nxt]
            if nxt not in state:
                found = walk(nxt)
                if found:
                    return found
        path.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state:
            found = walk(node)
            if found:
                return found
    return None


def package_cycle(mods: dict[str, Path]) -> list[str] | None:
    """A cycle between packages, annotation-only imports included (the facade aside: it
    imports every package by design and none imports it)."""
    graph: dict[str, set[str]] = {}
    for module in mods:
        mine = package(module)
        for target, _ in imports(module, mods, annotations=True):
            theirs = package(target)
            if theirs != mine and mine != "toolkit" and theirs != "toolkit":
                graph.setdefault(mine, set()).add(theirs)
    return _cycle(graph)


def module_cycle(mods: dict[str, Path]) -> list[str] | None:
    """A cycle between modules through run-time imports (function-level ones included)."""
    graph: dict[str, set[str]] = {}
    for module in mods:
        targets = {t for t, _ in imports(module, mods) if t in mods and t != module}
        graph.setdefault(module, set()).update(targets)
    return _cycle(graph)


def private_reaches(mods: dict[str, Path]) -> list[str]:
    """Imports of another package's non-public names (anything its ``__init__`` does not bind)."""
    bad = []
    for module in mods:
        for target, names in imports(module, mods, annotations=True):
            pkg = package(target)
            if pkg == package(module) or pkg == "toolkit" or not _is_package(pkg, mods):
                continue  # inside one package, the facade, and the top-level modules
            face = pkg
            if target != pkg:  # a public module itself, or a public subpackage's names
                parent, _, last = target.rpartition(".")
                if last in public_names(parent, mods) and not names:
                    continue
                if not (_is_package(target, mods) and last in public_names(parent, mods)):
                    bad.append(f"{module} reaches into {target}")
                    continue
                face = target
            hidden = sorted(set(names) - public_names(face, mods))
            if hidden:
                bad.append(f"{module} takes {hidden} from {face}, not among its public names")
    return bad


MODULES = modules()


def test_every_module_has_a_layer():
    unknown = [m for m in MODULES if layer(m) == "unknown"]
    assert not unknown, f"modules outside the layers' folders: {unknown}"


def test_the_top_folder_holds_the_facade_and_little_else():
    top = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert top == ["__init__.py", "_version.py", "errors.py"], top
    for folder in (p for p in PACKAGE.iterdir() if p.is_dir() and p.name != "__pycache__"):
        files = list(folder.glob("*.py"))
        if files:  # a package of one file is a module in disguise
            assert len(files) > 2 or (folder / "__main__.py").exists(), folder


def test_every_import_of_the_toolkit_names_a_module_of_it():
    """A relative import one dot short (``from .papers import ...`` in a subpackage) would
    only fail when its function runs."""
    missing = sorted(
        f"{module} imports {target}"
        for module in MODULES
        for target, _ in imports(module, MODULES, annotations=True)
        if target not in MODULES
    )
    assert not missing, missing


def test_layering():
    assert not layering_violations(MODULES)


def test_the_core_keeps_its_order():
    assert set(CORE_ORDER) == set(LAYERS["core"])
    assert not core_order_violations(MODULES)


def test_no_import_cycle_between_packages_annotations_included():
    assert package_cycle(MODULES) is None, " -> ".join(package_cycle(MODULES) or [])


def test_no_import_cycle_between_modules():
    assert module_cycle(MODULES) is None, " -> ".join(module_cycle(MODULES) or [])


def test_packages_are_used_through_their_public_names():
    assert not private_reaches(MODULES)


@pytest.mark.parametrize("module", sorted(MODULES))
def test_no_private_names_from_other_modules(module):
    for target, names in imports(module, MODULES, annotations=True):
        if target == module:
            continue
        private = [n for n in names if n.startswith("_") and n != "__version__"]
        assert not private, f"{module} imports private {private} from {target}"


@pytest.fixture
def planted(tmp_path):
    """A copy of the package to break on purpose."""
    copy = tmp_path / "toolkit"
    shutil.copytree(PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__", "*.json"))
    return copy


def _plant(root: Path, file: str, line: str) -> dict[str, Path]:
    path = root / file
    path.write_text(path.read_text(encoding="utf-8") + "\n" + line + "\n", encoding="utf-8")
    return modules(root)


def test_the_test_finds_a_planted_annotation_cycle(planted):
    assert package_cycle(modules(planted)) is None
    mods = _plant(
        planted,
        "kinematics/joints.py",
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from ..robot import Robot",
    )
    cycle = package_cycle(mods)
    assert cycle is not None and "toolkit.kinematics" in cycle and "toolkit.robot" in cycle


def test_the_test_finds_a_core_module_importing_an_app(planted):
    mods = _plant(planted, "ik/numeric/options.py", "from ...cli import main")
    assert any(
        "toolkit.ik.numeric.options" in v and "toolkit.cli" in v for v in layering_violations(mods)
    )


def test_the_test_finds_the_core_out_of_order(planted):
    """Planning importing the robot (up), and ik importing planning (beside it)."""
    assert not core_order_violations(modules(planted))
    mods = _plant(planted, "planning/edges.py", "def f():\n    from ..robot import Robot")
    assert any("toolkit.planning.edges (core rank 2) imports toolkit.robot" in v
               for v in core_order_violations(mods))  # fmt: skip
    mods = _plant(planted, "ik/targets.py", "from ..planning import RESOLUTION")
    assert any("toolkit.ik.targets" in v for v in core_order_violations(mods))


def test_the_test_finds_a_reach_into_another_package(planted):
    mods = _plant(planted, "ik/targets.py", "from ..common.compiler import _decorate")
    assert any("reaches into toolkit.common.compiler" in v for v in private_reaches(mods))
    mods = _plant(planted, "ik/targets.py", "from ..kinematics import _LOCAL")
    assert any("'_LOCAL'" in v for v in private_reaches(mods))


def test_the_test_finds_a_module_cycle(planted):
    mods = _plant(planted, "ik/checks.py", "def f():\n    from .numeric.solver import verify")
    assert module_cycle(mods) is not None


def robot_privates(mods: dict[str, Path]) -> list[str]:
    """Private members of a robot (``robot._x``, ``self.robot._x``) used outside
    ``toolkit.robot``: other packages use what ``Robot`` offers."""
    bad = []
    for module, path in mods.items():
        if module.startswith("toolkit.robot"):
            continue
        for node in ast.walk(_tree(path.read_text(encoding="utf-8"))):
            if not (isinstance(node, ast.Attribute) and node.attr.startswith("_")):
                continue
            base = ast.unparse(node.value)
            if not node.attr.startswith("__") and (base == "robot" or base.endswith(".robot")):
                bad.append(f"{module}:{node.lineno} {base}.{node.attr}")
    return bad


def test_other_packages_use_no_private_member_of_a_robot():
    assert not robot_privates(MODULES)


def test_the_test_finds_a_private_member_of_a_robot(planted):
    mods = _plant(planted, "maps/compute.py", "def f(robot):\n    return robot._door(0)")
    assert any("robot._door" in v for v in robot_privates(mods))


ROOMS = ("toolkit.ik.numeric", "toolkit.ik.analytic")
"""The two rooms of the IK: the numeric solver and the analytic one. Neither imports the
other; the shared modules of ``toolkit.ik`` (its checks, its targets) import neither; the
solvers a robot holds (``toolkit.ik.solvers``) stand over both and may import both, and
nothing below them imports them; the ``toolkit.ik`` face hands all on."""
SOLVERS = "toolkit.ik.solvers"


def room(module: str) -> str | None:
    if module == SOLVERS or module.startswith(SOLVERS + "."):
        return SOLVERS
    return next((r for r in ROOMS if module == r or module.startswith(r + ".")), None)


def room_crossings(mods: dict[str, Path]) -> list[str]:
    """Imports from one IK room into the other, or from a shared IK module into a room."""
    bad = []
    for module in mods:
        if not module.startswith("toolkit.ik."):
            continue  # the face of toolkit.ik, and the other packages
        mine = room(module)
        for target, _ in imports(module, mods, annotations=True):
            theirs = room(target)
            if theirs is not None and theirs != mine and mine != SOLVERS:
                bad.append(f"{module} ({mine or 'shared'}) imports {target} ({theirs})")
    return bad


def test_the_ik_rooms_import_only_the_shared_checks():
    assert {room(m) for m in MODULES} >= {*ROOMS, SOLVERS}
    assert not room_crossings(MODULES)


def test_the_test_finds_a_room_crossing(planted):
    assert not room_crossings(modules(planted))
    mods = _plant(planted, "ik/numeric/solver.py", "from ..analytic import door")
    assert any("toolkit.ik.numeric.solver" in v for v in room_crossings(mods))
    mods = _plant(planted, "ik/checks.py", "from .analytic.branches import turns")
    assert any("toolkit.ik.checks (shared)" in v for v in room_crossings(mods))
    mods = _plant(planted, "ik/analytic/door.py", "from ..solvers import AnalyticIK")
    assert any("toolkit.ik.analytic.door" in v for v in room_crossings(mods))


@pytest.mark.parametrize("module", sorted(MODULES))
def test_sizes(module):
    source = MODULES[module].read_text(encoding="utf-8")
    lines = source.splitlines()
    assert len(lines) <= 420, f"{module} has {len(lines)} lines"
    for node in ast.walk(_tree(source)):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            length = (node.end_lineno or node.lineno) - node.lineno + 1
            reason = "# long:" in lines[node.lineno - 1]
            assert length <= 60 or reason, f"{module}.{node.name} has {length} lines"


@pytest.mark.parametrize("module", sorted(m for m in MODULES if layer(m) in ("base", "core")))
def test_the_core_cites_no_paper(module):
    """The core knows no paper: [P1]..[P4] (their equations, their models) live in
    toolkit.papers; a core module citing one is paper code in the wrong layer."""
    source = MODULES[module].read_text(encoding="utf-8")
    cited = sorted(set(re.findall(r"\[P[1-4]\]", source)))
    assert not cited, f"{module} cites {cited}"


def test_the_short_paper_names_have_stubs_for_type_checkers():
    """``toolkit.backlash`` is ``toolkit.papers.backlash`` at run time (a sys.modules
    alias); a stub beside each short name gives type checkers its real types, not Any."""
    import sys

    import toolkit

    for name in ("arm5dof", "backlash", "bending", "katana", "structures"):
        getattr(toolkit, name)  # the package loads on first use
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


@pytest.mark.slow
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


RECORDS = ("packed", "space", "work", "trees")
"""The kernels' records (:class:`toolkit.collision.Packed`, and
:mod:`toolkit.planning.records`' ``Space``, ``Work``, ``Trees``): named tuples, read by
position only inside the kernels."""


def test_no_kernel_record_is_read_by_position_outside_the_kernels():
    """Outside a kernel module, ``space[2]`` or ``test.packed[5]`` is refused: a record's
    fields are read by name (``space.packed``, ``test.packed.first``)."""
    found = []
    for name, path in MODULES.items():
        if name.split(".")[-1].endswith("kernels"):
            continue
        for node in ast.walk(_tree(path.read_text(encoding="utf-8"))):
            if not (isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant)
                    and isinstance(node.slice.value, int)):  # fmt: skip
                continue
            base = node.value
            label = base.id if isinstance(base, ast.Name) else getattr(base, "attr", "")
            if label in RECORDS:
                found.append(f"{name}:{node.lineno} {label}[{node.slice.value}]")
    assert not found, found
