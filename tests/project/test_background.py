"""No call waits for the compiler (toolkit.common.background): in a fresh installation a
kernel's first call runs its Python body while a background process compiles it, the answer
is the compiled one's, and the next calls load the machine code that process wrote.

Each case runs in a fresh interpreter with its own empty cache and the default mode (the
rest of the suite runs with ``TOOLKIT_COMPILE=wait``, tests/conftest.py).
"""

from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys

import numpy as np
import pytest

import toolkit
from toolkit.common import background

_FIRST = """
import json, time, numpy as np, toolkit
from toolkit.common import background
from toolkit.kinematics import compile_seconds
ur5 = toolkit.load_example("ur5")
q = np.array([0.3, -1.1, 1.4, -0.9, 1.2, 0.4])
wall = toolkit.Scene().add_box("wall", [0.1, 1.2, 0.8], [0.45, 0.0, 0.4])

def answers():
    T = ur5.fk(q)
    return {"fk": T.tolist(), "ik": ur5.ik(T, q0=q + 0.1).q.tolist(),
            "ik_all": ur5.ik_all(T).q.tolist(),
            "in_collision": bool(ur5.in_collision(q, scene=wall))}

first = answers()
waiting, compiled_first = background.pending(), compile_seconds()
began = time.perf_counter()
while background.pending() and time.perf_counter() - began < 900:
    time.sleep(0.5)
    answers()  # a call collects the finished background process
later = answers()
machine_code = sum(len(d.overloads) for d, _ in background._REGISTRY.values())
print("RESULT " + json.dumps({"first": first, "later": later, "waiting": waiting,
      "compiled_here": [compiled_first, compile_seconds()], "machine_code": machine_code,
      "left": background.pending()}))
"""


def _run(code: str, cache, **env: str) -> subprocess.CompletedProcess:
    environ = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    environ.pop("TOOLKIT_COMPILE")  # the default: background
    environ.update(TOOLKIT_CACHE_DIR=str(cache), **env)
    return subprocess.run(
        [sys.executable, "-c", code], env=environ, capture_output=True, text=True, timeout=1200
    )


def _result(out: subprocess.CompletedProcess) -> dict:
    assert out.returncode == 0, out.stderr[-3000:]
    lines = [line for line in out.stdout.splitlines() if line.startswith("RESULT ")]
    assert lines, out.stdout[-2000:]
    return json.loads(lines[-1][len("RESULT ") :])


@pytest.mark.slow
def test_first_calls_run_as_python_then_load_what_the_background_compiled(tmp_path):
    """The UR5's first fk, ik, ik_all and in_collision in a fresh installation: nothing is
    compiled in the caller's process, the answers are those of the compiled kernels (this
    process, TOOLKIT_COMPILE=wait), and once the background process is done the same calls
    run machine code loaded from the cache, with the same answers."""
    out = _run(_FIRST, tmp_path / "cache")
    got = _result(out)
    assert got["waiting"] > 0, "the first calls handed their kernels to a background process"
    assert got["compiled_here"] == [0.0, 0.0], "the caller's process compiled nothing"
    assert got["left"] == 0 and got["machine_code"] > 0, "then it loaded their machine code"
    assert "background process" in out.stderr, "said once on the toolkit.compile logger"
    assert out.stderr.count("background process") == 1

    ur5 = toolkit.load_example("ur5")
    q = np.array([0.3, -1.1, 1.4, -0.9, 1.2, 0.4])
    wall = toolkit.Scene().add_box("wall", [0.1, 1.2, 0.8], [0.45, 0.0, 0.4])
    T = ur5.fk(q)
    for answers in (got["first"], got["later"]):
        np.testing.assert_allclose(answers["fk"], T, rtol=0, atol=1e-13)
        np.testing.assert_allclose(answers["ik"], ur5.ik(T, q0=q + 0.1).q, rtol=0, atol=1e-9)
        mine = ur5.ik_all(T).q
        theirs = np.array(answers["ik_all"])
        assert theirs.shape == mine.shape
        np.testing.assert_allclose(np.sort(theirs, axis=0), np.sort(mine, axis=0), atol=1e-9)
        assert answers["in_collision"] == bool(ur5.in_collision(q, scene=wall))


