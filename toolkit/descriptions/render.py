"""xacro -> URDF rendering with argument validation and an on-disk cache.

Templates live in the repository's ``urdf/`` folder and ship inside the wheel as
``toolkit/urdf/``. A render is keyed by a SHA-256 hash of the toolkit version,
every template file and the resolved arguments; the URDF goes to the verified cache of
:mod:`toolkit.common.cache` (``$TOOLKIT_CACHE_DIR``, else ``$XDG_CACHE_HOME/manipulator-toolkit``)
and is checked against its digest before every later use.
"""

from __future__ import annotations

import hashlib
import json
import sys
import threading
import time
import xml.dom.minidom
from collections.abc import Callable, Mapping
from functools import cache, lru_cache
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

from .._version import __version__
from ..common import cache as _cache
from ..common import validate as _validate
from ..errors import InstallationError, InvalidParameterError, RenderError, ToolkitError
from .catalogue import ModelSpec, get_spec

__all__ = [
    "committed_urdf_path",
    "model_arguments",
    "resolve_arguments",
    "template_arguments",
    "templates_dir",
    "urdf_path",
    "urdf_text",
]

_XACRO_NS = "http://www.ros.org/wiki/xacro"
_XACRO_LOCK = threading.Lock()  # xacro keeps module-level state
_HERE = Path(__file__).resolve().parents[1]  # the toolkit package


def templates_dir() -> Path:
    """The folder holding the xacro templates (inside the package when installed)."""
    for folder in (_HERE / "urdf", _HERE.parent / "urdf"):
        if (folder / "common.xacro").is_file():
            return folder
    raise InstallationError(
        f"xacro templates not found in {_HERE / 'urdf'} or {_HERE.parent / 'urdf'}; "
        "the installation is incomplete"
    )


def committed_urdf_path(name: str) -> Path:
    """Path of the URDF rendered with default arguments that ships with the toolkit."""
    get_spec(name)
    return templates_dir() / f"{name}.urdf"


def template_arguments(template: str) -> dict[str, str]:
    """Every ``xacro:arg`` of a template with its default text (unevaluated)."""
    if not isinstance(template, str) or "/" in template or template.startswith("."):
        raise InvalidParameterError(f"template must be a file name in urdf/, got {template!r:.80}")
    return dict(_template_arguments(template))


@cache
def _template_arguments(template: str) -> dict[str, str]:
    path = templates_dir() / template
    if not path.is_file():
        raise InstallationError(f"template {template!r} not found in {templates_dir()}")
    doc = xml.dom.minidom.parse(str(path))
    args = {}
    for node in doc.getElementsByTagNameNS(_XACRO_NS, "arg") or doc.getElementsByTagName(
        "xacro:arg"
    ):
        args[node.getAttribute("name")] = node.getAttribute("default")
    return args


def model_arguments(name: str) -> dict[str, str]:
    """Arguments a user may set for a catalogue model, with their default text."""
    spec = get_spec(name)
    return {
        key: default
        for key, default in template_arguments(spec.template).items()
        if key not in spec.fixed and key not in spec.hidden
    }


def _as_number(spec: ModelSpec, key: str, value: object) -> float | int:
    what = f"{spec.name}: argument {key!r}"
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise InvalidParameterError(f"{what} must be a number, got {value!r}") from None
    number = _validate.number(value, what)
    if key in spec.integers:
        if number != int(number) or number < 1:
            raise InvalidParameterError(f"{what} must be a whole number >= 1, got {value!r}")
        return int(number)
    return number


def _evaluate_defaults(spec: ModelSpec, mappings: Mapping[str, str]) -> dict[str, str]:
    """Let xacro itself evaluate every argument (defaults may be expressions)."""
    args = template_arguments(spec.template)
    lines = [f'<robot name="args" xmlns:xacro="{_XACRO_NS}">']
    lines += [f"<xacro:arg name={quoteattr(k)} default={quoteattr(v)}/>" for k, v in args.items()]
    lines += [f"<value name={quoteattr(k)} text={quoteattr(f'$(arg {k})')}/>" for k in args]
    lines.append("</robot>")
    doc = _run_xacro(None, "\n".join(lines), mappings)
    return {
        n.getAttribute("name"): n.getAttribute("text") for n in doc.getElementsByTagName("value")
    }


