"""The analytic families as one record each: one key (``Family``), one registry, and no
family's name spelled outside its own module."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import pytest

import toolkit
from toolkit.ik import Family, registry
from toolkit.ik.analytic import family as family_module

PACKAGE = Path(toolkit.__file__).resolve().parent


def test_every_family_has_one_record_and_the_compiled_ones_keep_the_doors_order():
    assert set(registry.REGISTRY) == set(Family)
    assert all(key is record.key for key, record in registry.REGISTRY.items())
    compiled = tuple(k for k, r in registry.REGISTRY.items() if r.kernel is not None)
    assert compiled == family_module.COMPILED
    assert all((r.door is None) == (r.kernel is None) for r in registry.REGISTRY.values())
    assert [k.kernel_index for k in compiled] == list(range(len(compiled)))
    assert set(compiled) == set(Family)  # every family compiled (its Python form the oracle)


@pytest.mark.parametrize(
    ("robot", "family", "joints"),
    [("ur5", Family.THREE_PARALLEL, 6), ("kinova", Family.SPHERICAL_WRIST, 6)],
)
def test_a_structure_names_its_family_by_key_and_shows_its_name(robot, family, joints):
    found = toolkit.load_example(robot).structure
    assert found.family is family and family.joints == joints
    assert found.family == family.value  # a str: comparisons with the name hold
    assert f"{found.family}" == str(found.family) == family.value
    assert json.loads(json.dumps({"family": found.family})) == {"family": family.value}
    assert not found.places_point and found.compiled


def test_a_3_joint_family_places_a_point():
    points = {f for f in Family if f.places_point}
    assert points == {f for f in Family if f.joints == 3}
    assert Family.PPP in points and Family.THREE_PARALLEL not in points
    assert all(registry.REGISTRY[f].places_point for f in points)


def _name_literals(path: Path, names: set[str], root: Path = PACKAGE) -> list[str]:
    """String constants of ``path`` that are exactly a family's name (docstrings and
    messages that mention one are longer than the name)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Constant) and node.value in names:
            found.append(f"{path.relative_to(root)}:{node.lineno} {node.value!r}")
    return found


def test_no_family_name_is_spelled_outside_its_own_module():
    """The papers' models aside: [P3]'s structures are named by their joints' kinds
    ("PPP", "RPP"), a description of a model, not the IK family read from its axes."""
    names = {f.value for f in Family}
    own = Path(family_module.__file__).resolve()
    spelled = [hit for p in sorted(PACKAGE.rglob("*.py"))
               if p.resolve() != own and "papers" not in p.relative_to(PACKAGE).parts
               for hit in _name_literals(p, names)]  # fmt: skip
    assert not spelled, spelled
    assert len(_name_literals(own, names)) == len(Family)  # the test finds names


def test_the_name_test_finds_a_planted_name(tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text('if found.family == "spherical wrist":\n    pass\n', encoding="utf-8")
    hits = _name_literals(planted, {f.value for f in Family}, tmp_path)
    assert hits == ["planted.py:1 'spherical wrist'"]
