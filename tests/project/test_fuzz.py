"""Every public callable, called with bad values: a ToolkitError or a valid result, nothing else.

The public API is enumerated from the modules' ``__all__`` (functions, classes and the
public methods of their instances), so a newly added public function is fuzzed without
editing this file. For each parameter in turn, hypothesis draws a value no parameter of
the toolkit accepts (NaN and infinities, ``object()``, complex numbers, a 10**400 integer,
ragged and wrongly shaped arrays, ``None`` where None is not the default, booleans where
no flag is meant, text where no name is meant) while the other required parameters get a
valid example from :data:`EXAMPLES` (by parameter name). Allowed outcomes: a
``toolkit.ToolkitError`` subclass. A raw exception fails the test (the traceback names the
callable); so does a call that returns normally (a silent acceptance).

Not fuzzed, with the reason: result and record types (named tuples, dataclasses without
a validating ``__post_init__``: they hold data, they do not take input), the viewer
(needs a browser session; ``tests/viz/test_viz.py`` checks its inputs) and the report
sections (no input). The CLI is fuzzed at the end through ``toolkit.cli.main``.
"""

from __future__ import annotations

import dataclasses
import enum
import importlib
import inspect
import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import toolkit
import toolkit.viz.visuals
from toolkit.cli import main

MODULES = [
    "toolkit",
    "toolkit.robot",
    "toolkit.kinematics.joints",
    "toolkit.ik",
    "toolkit.robot.loading",
    "toolkit.descriptions.render",
    "toolkit.common.cache",
    "toolkit.descriptions.catalogue",
    "toolkit.katana",
    "toolkit.arm5dof",
    "toolkit.backlash",
    "toolkit.structures",
    "toolkit.bending",
    "toolkit.maps",
    "toolkit.viz.visuals",
    "toolkit.motion",
    "toolkit.dynamics",
    "toolkit.collision",
]

_KATANA = toolkit.load("katana_6m180")
_SCARA = toolkit.load("scara")
_LAYER = toolkit.backlash.Backlash(_KATANA, payload=0.5)
_Q = np.array([0.1, 0.5, -0.4, -0.8, 0.2])
_MAP = toolkit.maps.reachability(_SCARA, voxel=0.2, position_only=True, workers=1)
_T = _KATANA.fk(_Q)
_MOTION_DATA = toolkit.backlash.along(
    _LAYER, toolkit.motion.quintic(_KATANA, [_Q, _Q + 0.1], [0.0, 0.2]), 50.0
)

# valid examples by parameter name (a callable gets the owner's module name)
EXAMPLES: dict[str, Any] = {
    "name": lambda m: "scara" if "structures" in m else "katana_6m180",
    "robot": lambda m: _SCARA if "structures" in m else _KATANA,
    "model": _KATANA.model,
    "tip_frame": _KATANA.frames.id(None),
    "layer": _LAYER,
    "q": lambda m: np.zeros(3) if "structures" in m else _Q,
    "start": _Q,
    "q_cmd": _Q,
    "theta": _Q,
    "values": np.zeros(5),
    "group": lambda m: list(_KATANA.joints.names[:3]),
    "v": np.zeros(5),
    "qd": np.zeros(5),
    "qdd": np.zeros(5),
    "frame": "tool",
    "plane": "xz",
    "voxel": 0.4,
    "orientations": 2,
    "payloads": (0.5,),
    "workers": 1,
    "chunk": 8,
    "result": lambda m: _MAP,
    "viewer": None,  # a real viewer is tested in test_viz; None must be refused clearly
    "statistic": "p95",
    "low": [0.0, 0.0, 0.0],
    "high": [1.0, 1.0, 1.0],
    "half_angle": 0.5,
    "visuals": lambda m: toolkit.viz.visual_model(_KATANA),
    "heights": [0.1],
    "level": 0.1,
    "target": lambda m: (
        np.array([0.3, 0.3, 0.6])
        if "structures" in m
        else np.array([0.005, 0.0, -0.05])
        if "bending" in m
        else _T
    ),
    "targets": [_T],
    "tasks": np.array([[0.3, 0.0, 0.3]]),
    "region": [[0.0, 0.0], [0.001, 0.001]],  # one candidate base: quick
    "base": [0.0, 0.0, 0.0, 0.0],
    "scene": None,
    "path": lambda m: np.zeros((5, 3)) if "structures" in m else "/nonexistent.urdf",
    "template": "scara.urdf.xacro",
    "source": str(toolkit.urdf_path("scara")),
    "mask": [1, 1, 1, 1, 1, 0],
    "position": (40.0, 10.0, 30.0),
    "pitch": 0.2,
    "positions": np.array([[40.0, 10.0, 30.0]]),
    "pitches": np.array([0.2]),
    "base_offset": 3.0,
    "upper_arm": 50.0,
    "forearm": 25.0,
    "gripper": 5.0,
    "alpha": 0.1,
    "psi": 0.3,
    "phi": 0.2,
    "a": 0.1,
    "b": 0.3,
    "c": 0.2,
    "d": lambda m: 0.016 if "bending" in m else 0.1,
    "R": 0.02,
    "h0": 0.008,
    "n": 5,
    "alphas": [0.1, 0.2],
    "psis": [0.3, 0.4],
    "cables": {"XP": 0.001},
    "f": np.zeros((5, 3)),
    "t": np.linspace(0.0, 1.0, 5),
    "q0": np.zeros(3),
    "xyz": [0.0, 0.1, 0.2],
    "rpy": [0.1, 0.2, 0.3],
    "r": 0.1,
    "p": 0.2,
    "y": 0.3,
    "torque": [1.0],
    "torques": [[1.0]],
    "nominal_torque": [2.0],
    "delta": 0.03,
    "k_h": 0.2,
    "commands": _KATANA.random_q(4, seed=1),
    "frame_id": 0,
    "position_only": False,
    "spec": None,  # register() is fuzzed on its one argument only
    "trajectory": toolkit.motion.quintic(_KATANA, [_Q, _Q + 0.1], [0.0, 0.2]),
    "durations": [0.2],
    "data": lambda m: _MOTION_DATA,
    "waypoints": np.array([_Q, _Q + 0.1]),
    "times": None,
    "acceleration": 2.0,
    "jerk": 20.0,
    "velocity": None,
    "dt": 0.01,
    "max_cycles": 5,
    "payload": None,
    "duration": 0.5,
    "goal": None,
    "start_pose": _T,
    "goal_pose": _T,
    "resolution": 0.02,
    "per_shape": 2,
    "tau": np.zeros(5),
}