def resolve_arguments(name: str, **params: object) -> dict[str, float | int | str]:
    """Validate keyword overrides and return every argument's value for the render.

    Raises :class:`InvalidParameterError` for an unknown or fixed argument name, a
    non-numeric or non-finite value, a length or mass that is not positive, or a
    lower limit that is not below its upper limit; the model's geometry check
    (for example ``d < 2R``) runs last.
    """
    spec = get_spec(name)
    allowed = model_arguments(name)
    for key in params:
        if key in spec.fixed:
            raise InvalidParameterError(
                f"{name}: argument {key!r} is fixed to {spec.fixed[key]!r} by this model"
            )
        if key not in allowed:
            raise InvalidParameterError(
                f"{name}: unknown argument {key!r}; valid arguments: {', '.join(sorted(allowed))}"
            )
    overrides = {key: _as_number(spec, key, value) for key, value in params.items()}
    mappings = {**spec.fixed, **{k: repr(v) for k, v in overrides.items()}}
    resolved_text = _evaluate_defaults(spec, mappings)
    values: dict[str, float | int | str] = {}
    for key in allowed:
        values[key] = (
            overrides[key] if key in overrides else _as_number(spec, key, resolved_text[key])
        )
    for key in sorted(spec.positive & values.keys()):
        if not values[key] > 0:  # type: ignore[operator]
            raise InvalidParameterError(f"{name}: argument {key!r} must be > 0, got {values[key]}")
    for key in sorted(spec.nonnegative & values.keys()):
        if not values[key] >= 0:  # type: ignore[operator]
            raise InvalidParameterError(f"{name}: argument {key!r} must be >= 0, got {values[key]}")
    for lower, upper in spec.limit_pairs:
        if not values[lower] < values[upper]:  # type: ignore[operator]
            raise InvalidParameterError(
                f"{name}: lower limit {lower}={values[lower]} must be below "
                f"upper limit {upper}={values[upper]}"
            )
    if spec.check is not None:
        spec.check({k: v for k, v in values.items() if not isinstance(v, str)})
    values.update(spec.fixed)
    return values


def _run_xacro(
    path: Path | None, text: str | None, mappings: Mapping[str, str]
) -> xml.dom.minidom.Document:
    with _XACRO_LOCK:
        return _run_xacro_unlocked(path, text, mappings)


def _run_xacro_unlocked(
    path: Path | None, text: str | None, mappings: Mapping[str, str]
) -> xml.dom.minidom.Document:
    import xacro

    try:
        xacro.init_stacks(str(path) if path else None)
        doc = xacro.parse(text, str(path) if path else None)
        xacro.process_doc(doc, mappings=dict(mappings))
    except Exception as exc:  # xacro raises a zoo of exception types
        where = path.name if path else "argument evaluation"
        raise RenderError(f"xacro failed on {where}: {exc}") from exc
    return doc  # type: ignore[no-any-return]


XACRO_SECONDS = 60.0
"""Wall-clock budget [s] of rendering one user xacro file (a macro bomb stops there)."""
XACRO_CALLS = 50_000_000
"""Python calls xacro may make for one user file (the same guard, machine-independent)."""


class _Budget:
    """A trace function that stops a runaway xacro expansion with a RenderError."""

    def __init__(self, path: Path) -> None:
        self.path, self.calls, self.spent = path, 0, False
        self.deadline = time.monotonic() + XACRO_SECONDS

    def __call__(self, frame: object, event: str, arg: object) -> None:
        if event == "call":
            self.calls += 1
            if self.spent or (
                self.calls % 4096 == 0
                and (self.calls > XACRO_CALLS or time.monotonic() > self.deadline)
            ):
                self.spent = True
                raise RenderError(
                    f"xacro expansion of {self.path} stopped: more than {XACRO_SECONDS:g} s "
                    f"or {XACRO_CALLS:,} calls (a macro that expands without bound?)"
                )


