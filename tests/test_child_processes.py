"""Child processes die with their parent and within their budget (issue 29, item 7).

Fault injection: a process that has budgeted SymPy children (:mod:`symvib.symbolic.budget`),
or pool workers (``symvib paper``), is sent SIGKILL, SIGTERM or SIGINT, to the process
alone and to its group; every descendant it had (read from ``/proc/<pid>/task/*/children``
before the signal) must be gone soon after, well within its budget plus a second.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from symvib import children

pytestmark = pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="needs /proc (Linux)")

#: Budget (s) of the spinning child of the minimal driver.
BUDGET = 30.0
#: Seconds after the signal within which every descendant must be gone: the watchdog's period and
#: a second, far below the budget (so that only the tether, not the budget's end, can pass it).
GONE_WITHIN = children.WATCHDOG_SECONDS + 1.0
#: Hang guard (s) for a process to start its children, or to exit after a signal.
HANG_GUARD = 120.0
SIGNALS = (signal.SIGKILL, signal.SIGTERM, signal.SIGINT)
TARGETS = ("process", "group")

#: A minimal driver of the derivation's code path: budgeted children that would spin for BUDGET s.
DRIVER = textwrap.dedent(f"""
    import sys
    from symvib.symbolic import budget

    def spin():
        while True:
            pass

    print("ready", flush=True)
    while True:
        budget.run(spin, (), seconds={BUDGET})
""")


def _children(pid: int) -> set:
    found = set()
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            found.update(int(p) for p in (task / "children").read_text().split())
        except OSError:
            continue
    return found


def descendants(pid: int) -> set:
    """Every living descendant of ``pid`` (from /proc)."""
    out, todo = set(), [pid]
    while todo:
        for child in _children(todo.pop()):
            if child not in out:
                out.add(child)
                todo.append(child)
    return out


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie waiting for init to reap it has ended)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] not in ("Z", "X")


def _reset_sigint():
    # A shell's background job ignores SIGINT, and Python then keeps it ignored: restore the default.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(args, env=None, cwd=None):
    return subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=cwd,
                            start_new_session=True, preexec_fn=_reset_sigint)


def _wait_for_children(proc, count: int = 1) -> set:
    deadline = time.monotonic() + HANG_GUARD
    while time.monotonic() < deadline:
        found = descendants(proc.pid)
        if len(found) >= count:
            time.sleep(0.3)  # let the children start their own (a pool worker's budgeted child)
            return found | descendants(proc.pid)
        assert proc.poll() is None, f"exited early: {proc.communicate()}"
        time.sleep(0.05)
    pytest.fail("no child process started")


def _signal(proc, signum, target):
    if target == "group":
        os.killpg(proc.pid, signum)
    else:
        os.kill(proc.pid, signum)


def _assert_gone(pids: set, start: float):
    while time.monotonic() - start < GONE_WITHIN:
        if not any(alive(p) for p in pids):
            return
        time.sleep(0.05)
    left = sorted(p for p in pids if alive(p))
    for p in left:  # leave nothing behind for the next test
        try:
            os.kill(p, signal.SIGKILL)
        except OSError:
            pass
    pytest.fail(f"processes {left} outlived their parent by more than {GONE_WITHIN} s")


def _finish(proc) -> tuple:
    try:
        _, err = proc.communicate(timeout=HANG_GUARD)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail("the process did not exit after the signal")
    return proc.returncode, err


@pytest.mark.parametrize("target", TARGETS)
@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_budgeted_children_die_with_their_parent(signum, target):
    proc = _start([sys.executable, "-c", DRIVER])
    assert proc.stdout.readline().strip() == "ready"
    kids = _wait_for_children(proc)
    _signal(proc, signum, target)
    start = time.monotonic()
    _assert_gone(kids, start)
    _finish(proc)


def test_a_child_ends_at_its_cpu_limit_even_when_its_parent_cannot():
    """The parent stopped (SIGSTOP): the kernel ends the child a little after its budget."""
    code = textwrap.dedent("""
        import os, signal, sys
        from symvib import children
        pid = os.fork()
        if pid == 0:
            children.tether(os.getppid(), cpu_seconds=0.5)
            while True:
                pass
        print(pid, flush=True)
        _, status = os.waitpid(pid, 0)
        print(os.WTERMSIG(status) if os.WIFSIGNALED(status) else -1, flush=True)
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=HANG_GUARD)
    _, how = out.stdout.split()
    assert int(how) in (signal.SIGXCPU, signal.SIGKILL), out