_DOMAIN = """
import math, toolkit
from toolkit.kinematics import compile_seconds, trig
s, c = trig.sincos(float("inf"))
print("RESULT", math.isnan(s) and math.isnan(c), compile_seconds() > 0)
"""


def test_where_python_parts_from_the_compiled_kernel_the_call_compiles(tmp_path):
    """``math.sin(inf)`` raises in Python where the compiled kernel returns NaN: the call
    is made again compiled, in the caller's process, and answers as the kernel does."""
    out = _run(_DOMAIN, tmp_path / "cache")
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.split()[-2:] == ["True", "True"]


def test_an_unknown_mode_is_refused(monkeypatch):
    monkeypatch.setenv("TOOLKIT_COMPILE", "soon")
    with pytest.raises(ValueError, match=r"TOOLKIT_COMPILE='soon'.*background, wait"):
        background.mode()
    monkeypatch.setenv("TOOLKIT_COMPILE", "background")
    assert background.mode() == "background"
    with background.waiting():
        assert background.mode() == "wait", "the warm-up compiles in its own process"
    assert background.mode() == "background"


def test_the_background_process_compiles_only_the_toolkits_own_kernels(tmp_path):
    """Jobs naming anything but a registered toolkit kernel are refused (exit status 1),
    and nothing is compiled for them."""
    from numba.core import types

    jobs = [("os", "system", (types.int64,)), ("toolkit.kinematics.trig", "nothing", ())]
    root = str(__import__("pathlib").Path(toolkit.__file__).resolve().parents[1])
    code = f"import sys; sys.path.insert(0, {root!r}); from toolkit.common import background; "
    out = subprocess.run(
        [sys.executable, "-c", code + "background.main()"], input=pickle.dumps(jobs),
        capture_output=True, timeout=300,
        env={**os.environ, "TOOLKIT_CACHE_DIR": str(tmp_path)},
    )  # fmt: skip
    assert out.returncode == 1, out.stderr[-2000:]
    assert not list(tmp_path.rglob("*.nbi"))


@pytest.mark.slow
def test_background_processes_compile_one_at_a_time(tmp_path):
    """A background process waits for the cache folder's lock before it compiles (a fork
    pool's workers would otherwise compile the same kernels side by side): held here, the
    process compiles nothing; released, it compiles and exits 0."""
    import fcntl
    import time

    from numba.core import types

    folder = tmp_path / "numba"
    folder.mkdir(mode=0o700)
    jobs = [("toolkit.kinematics.trig", "sincos", (types.float64,))]
    root = str(__import__("pathlib").Path(toolkit.__file__).resolve().parents[1])
    code = f"import sys; sys.path.insert(0, {root!r}); from toolkit.common import background; "
    env = {**os.environ, "TOOLKIT_CACHE_DIR": str(tmp_path), "NUMBA_CACHE_DIR": str(folder)}
    with open(folder / background.LOCK_NAME, "ab") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        process = subprocess.Popen(
            [sys.executable, "-c", code + "background.main()"], stdin=subprocess.PIPE,
            env=env, cwd=str(folder),
        )  # fmt: skip
        assert process.stdin is not None
        process.stdin.write(pickle.dumps(jobs))
        process.stdin.close()
        time.sleep(15)  # long enough to import the toolkit and compile sincos
        assert process.poll() is None, "it did not wait for the lock"
        assert not list(folder.rglob("*.nbi")), "it compiled while the lock was held"
    assert process.wait(timeout=600) == 0
    assert list(folder.rglob("*sincos*.nbi")), "then it compiled"