def run_xacro(path: Path, mappings: Mapping[str, str], find: Callable[[str], Path]) -> str:
    """The URDF text xacro renders from a user's file; ``$(find pkg)`` calls ``find``.

    The expansion runs under a budget (:data:`XACRO_SECONDS`, :data:`XACRO_CALLS`): a macro
    bomb raises :class:`~toolkit.errors.RenderError` and releases the xacro lock."""
    import xacro.substitution_args as substitution

    failures: list[ToolkitError] = []

    def hook(pkg: str) -> str:
        try:
            return str(find(pkg))
        except ToolkitError as exc:  # re-raised below as itself, not wrapped by xacro
            failures.append(exc)
            raise

    budget = _Budget(path)
    with _XACRO_LOCK:
        original = substitution._eval_find
        substitution._eval_find = hook
        tracer = sys.gettrace()
        sys.settrace(budget)
        try:
            doc = _run_xacro_unlocked(path, None, mappings)
        except RenderError:
            if failures:
                raise failures[0] from None
            if budget.spent:
                raise RenderError(
                    f"xacro expansion of {path} stopped: more than {XACRO_SECONDS:g} s or "
                    f"{XACRO_CALLS:,} calls (a macro that expands without bound?)"
                ) from None
            raise
        finally:
            sys.settrace(tracer)
            substitution._eval_find = original
    root = doc.documentElement
    if root is None:  # pragma: no cover - xacro returns a document
        raise RenderError(f"xacro returned an empty document for {path}")
    return '<?xml version="1.0"?>\n' + root.toprettyxml(indent="  ")


def _strip_comments(node: xml.dom.minidom.Node) -> None:
    """Remove every comment below ``node`` (the rendered URDF carries one banner only)."""
    for child in list(node.childNodes):
        if child.nodeType == child.COMMENT_NODE:
            node.removeChild(child)  # type: ignore[misc]
        else:
            _strip_comments(child)


def _render(spec: ModelSpec, values: Mapping[str, object], overrides: Mapping[str, object]) -> str:
    mappings = {k: v if isinstance(v, str) else repr(v) for k, v in values.items()}
    doc = _run_xacro(templates_dir() / spec.template, None, mappings)
    _strip_comments(doc)
    root = doc.documentElement
    if root is None:  # pragma: no cover - xacro always returns a <robot> document
        raise RenderError(f"xacro returned an empty document for {spec.template}")
    body = root.toprettyxml(indent="  ")
    lines = [line for line in body.splitlines() if line.strip()]
    what = (
        "with default arguments"
        if not overrides
        else "with " + ", ".join(f"{k}={overrides[k]!r}" for k in sorted(overrides))
    )
    banner = (
        f"<!-- Generated by manipulator-toolkit from urdf/{spec.template} for model "
        f"{spec.name} {what}. Do not edit: change the template or pass arguments. -->"
    )
    return '<?xml version="1.0"?>\n' + banner + "\n" + "\n".join(lines) + "\n"


@lru_cache(maxsize=1)
def _templates_digest() -> str:
    h = hashlib.sha256(__version__.encode())
    for path in sorted(templates_dir().glob("*.xacro")):
        h.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


def _key(name: str, params: Mapping[str, object]) -> tuple[str, dict[str, Any]]:
    spec = get_spec(name)
    values = resolve_arguments(name, **params)
    # the banner names the arguments that differ from the defaults, so that equal
    # argument values always give the same text (and the same cache entry)
    defaults = resolve_arguments(name) if params else values
    overrides = {k: values[k] for k in params if values[k] != defaults[k]}
    payload = json.dumps({"model": name, "args": values}, sort_keys=True, default=repr)
    digest = hashlib.sha256((_templates_digest() + payload).encode()).hexdigest()
    return digest, {"spec": spec, "values": values, "overrides": overrides}


_MEMO: dict[str, str] = {}


def _text(digest: str, job: dict[str, Any]) -> str:
    """The rendered URDF of a job, rendered once per process (xacro takes milliseconds)."""
    if digest not in _MEMO:
        _MEMO[digest] = _render(job["spec"], job["values"], job["overrides"])
    return _MEMO[digest]


def urdf_path(name: str, **params: object) -> Path:
    """Path of the cached URDF of a catalogue model with keyword overrides.

    The file lives in a verified cache (:mod:`toolkit.common.cache`): rendered through xacro
    the first time for an argument set, checked against its digest before every later
    use, and re-rendered if it is missing, damaged or tampered with.
    """
    digest, job = _key(name, params)
    return _cache.store(f"{name}-{digest[:20]}.urdf", lambda: _text(digest, job))


def urdf_text(name: str, **params: object) -> str:
    """URDF text of a catalogue model; keyword arguments override the template's defaults."""
    digest, job = _key(name, params)
    return _text(digest, job)