def test_pool_workers_die_with_their_parent():
    """A worker pool (symvib.children.worker_pool) of a killed process leaves no worker behind."""
    code = textwrap.dedent("""
        import time
        from symvib.children import worker_pool
        with worker_pool(2) as pool:
            futures = [pool.submit(time.sleep, 600) for _ in range(2)]
            print("ready", flush=True)
            time.sleep(600)
    """)
    proc = _start([sys.executable, "-c", code])
    assert proc.stdout.readline().strip() == "ready"
    kids = _wait_for_children(proc, 2)
    os.kill(proc.pid, signal.SIGKILL)
    _assert_gone(kids, time.monotonic())
    _finish(proc)


@pytest.mark.parametrize("signum", (signal.SIGINT, signal.SIGTERM), ids=lambda s: signal.Signals(s).name)
def test_an_interrupted_pool_is_not_awaited(signum):
    """Ctrl-C or SIGTERM in a ``with worker_pool`` block: the workers are killed, the process exits at once."""
    code = textwrap.dedent("""
        import sys, time
        from symvib.children import Terminated, terminate_as_exception, worker_pool
        try:
            with terminate_as_exception(), worker_pool(1) as pool:
                pool.submit(time.sleep, 600)
                print("ready", flush=True)
                time.sleep(600)
        except (KeyboardInterrupt, Terminated):
            sys.exit(7)
    """)
    proc = _start([sys.executable, "-c", code])
    assert proc.stdout.readline().strip() == "ready"
    kids = _wait_for_children(proc)
    os.kill(proc.pid, signum)
    start = time.monotonic()
    _assert_gone(kids, start)
    code, _ = _finish(proc)
    assert code == 7
    assert time.monotonic() - start < GONE_WITHIN + 5.0


def _scene(folder: Path) -> Path:
    """A scene of a new user curve: its derivation runs budgeted children for seconds."""
    path = folder / "slow.toml"
    path.write_text(textwrap.dedent("""
        name = "slow"
        [curve]
        z = "a*(cosh(x/a) - 1) + x**4/(1 + x**2)"
        [parameters]
        a = 1.0
        [physics]
        mu = 0.1
        restitution = 0.8
        [limiters]
        left = -1
        right = 1
        [initial]
        q = 0
        qdot = 2
    """), encoding="utf-8")
    return path


def _cli_env(tmp_path: Path) -> dict:
    env = dict(os.environ, SYMVIB_CACHE=str(tmp_path / "cache"), MPLBACKEND="Agg")
    env.pop("NUMBA_CACHE_DIR", None)
    return env


@pytest.mark.slow
@pytest.mark.parametrize("target", TARGETS)
@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_symvib_run_leaves_no_process(tmp_path, signum, target):
    scene = _scene(tmp_path)
    proc = _start([sys.executable, "-m", "symvib.cli", "run", str(scene)], env=_cli_env(tmp_path))
    kids = _wait_for_children(proc)
    _signal(proc, signum, target)
    _assert_gone(kids, time.monotonic())
    code, err = _finish(proc)
    if signum == signal.SIGINT and target == "process":
        assert code == children.EXIT_INTERRUPTED
        assert err.strip().splitlines() == ["symvib run: interrupted"], err
    if signum == signal.SIGTERM and target == "process":
        assert code == children.EXIT_TERMINATED
        assert "Traceback" not in err


@pytest.mark.slow
@pytest.mark.parametrize("target", TARGETS)
@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_symvib_paper_leaves_no_process(tmp_path, signum, target):
    proc = _start([sys.executable, "-m", "symvib.cli", "paper", "--out", str(tmp_path / "paper"), "--quiet"],
                  env=_cli_env(tmp_path))
    kids = _wait_for_children(proc, 2)
    _signal(proc, signum, target)
    _assert_gone(kids, time.monotonic())
    code, err = _finish(proc)
    if target == "process" and signum != signal.SIGKILL:
        assert "Traceback" not in err
        assert len(err.strip().splitlines()) == 1, err