def _example(param: str, module: str) -> Any:
    if param not in EXAMPLES:
        raise AssertionError(f"add a valid example for parameter {param!r} to EXAMPLES")
    value = EXAMPLES[param]
    return value(module) if callable(value) and not isinstance(value, type) else value


def _is_record(cls: type) -> bool:
    """Records and keys: named tuples, dataclasses without checks, enums (a key's
    constructor is Python's lookup by value), and protocols (a shape, no behaviour: their
    implementations are fuzzed where they are exported)."""
    if (issubclass(cls, tuple) and hasattr(cls, "_fields")) or issubclass(cls, enum.Enum):
        return True
    if getattr(cls, "_is_protocol", False):
        return True
    return dataclasses.is_dataclass(cls) and "__post_init__" not in vars(cls)


def _instance(cls: type, module: str) -> Any:
    """An instance whose methods are fuzzed."""
    if cls is toolkit.Robot:
        return _KATANA
    if cls is toolkit.backlash.Backlash:
        return _LAYER
    sig = inspect.signature(cls)
    kwargs = {
        p.name: _example(p.name, module)
        for p in sig.parameters.values()
        if p.default is p.empty and p.kind is not p.VAR_KEYWORD
    }
    return cls(**kwargs)


def _callables() -> list[tuple[str, str, Callable[..., Any]]]:
    out: list[tuple[str, str, Callable[..., Any]]] = []
    seen: set[int] = set()
    for module in MODULES:
        mod = importlib.import_module(module)
        for attr in getattr(mod, "__all__", []):
            obj = getattr(mod, attr)
            if inspect.ismodule(obj) or id(obj) in seen or not callable(obj):
                continue
            seen.add(id(obj))
            if inspect.isclass(obj):
                if issubclass(obj, BaseException) or _is_record(obj):
                    continue
                out.append((f"{module}.{attr}", module, obj))
                owners = [k for k in obj.__mro__ if k.__module__.startswith("toolkit")]
                methods = {
                    m: 0 for k in owners for m, v in vars(k).items() if inspect.isfunction(v)
                }
                for meth in methods:
                    if not meth.startswith("_"):
                        out.append((f"{module}.{attr}.{meth}", module, getattr(obj, meth)))
            else:
                out.append((f"{module}.{attr}", module, obj))
    return out


def _cases() -> list[tuple[str, str, Callable[..., Any], str]]:
    cases = []
    for label, module, func in _callables():
        params = [
            p
            for p in inspect.signature(func).parameters.values()
            if p.name != "self" and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
        ]
        cases += [(label, module, func, p.name) for p in params]
    return cases


CASES = _cases()

BAD = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, 10**400, 1j, 2 + 3j]),
    st.builds(object),
    st.just(None),
    st.booleans(),
    st.text(min_size=1, max_size=4),
    st.sampled_from([np.zeros((2, 7, 3)), np.full(5, np.nan), [[1.0, 2.0], [3.0]], [object()]]),
)


