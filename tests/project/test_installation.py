"""Any installation, any caller: read-only homes, hostile cache folders, full disks,
threads on numba's workqueue layer, fork-based pools after batch calls, and the warm-up.

Each case runs in a fresh interpreter (numba decides its cache folder and threading layer
once per process). A folder "of another user" is simulated as the cache tests do: by its
mode, or by its owner when the tests run as root.
"""

from __future__ import annotations

import errno
import os
import subprocess
import sys
import warnings

import pytest

import toolkit
from toolkit.common import compiler as _numba

_WORK = """
import warnings, numpy as np, toolkit
warnings.simplefilter("always")
robot = toolkit.load_example("kinova")
Q = robot.random_q(100, seed=1)
T = robot.fk(Q)
ok = robot.ik(T[0]).success and robot.ik_batch(T[:70]).success.all()
print("RESULT", robot.kinematics.engine.name, bool(ok), bool(np.isfinite(robot.jacobian(Q)).all()))
"""


def _run(
    code: str, env: dict[str, str], timeout: float = 900, argv: tuple[str, ...] = ()
) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", code, *argv], env=env, capture_output=True, text=True,
        timeout=timeout,
    )  # fmt: skip


def _env(**changes: str | None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    for key, value in changes.items():
        if value is None:
            env.pop(key, None)
        else:
            env[key] = value
    return env


def _result(out: subprocess.CompletedProcess) -> list[str]:
    assert out.returncode == 0, out.stderr[-3000:]
    lines = [line for line in out.stdout.splitlines() if line.startswith("RESULT")]
    assert lines, out.stdout[-2000:]
    return lines[-1].split()[1:]


@pytest.mark.slow
def test_no_writable_folder_compiles_in_memory(tmp_path):
    """A read-only home and temporary folder (a system or container install): every
    compiled call still works, with one warning saying the kernels live in memory."""
    blocker = tmp_path / "a-file"
    blocker.write_text("no folder can be made below a file, not even by root")
    env = _env(
        HOME=str(blocker / "home"),
        XDG_CACHE_HOME=str(blocker / "cache"),
        TOOLKIT_CACHE_DIR=None,
        TMPDIR=str(blocker / "tmp"),
    )
    # root may write /tmp whatever TMPDIR says: the temporary folder is closed in Python
    closed = (
        "import tempfile\n"
        f"tempfile.gettempdir = lambda: {str(blocker / 'tmp')!r}\n"
        "def _no(*a, **k): raise PermissionError(13, 'read-only file system')\n"
        "tempfile.mkdtemp = _no\n"
    )
    out = _run(closed + _WORK, env)
    assert _result(out) == ["compiled", "True", "True"]
    assert "compiled in memory" in out.stderr


def _hostile_folder(tmp_path):
    folder = tmp_path / "shared-numba-cache"
    folder.mkdir()
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        os.chown(folder, 65534, 65534)  # owned by "nobody"
    folder.chmod(0o777)
    return folder


@pytest.mark.slow
def test_a_numba_cache_folder_others_can_write_is_ignored(tmp_path):
    """numba's cache loads pickles: a NUMBA_CACHE_DIR another user can write is refused."""
    folder = _hostile_folder(tmp_path)
    out = _run(_WORK, _env(NUMBA_CACHE_DIR=str(folder)))
    assert _result(out) == ["compiled", "True", "True"]
    assert "NUMBA_CACHE_DIR" in out.stderr and "ignored" in out.stderr
    assert list(folder.iterdir()) == [], "nothing may be written to, or read from, it"


@pytest.mark.slow
def test_a_private_numba_cache_folder_is_used(tmp_path):
    folder = tmp_path / "mine"
    folder.mkdir(mode=0o700)
    out = _run(_WORK + "\nfrom toolkit.kinematics import cache_folder; print(cache_folder())", _env(
        NUMBA_CACHE_DIR=str(folder)
    ))  # fmt: skip
    assert _result(out) == ["compiled", "True", "True"]
    assert any(folder.rglob("*.nbi")), "the kernels' index files are written there"


_CALLER = """
import sys
sys.path.insert(0, sys.argv[1])
from toolkit.common import compiler
compiler._DIGEST[:] = [sys.argv[2]]  # the package's sources as they stood (a stand-in)
import caller
print("RESULT", caller.read())
"""


@pytest.mark.slow
def test_a_kernel_cached_before_a_change_to_a_kernel_it_calls_is_compiled_anew(tmp_path):
    """numba keys a cached kernel by its own file's stamp, while it holds the machine code
    of the kernels it calls from other files: a change to the callee's file alone left the
    caller loaded stale. The toolkit's stamp holds a digest of its sources (here set by
    hand, as a checkout would change it): the caller is compiled anew."""
    code, cache = tmp_path / "code", tmp_path / "cache"
    code.mkdir()
    cache.mkdir(mode=0o700)
    kernel = "from toolkit.kinematics import kernel\n\n\n@kernel\n"
    (code / "callee.py").write_text(kernel + "def value():\n    return 1.0\n")
    (code / "caller.py").write_text(
        "import callee\n" + kernel + "def read():\n    return callee.value() + 10.0\n"
    )
    env = _env(NUMBA_CACHE_DIR=str(cache))
    assert _result(_run(_CALLER, env, argv=(str(code), "before"))) == ["11.0"]
    assert any(cache.rglob("caller.read-*.nbi")), "the caller was cached"
    (code / "callee.py").write_text(
        kernel + "def value():\n    return 2.0\n"
    )  # caller.py untouched
    assert _result(_run(_CALLER, env, argv=(str(code), "after"))) == ["12.0"]


def test_every_kernels_cache_stamp_is_the_digest_of_what_it_compiles_from(tmp_path):
    """The stamp (module doc of toolkit.common.compiler) is where numba reads it, in place of
    the file's time stamp: the digest of the files the kernel reaches and the constants it
    reads (``kernel_digest``), which every toolkit kernel has. The planner's edge check
    reaches the kernels it calls and no file of the compiler's set-up; and the whole
    package's digest changes with any byte of any source file."""
    from toolkit.collision import bound_kernels, gap_kernels
    from toolkit.common import background, sources
    from toolkit.planning import kernels

    for dispatcher in (kernels.edge_swept, gap_kernels.pair_gaps,
                       bound_kernels.decide_batch.serial):  # fmt: skip
        stamp = dispatcher._cache._cache_file._source_stamp
        assert stamp == ("toolkit", sources.kernel_digest(dispatcher))
        assert len(stamp[1]) == 16 and int(stamp[1], 16) >= 0
    from toolkit.cli import precompile  # noqa: F401 - imports every concept's kernels

    untraced = [key for key, (d, _) in background._REGISTRY.items()
                if sources.kernel_digest(d) is None]  # fmt: skip
    assert len(background._REGISTRY) > 100 and not untraced
    found = sources.kernel_sources(kernels.edge_swept)
    assert found is not None
    files, values = found
    assert {"planning/kernels.py", "collision/gap_kernels.py", "kinematics/kernels.py"} <= set(
        files)  # fmt: skip
    assert not [f for f in files if f.startswith(("common/", "robot/", "cli/"))]
    assert any(v.endswith(f"GROWTH=float:{kernels.GROWTH!r}") for v in values)
    tree = tmp_path / "pkg"
    (tree / "sub").mkdir(parents=True)
    (tree / "a.py").write_text("x = 1\n")
    (tree / "sub" / "b.py").write_text("y = 2\n")
    first = _numba.sources_digest(tree)
    assert _numba.sources_digest(tree) == first
    (tree / "sub" / "b.py").write_text("y = 3\n")
    assert _numba.sources_digest(tree) != first
    (tree / "sub" / "b.py").write_text("y = 2\n")
    assert _numba.sources_digest(tree) == first
    (tree / "sub" / "b.py").rename(tree / "b.py")  # the same bytes under another path
    assert _numba.sources_digest(tree) != first


_DIGEST_OF = """
import sys
sys.path.insert(0, sys.argv[1])
from toolkit.common import sources
import caller
print("RESULT", sources.kernel_digest(caller.read))
"""


def test_a_kernels_digest_follows_what_it_calls_and_reads_and_nothing_else(tmp_path):
    """``kernel_digest``: a change to the kernel's file, to a kernel it calls in another
    file, or to a constant it reads from another module changes it; a change to a module
    it imports and does not call, or a new time stamp on the same bytes (a reinstall), does
    not. Each digest is taken in a fresh interpreter, as a user's next process would."""
    code = tmp_path / "code"
    code.mkdir()
    kernel = "from toolkit.kinematics import kernel\n\n\n@kernel\n"
    files = {
        "callee.py": kernel + "def value():\n    return 1.0\n",
        "consts.py": "LIMIT = 2.0\n",
        "unused.py": "def helper():\n    return 0\n",
        "caller.py": "import callee\nimport unused\nfrom consts import LIMIT\n"
        + kernel
        + "def read():\n    return callee.value() + LIMIT\n",
    }
    for name, text in files.items():
        (code / name).write_text(text)

    def digest() -> str:
        return _result(_run(_DIGEST_OF, _env(), argv=(str(code),)))[0]

    first = digest()
    assert len(first) == 16
    changes = {"unused.py": ("return 0", "return 5", False),
               "consts.py": ("2.0", "3.0", True),
               "callee.py": ("1.0", "1.5", True),
               "caller.py": ("+ LIMIT", "- LIMIT", True)}  # fmt: skip
    for name, (old, new, matters) in changes.items():
        (code / name).write_text(files[name].replace(old, new))
        assert (digest() != first) == matters, name
        (code / name).write_text(files[name])
    os.utime(code / "callee.py", (1, 1))  # the same bytes, another time stamp
    assert digest() == first


def test_a_kernel_whose_code_cannot_be_followed_has_no_digest_and_its_values_count():
    """``kernel_digest``: a global that does not exist, or a closure's cell not filled yet,
    gives None (the stamp falls back to the module's digest) instead of an error; a
    closure's value is part of the digest."""
    from toolkit.common import sources

    def reads_nothing_known():
        return undefined_name  # noqa: F821 - the point

    def make(value):
        def kernel():
            return value

        return kernel

    def empty():
        def kernel():
            return later  # filled below, after the digest

        digest = sources.kernel_digest(kernel)
        later = 1.0
        return digest, kernel

    assert sources.kernel_digest(reads_nothing_known) is None
    assert sources.kernel_digest(make(1.0)) != sources.kernel_digest(make(2.0))
    digest, kernel = empty()
    assert digest is None and sources.kernel_digest(kernel) is not None


def test_a_kernels_digest_follows_what_its_module_imports_and_nothing_else(tmp_path):
    """``module_digest``: a change to the kernel's file, to a file it imports (through a
    package's ``__init__``, relatively or absolutely, in parentheses, indented) changes it;
    a change to a file it does not import (the package's face) does not; a module outside
    the package has none."""
    from toolkit.common import sources

    root = tmp_path / "toolkit"
    for folder in ("core", "face", "deep"):
        (root / folder).mkdir(parents=True)
    files = {
        "__init__.py": "from . import face\n",
        "core/__init__.py": "from .kern import k\n",
        "core/kern.py": "from ..deep import (\n    consts,\n)\nfrom . import helper\n",
        "core/helper.py": "def f():\n    import toolkit.deep.lazy\n",
        "deep/__init__.py": "",
        "deep/consts.py": "X = 1\n",
        "deep/lazy.py": "Y = 1\n",
        "face/__init__.py": "from ..core import kern\n",
    }
    for name, text in files.items():
        (root / name).write_text(text)

    def digest() -> str | None:
        sources._GRAPHS.clear()  # read afresh (a process reads the files once)
        return sources.module_digest("toolkit.core.kern", root)

    first = digest()
    assert first is not None and sources.module_digest("elsewhere.kern", root) is None
    for name in ("core/kern.py", "deep/consts.py", "core/helper.py", "deep/lazy.py",
                 "core/__init__.py", "deep/__init__.py"):  # fmt: skip
        before = (root / name).read_text()
        (root / name).write_text(before + "# changed\n")
        assert digest() != first, name
        (root / name).write_text(before)
        assert digest() == first
    for name in ("face/__init__.py", "__init__.py"):
        (root / name).write_text((root / name).read_text() + "# changed\n")
        assert digest() == first, name
    sources._GRAPHS.clear()


def test_a_failing_cache_write_warns_once_and_the_call_goes_on():
    """A full disk (ENOSPC) while numba saves a kernel: the kernel stays in memory."""

    class FullDisk:
        calls = 0

        def save_overload(self, *args, **kwargs):
            FullDisk.calls += 1
            raise OSError(errno.ENOSPC, "No space left on device")

    class Dispatcher:
        _cache = FullDisk()

    dispatcher = Dispatcher()
    _numba._guard_saves(dispatcher)
    _numba._WARNED.discard("save")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dispatcher._cache.save_overload("sig", "data")
        dispatcher._cache.save_overload("sig", "data")
    assert FullDisk.calls == 2
    messages = [str(w.message) for w in caught if issubclass(w.category, _numba.EngineCacheWarning)]
    assert len(messages) == 1 and "No space left" in messages[0]


_THREADS = """
import threading, numpy as np, numba, toolkit
robot = toolkit.load_example("ur5")
Q = robot.random_q(400, seed=2)
T = robot.fk(Q)
errors = []
def work(k):
    try:
        for _ in range(5):
            assert np.allclose(robot.fk(Q), T)
            robot.jacobian(Q); robot.gravity(Q)
            assert robot.ik_batch(T[:80], seed=k).success.mean() > 0.9
    except Exception as exc:
        errors.append(repr(exc))
threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
[t.start() for t in threads]; [t.join() for t in threads]
print("RESULT", numba.threading_layer(), len(errors), errors[:1])
"""


@pytest.mark.slow
def test_threads_launching_batches_on_the_workqueue_layer():
    """numba's workqueue layer aborts the process when two threads launch parallel
    kernels at once; the toolkit serialises the launches."""
    out = _run(_THREADS, _env(NUMBA_THREADING_LAYER="workqueue"))
    assert _result(out)[:2] == ["workqueue", "0"]


@pytest.mark.slow  # a fresh interpreter on numba's default layer: ~25 s
def test_threads_on_the_default_layer():
    out = _run(_THREADS, _env())
    assert _result(out)[1] == "0"


_FORK = """
import multiprocessing as mp, numpy as np, toolkit
robot = toolkit.load_example("ur5")
Q = robot.random_q(300, seed=3)
T = robot.fk(Q)  # a parallel batch in the parent, before the fork
robot.ik_batch(T[:100])
def child(k):
    return float(np.abs(robot.fk(Q) - T).max()), float(robot.ik_batch(T[:80], seed=k).success_rate)
with mp.get_context("fork").Pool(2) as pool:
    out = pool.map(child, range(4))
print("RESULT", max(e for e, _ in out) == 0.0, min(s for _, s in out) > 0.9)
"""


@pytest.mark.skipif(sys.platform != "linux", reason="fork is Linux's default start method")
@pytest.mark.slow  # a fresh interpreter that forks a pool: ~25 s
def test_a_fork_pool_after_batch_calls_works():
    """GNU OpenMP cannot run in a forked child: the toolkit asks numba for a fork-safe
    layer, so a fork-based pool started after batch calls answers (and does not hang)."""
    out = _run(_FORK, _env(), timeout=600)
    assert _result(out) == ["True", "True"]


def test_warmup_compiles_every_kernel(capsys):
    times = toolkit.warmup(verbose=True)
    assert times["total"] >= max(v for k, v in times.items() if k != "total")
    assert any(k.startswith("backlash") for k in times)
    assert {"analytic ik_all_batch ur5", "analytic ik_all_batch katana_6m180"} <= set(times)
    printed = capsys.readouterr().out
    assert "compiled kernels cached in" in printed and "warm-up done" in printed


def test_warmup_from_the_command_line():
    from toolkit.cli import main

    assert main(["warmup"]) == 0


_LAZY = """
import sys, threading
import toolkit
heavy = ("numpy", "pinocchio", "numba")
names = dir(toolkit)  # the face, without loading it
assert {"load", "load_example", "Robot", "Scene", "planning", "katana"} <= set(names), names
assert "toolkit.robot" not in sys.modules and "_bind" not in names
before = [m for m in heavy if m in sys.modules]
from toolkit.cli import main
try:
    main(["--help"])
except SystemExit:
    pass
after_help = [m for m in heavy if m in sys.modules]
out = []
threads = [threading.Thread(target=lambda: out.append(toolkit.load("scara").nq)) for _ in range(4)]
for t in threads:
    t.start()
for t in threads:
    t.join()
import toolkit.katana
from toolkit.backlash.fixed_point import settle
import toolkit.papers.backlash.fixed_point as fixed_point
same = (toolkit.katana is sys.modules["toolkit.papers.katana"] is toolkit.katana
        and settle is fixed_point.settle and toolkit.warmup is toolkit.cli.warmup)
print("RESULT", ",".join(before) or "-", ",".join(after_help) or "-", out, same)
"""


def test_the_package_loads_on_first_use_and_the_help_loads_nothing_heavy():
    """``import toolkit``, ``dir(toolkit)`` (every public name) and ``toolkit --help``
    import neither numpy, Pinocchio nor numba (0.07 s for the help, 1.0 s before); the
    first name asked for loads the package, once
    among threads asking at the same time; a paper's short name, its submodules and the
    facade's warmup are the same objects as before."""
    before, after_help, *rest = _result(_run(_LAZY, _env()))
    assert before == "-" and after_help == "-"
    assert " ".join(rest) == "[3, 3, 3, 3] True"


def test_the_calibrate_help_lists_the_kinds_calibration_takes():
    from toolkit import calibration
    from toolkit.cli import calibrate

    assert calibrate.KINDS == tuple(k for k in calibration.KINDS if k != "backlash")
