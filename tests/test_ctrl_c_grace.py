"""Ctrl-C always ends a command, promptly and quietly.

CI saw a ``demo --workers 2`` given Ctrl-C 0.48 s after its start that did not end within 60 s and printed
nothing (its Ctrl-C had come in code where it waits to be raised, and the command then waited for its
workers, where no call comes to raise it); and, once in 150 local runs, a Ctrl-C that cut a compiler's
engine in half, whose finalizer then printed "Exception ignored ... Traceback" after "cleatfmu: interrupted".
Now:

* a Ctrl-C that waits is retried every 20 ms, so a command blocked in a wait is interrupted;
* a command that has not ended :data:`~identification.cli.signals.GRACE_S` after its first signal (a library
  that swallows the exception) is ended with its output undone, exit 130
  (``tests/test_forced_exit.py``, with SIGTERM's 143);
* finalizers that fail after a signal print nothing (the command's one line stays the last).
"""

import subprocess
import sys
import textwrap

import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="POSIX signals")

_BLOCKED = textwrap.dedent("""
    import sys, threading, time, types
    sys.argv[0] = "-m"
    from identification.cli import command_line as cl, signals as sg

    sg._signalled, sg._ended = 0, False
    # a Ctrl-C that came in the logging module's code (it would drop the exception there): it waits ...
    import logging
    fragile = types.SimpleNamespace(f_code=logging.Logger.isEnabledFor.__code__, f_back=None)
    sg._raise_interrupt(2, fragile)
    lock = threading.Lock()
    lock.acquire()
    t0 = time.monotonic()
    try:        # ... and the command then waits for a lock (its workers' results): no call comes
        got = lock.acquire(timeout=20)
        print("not raised", got, flush=True)
    except KeyboardInterrupt:
        print("raised after %.1f s" % (time.monotonic() - t0), flush=True)
    time.sleep(0.1)     # the retry and the call hook raise it once: nothing comes after
    print("once", flush=True)
""")


def test_a_waiting_ctrl_c_interrupts_a_command_blocked_in_a_wait():
    res = subprocess.run([sys.executable, "-c", _BLOCKED], capture_output=True, text=True, timeout=60)
    assert res.stdout.splitlines() == ["raised after 0.0 s", "once"], (res.stdout, res.stderr)
    assert "Traceback" not in res.stderr, res.stderr


_HALF_BUILT = textwrap.dedent("""
    import os, signal, sys, types
    sys.argv[0] = "-m"
    from identification.cli import command_line as cl

    class Engine:                   # a library's object that a Ctrl-C cut in half as it was built
        def __init__(self):
            os.kill(os.getpid(), signal.SIGINT)
            self.handle = 1
        def __del__(self):
            self.handle             # AttributeError: never set
    def command(args):
        Engine()
        return 0

    class _Parser:
        def parse_known_args(self, argv):
            return types.SimpleNamespace(func=command, trailing=None), []

    cl.build_parser = lambda name=None: _Parser()
    status = cl._main([])           # (``main`` would end the program at once)
    sys.stderr.flush()
    class Later:                    # after the command: the hook it replaced is back
        def __del__(self):
            raise ValueError("after the command")
    Later()
    sys.stderr.flush()
    os._exit(status)
""")


def test_finalizers_that_fail_after_ctrl_c_print_nothing_after_the_commands_line():
    res = subprocess.run([sys.executable, "-c", _HALF_BUILT], capture_output=True, text=True, timeout=60)
    assert res.returncode == 130, res.stderr
    lines = res.stderr.strip().splitlines()
    assert lines[0] == "cleatfmu: interrupted", res.stderr
    assert "AttributeError" not in res.stderr, res.stderr
    assert "ValueError: after the command" in res.stderr, res.stderr