def _sigterm_handler_is_default():
    return signal.getsignal(signal.SIGTERM) is signal.SIG_DFL


def test_a_pool_worker_forked_under_terminate_as_exception_ends_quietly_on_sigterm():
    # Forked inside the parent's `terminate_as_exception`, a worker would inherit the handler that
    # raises Terminated, and a SIGTERM from the pool's shutdown would print a traceback there.
    with children.terminate_as_exception():
        with children.worker_pool(1, "fork") as pool:
            assert pool.submit(_sigterm_handler_is_default).result(timeout=HANG_GUARD) is True


#: A command whose signal exception is lost on its way, as an interrupted import of a C extension
#: loses it (``ImportError: initialization failed``; seen under load in ``symvib paper``).
LOST_SIGNAL = textwrap.dedent("""
    import sys, time
    import symvib.paper.report as report
    from symvib.children import worker_pool

    def run_paper(out_dir, **kwargs):
        with worker_pool(1) as pool:
            pool.submit(time.sleep, 600)
            print("ready", flush=True)
            while True:
                try:
                    time.sleep(0.05)
                except BaseException:
                    raise ImportError("initialization failed") from None
    report.run_paper = run_paper
    from symvib.cli import main
    sys.exit(main(["paper", "--out", sys.argv[1], "--quiet"]))
""")

#: A process that swallows the signal's exception and works on inside the block.
SWALLOWED_SIGNAL = textwrap.dedent("""
    import time
    from symvib.children import terminate_as_exception, worker_pool
    with terminate_as_exception("swallower"), worker_pool(1) as pool:
        pool.submit(time.sleep, 600)
        print("ready", flush=True)
        for _ in range(12000):
            try:
                time.sleep(0.05)
            except BaseException:
                pass
""")


@pytest.mark.parametrize("signum", (signal.SIGINT, signal.SIGTERM), ids=lambda s: signal.Signals(s).name)
def test_a_signal_whose_exception_is_lost_still_ends_the_command(tmp_path, signum):
    """The workers die at the signal, and the command reports the signal, not the ImportError it became."""
    proc = _start([sys.executable, "-c", LOST_SIGNAL, str(tmp_path / "paper")], env=_cli_env(tmp_path))
    assert proc.stdout.readline().strip() == "ready"
    kids = _wait_for_children(proc)
    os.kill(proc.pid, signum)
    _assert_gone(kids, time.monotonic())
    code, err = _finish(proc)
    assert code == children.exit_code(signum)
    what = "interrupted" if signum == signal.SIGINT else "terminated"
    assert err.strip().splitlines() == [f"symvib paper: {what}"], err


@pytest.mark.parametrize("signum", (signal.SIGINT, signal.SIGTERM), ids=lambda s: signal.Signals(s).name)
def test_a_swallowed_signal_ends_the_process_after_its_grace(signum):
    """Code that catches the signal's exception and works on: its children die at the signal, and
    the process exits GRACE_SECONDS later with the signal's status and one line."""
    proc = _start([sys.executable, "-c", SWALLOWED_SIGNAL])
    assert proc.stdout.readline().strip() == "ready"
    kids = _wait_for_children(proc)
    os.kill(proc.pid, signum)
    start = time.monotonic()
    _assert_gone(kids, start)
    code, err = _finish(proc)
    waited = time.monotonic() - start
    assert code == children.exit_code(signum)
    what = "interrupted" if signum == signal.SIGINT else "terminated"
    assert err.strip().splitlines() == [f"swallower: {what}"], err
    # (the grace timer, not an earlier exit; a timer may wake a few ms early, so half of it)
    assert children.GRACE_SECONDS / 2 <= waited < children.GRACE_SECONDS + HANG_GUARD / 4


def test_a_forked_worker_owns_none_of_its_parents_children():
    # The registry is copied by fork: a worker interrupted by a Ctrl-C to the group must not kill
    # its parent's other children (it owns none of them).
    with children.worker_pool(1, "fork") as pool:
        assert pool.submit(_owned_count).result(timeout=HANG_GUARD) == 0


def _owned_count():
    return len(children._OWNED)