def _allowed(param: inspect.Parameter, value: Any) -> bool:
    """Values the parameter legitimately takes (drawn, then skipped)."""
    note = str(param.annotation)
    if value is None and (param.default is None or "None" in note):
        return True
    if isinstance(value, bool) and ("bool" in note or isinstance(param.default, bool)):
        return True
    # an optional text label (a viewer object's name, a message's subject) takes any text,
    # and a file to write may be named by any text (nothing is written for it here)
    if isinstance(value, str) and param.name == "path" and "\0" not in value:
        return True
    return isinstance(value, str) and "str" in note and param.default is not param.empty


def _call(func: Callable[..., Any], module: str, label: str, bad: str, value: Any) -> None:
    sig = inspect.signature(func)
    owner = label.rsplit(".", 1)[0]
    args: dict[str, Any] = {}
    for p in sig.parameters.values():
        if p.name == "self" or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        if p.name == bad:
            args[p.name] = value
        elif p.default is p.empty:
            args[p.name] = _example(p.name, module)
    if "self" in sig.parameters:
        cls = getattr(importlib.import_module(module), owner.rsplit(".", 1)[-1])
        func = getattr(_instance(cls, module), func.__name__)
    func(**args)


@pytest.mark.parametrize(
    ("label", "module", "func", "bad"), CASES, ids=[f"{c[0]}[{c[3]}]" for c in CASES]
)
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(value=BAD)
def test_bad_values_raise_toolkit_errors(label, module, func, bad, value):
    param = inspect.signature(func).parameters[bad]
    if _allowed(param, value):
        return
    try:
        _call(func, module, label, bad, value)
    except toolkit.ToolkitError:
        return
    pytest.fail(f"{label}({bad}={value!r}) was accepted silently")


def test_every_public_callable_is_fuzzed():
    labels = {c[0] for c in CASES}
    assert len(labels) > 80
    assert "toolkit.Robot.ik" in labels and "toolkit.bending.inverse" in labels


CLI_BAD = [
    ["fk", "katana_6m180", "nan", "0", "0", "0", "0"],
    ["fk", "katana_6m180", "0", "0"],
    ["fk", "nope", "0"],
    ["fk", "katana_6m180", "0", "0", "0", "0", "0", "--frame", "nope"],
    ["fk", "katana_6m180", "0", "0", "0", "0", "0", "--set", "a2=-1"],
    ["fk", "katana_6m180", "0", "0", "0", "0", "0", "--set", "a2"],
    ["ik", "ur5", "inf", "0", "0"],
    ["ik", "ur5", "0.3", "0.2", "0.4", "--rpy", "nan", "0", "0"],
    ["ik", "ur5", "0.3", "0.2", "0.4", "--seed", "-1"],
    ["urdf", "katana_6m180", "-o", "/nonexistent/folder/x.urdf"],
    ["urdf", "--all"],
    ["urdf"],
    ["view", "scara", "--seconds", "-1"],
    ["view", "scara", "--q", "nan", "0", "0"],
    ["report", "-o", "/proc/nonexistent/report"],
]


@pytest.mark.parametrize("argv", CLI_BAD, ids=[" ".join(a) for a in CLI_BAD])
def test_cli_bad_input_exits_2_with_a_message(argv, capsys):
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own usage errors
        code = int(exc.code or 0)
    err = capsys.readouterr().err
    assert code == 2 and "error" in err and "Traceback" not in err


def _length_pairs() -> list[tuple[str, Callable[[], object]]]:
    """Calls whose two array arguments must agree in length, given lengths that do not."""
    from toolkit import backlash as bl

    ur5 = toolkit.load_example("ur5")
    katana = toolkit.load("katana_6m180")
    layer = bl.Backlash(katana)
    six = ur5.fk(ur5.random_q(6, seed=1))
    return [
        ("backlash.offset(torque, nominal_torque)", lambda: bl.offset(np.ones(5), np.ones(3))),
        ("backlash.offset(torque, delta)", lambda: bl.offset(np.ones(5), np.ones(5), np.ones(4))),
        ("Backlash.torques(theta, dtheta)", lambda: layer.torques(np.zeros(5), np.zeros(4))),
        (
            "Backlash.torques(theta (N, n), ddtheta (M, n))",
            lambda: layer.torques(np.zeros((3, 5)), None, np.zeros((2, 5))),
        ),
        (
            "Robot.point_kinematics(q, qd, qdd)",
            lambda: ur5.point_kinematics(np.zeros(6), np.zeros(5), np.zeros(6)),
        ),
        ("Robot.ik_batch(targets, q0)", lambda: ur5.ik_batch(six, ur5.random_q(4, seed=2))),
        ("Backlash.solve(q_cmd, start)", lambda: layer.solve(np.zeros((3, 5)), start=np.zeros(4))),
    ]


@pytest.mark.parametrize("index", range(7))
def test_arguments_that_must_agree_in_length(index):
    label, call = _length_pairs()[index]
    with pytest.raises(toolkit.ToolkitError):
        call()
    assert label  # the case's name, shown by pytest when it fails
