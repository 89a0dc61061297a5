"""Signals during a command: Ctrl-C (SIGINT) and SIGTERM.

Each ends the command where it is, by an exception (KeyboardInterrupt, :class:`Terminated`) that unwinds
it as an error would: its output undone (:class:`~identification._files.OutputFolders`), its temporary
folders removed, its workers stopped; the command line then prints one line and ends with 130 or 143.

Where such an exception would be dropped or printed as "Exception ignored" (the logging module's fork
hooks, the import machinery's own frames, finalizers and weak references' callbacks: :data:`_FRAGILE`,
:data:`_DROPPING`), or where a library is importing itself (a compiled module's initialisation that
prints the exception of an import it makes, and leaves the library half imported: seen with numba), it waits:
SIGTERM is raised again 20 ms later, Ctrl-C at the next Python call outside that code.  While the process
forks (its worker pool) both are held; a Ctrl-C that waits is also retried every 20 ms, so that a command
blocked in a wait meanwhile (for its workers' results) is not left waiting.  A signal the command does not
answer within :data:`GRACE_S` ends the process with its output undone (:func:`_force_exit`).
"""

from __future__ import annotations

import os
import signal
import sys
import time

__all__ = ["Terminated", "EXIT_TERMINATED"]

class Terminated(BaseException):
    """SIGTERM, raised where the command is, so that it unwinds as after Ctrl-C: its output undone
    (:class:`~identification._files.OutputFolders`), its temporary folders removed, its workers stopped."""


#: Exit status after SIGTERM: 128 + 15, what a shell reports for a program SIGTERM stopped.
EXIT_TERMINATED = 143


#: The exit status of a signal that came while the command ran (0: none): a library that catches the
#: exception a signal raised and raises its own (a compiler wrapping it) still ends as that signal's run.
_signalled = 0


#: Seconds an interrupted or terminated command has to unwind before it is ended where it stands.
GRACE_S = 10.0

#: When the command's first signal came (``time.monotonic()``; None: none yet), for :func:`_watch`.
_signal_at = None

#: The number of the command under way (a watch of an earlier command in this process ends).
_command_serial = 0

#: The process that runs the command (a worker forked from it that gets a signal before its own handling
#: is set up starts no grace of its own).
_command_pid = None

#: Whether a Ctrl-C waits to be raised (:func:`_raise_at_the_next_safe_call` and its retry on SIGALRM;
#: whichever raises it first clears this, and the other then raises nothing).
_interrupt_waiting = False


def _force_exit() -> None:
    """End an interrupted or terminated run that did not unwind in time (a library that swallowed the
    exception, holds a lock the unwinding needs, or waits where nothing raises): its output under way is
    undone first, from this timer's thread (:func:`identification._files.undo_at_forced_exit`); exit 130
    after Ctrl-C, 143 after SIGTERM."""
    status = EXIT_TERMINATED if _signalled != 130 else 130
    try:
        files = sys.modules.get("identification._files")
        if files is not None:
            files.undo_at_forced_exit()
        sys.stderr.write("cleatfmu: " + ("interrupted" if status == 130 else "terminated") + "\n")
        sys.stderr.flush()
    finally:
        os._exit(status)


def _watch_the_command() -> None:
    """Watch the command that starts now in a thread of its own (:func:`_watch`), which ends with it.

    Started beforehand rather than from a signal's handler: a thread started there would wait forever for
    the lock of the threads' table if the signal came as the command started a thread of its own."""
    global _command_serial, _signal_at
    import threading

    _command_serial += 1
    _signal_at = None
    threading.Thread(target=_watch, args=(_command_serial,), name="cleatfmu-grace", daemon=True).start()


def _watch(serial: int) -> None:
    """End the command `serial` where it stands (:func:`_force_exit`) once :data:`GRACE_S` have passed since
    its first signal without its end; return when it has ended."""
    while serial == _command_serial and not _ended:
        at = _signal_at
        if at is not None and time.monotonic() - at > GRACE_S:
            _force_exit()
        time.sleep(0.05)


def _start_the_grace() -> None:
    """The command's first signal: from now it has :data:`GRACE_S` to unwind (:func:`_watch`).  Lock-free
    (a handler); a worker forked from the command that gets a signal before its own handling is set up
    changes nothing."""
    global _signal_at
    if _signal_at is None and os.getpid() == _command_pid:
        _signal_at = time.monotonic()


#: Standard-library code where an exception raised by a signal handler is ignored ("Exception ignored in")
#: or leaves a lock held: the import machinery's own frames (an import lock's callback drops it) and the
#: abstract base classes' subclass checks (called from C, which drops it).  Only the frame the signal came
#: in counts: an exception raised in a module being imported ends the import as any error does.
_FRAGILE = ("<frozen importlib", "<frozen abc>")
#: Code whose exceptions are dropped with everything it calls: the logging module (its fork hooks take and
#: re-create its locks around every fork), the weak references' callbacks (called by the garbage
#: collector), finalizers (``__del__``) and this module's fork hooks (:data:`_FORK_HOOKS`).  A signal in
#: anything they call waits too (seen: a weak set's iterator called from the logging module's child hook).
_DROPPING = ("logging" + os.sep + "__init__.py", os.sep + "_weakrefset.py", os.sep + "weakref.py")
_DROPPING_FUNCTIONS = ("__del__",)
#: Steps a signal's exception must not cut in two: making a temporary file and recording it for removal
#: (:func:`identification._files.temp_beside`; cut between the two, the file would stay).  A signal there
#: waits until the step has returned.  (file name, function name)
_WHOLE_STEPS = ((os.sep + "_files.py", "temp_beside"),)


#: This package's folder: a module of it being imported is the program's own code (a signal is raised there).
_PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep


def _in_the_standard_library(frame) -> bool:
    """Whether a signal's exception must not be raised in `frame`: fragile code (:data:`_FRAGILE`) there,
    code that drops exceptions (:data:`_DROPPING`) there or among its callers, or a library importing
    itself (the innermost module body being imported is a library's: :func:`_imported_body`)."""
    if _forking:
        return True
    if frame is not None and any(part in frame.f_code.co_filename for part in _FRAGILE):
        return True
    library_import = None       # (decided by the innermost module body being imported)
    while frame is not None:
        code = frame.f_code
        if code in _FORK_HOOKS or code.co_name in _DROPPING_FUNCTIONS or any(part in code.co_filename
                                                                           for part in _DROPPING):
            return True
        if any(code.co_name == name and code.co_filename.endswith(file) for file, name in _WHOLE_STEPS):
            return True
        if library_import is None and _imported_body(frame):
            library_import = _a_library(frame)
        frame = frame.f_back
    return bool(library_import)


def _imported_body(frame) -> bool:
    """Whether `frame` runs the body of a module being imported."""
    return frame.f_code.co_name == "<module>" and frame.f_back is not None \
        and "<frozen importlib" in frame.f_back.f_code.co_filename


def _a_library(frame) -> bool:
    """Whether `frame` runs code outside this package (:data:`_PACKAGE`)."""
    return not os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE)


def _outermost_library_import(frame):
    """The outermost frame among `frame` and its callers that runs a library's module body being imported
    (None: no library is importing itself): a Ctrl-C that came beneath it waits until it has returned."""
    found = None
    while frame is not None:
        if _imported_body(frame) and _a_library(frame):
            found = frame
        frame = frame.f_back
    return found


def _raise_now_or_soon(code: int, frame) -> None:
    """Raise the exception of `code` (:class:`Terminated` for 143, KeyboardInterrupt for 130) where the
    command is; in fragile standard-library code (:data:`_FRAGILE`: an exception there is printed as
    "Exception ignored" and dropped, or leaves a lock held) arm a retry 20 ms later instead
    (:func:`_raise_pending`, on SIGALRM)."""
    if _in_the_standard_library(frame):
        _retry_soon()
        return
    if code != EXIT_TERMINATED:
        _stop_waiting()
    raise Terminated() if code == EXIT_TERMINATED else KeyboardInterrupt


def _retry_soon() -> None:
    """Arm the retry of a waiting signal 20 ms from now (:func:`_raise_pending`, on SIGALRM)."""
    if signal.getsignal(signal.SIGALRM) is not _raise_pending:
        signal.signal(signal.SIGALRM, _raise_pending)
    signal.setitimer(signal.ITIMER_REAL, 0.02)


def _raise_pending(signum, frame):
    """SIGALRM: the retry of a signal that came in fragile code (:func:`_raise_now_or_soon`); nothing once the
    command has ended (:data:`_ended`), nor for a waiting Ctrl-C raised meanwhile at a call."""
    if not _signalled or _ended or (_signalled == 130 and not _interrupt_waiting):
        return
    _raise_now_or_soon(_signalled, frame)


def _stop_waiting() -> None:
    """A waiting Ctrl-C is being raised: its other way of being raised is dropped (the profile hook of
    :func:`_raise_at_the_next_safe_call`; a retry still armed then finds nothing to do)."""
    global _interrupt_waiting
    _interrupt_waiting = False
    hook = sys.getprofile()
    if hook is not None and getattr(hook, "__qualname__", "").startswith("_raise_at_the_next_safe_call"):
        sys.setprofile(None)


def _raise_terminated(signum, frame):
    """SIGTERM: raise :class:`Terminated` where the command is (or soon, :func:`_raise_now_or_soon`); after
    :data:`GRACE_S` end the run where it stands.  Once the command has ended (:data:`_ended`) a
    SIGTERM is only remembered."""
    global _signalled
    if _ended:
        _signalled = _signalled or EXIT_TERMINATED
        return
    _start_the_grace()
    _signalled = EXIT_TERMINATED
    _raise_now_or_soon(EXIT_TERMINATED, frame)


def _raise_interrupt(signum, frame):
    """Ctrl-C: raise KeyboardInterrupt where the command is, or, in fragile standard-library code (an import
    lock's callback drops it), at the next call outside it (:func:`_raise_at_the_next_safe_call`) or, where
    no call comes (the command blocked in a wait), at a retry 20 ms later outside it; after :data:`GRACE_S`
    end the run where it stands.  Once the command has ended (:data:`_ended`), only remember it."""
    global _signalled, _interrupt_waiting
    if _ended:
        _signalled = _signalled or 130
        return
    _start_the_grace()
    _signalled = 130
    if _in_the_standard_library(frame):
        _interrupt_waiting = True
        _retry_soon()                           # (first: the hook would take its calls for the command's)
        _raise_at_the_next_safe_call(frame)
        return
    _stop_waiting()
    raise KeyboardInterrupt


def _raise_at_the_next_safe_call(frame=None) -> None:
    """Raise KeyboardInterrupt at the next call or return outside fragile code (:data:`_FRAGILE`), through
    a profile hook of the main thread that removes itself: no timer, no further signal.  Beneath a library
    importing itself (:func:`_outermost_library_import` of `frame`, the frame the signal came in) it looks
    no further until that import has returned (a check of the whole stack at every call of a library's
    import made scipy's take 30 s)."""
    own = (_raise_interrupt.__code__, _raise_at_the_next_safe_call.__code__)
    pid = os.getpid()
    barrier = [_outermost_library_import(frame)]

    def hook(frame, event, arg):
        if os.getpid() != pid:      # a child forked meanwhile inherits the hook: the Ctrl-C is not its own
            sys.setprofile(None)
            return
        if barrier[0] is not None:
            if event == "return" and frame is barrier[0]:
                barrier[0] = None
            return
        if event in ("call", "return") and frame.f_code not in own and frame.f_code is not hook.__code__ \
                and not _in_the_standard_library(frame):
            sys.setprofile(None)
            if not _ended and _interrupt_waiting:
                _stop_waiting()
                raise KeyboardInterrupt
    sys.setprofile(hook)


#: Whether the command has ended (its outcome decided, its clean-up done): a signal from here on raises
#: nothing, which could only escape as a traceback from the command line's own code.
_ended = False


def _previous_sigterm():
    """SIGTERM's handler before the command (the default where :mod:`identification` deferred it during the
    imports), or None where the command cannot set its own (not the main thread: a notebook's worker)."""
    import threading

    import identification

    if threading.current_thread() is not threading.main_thread():
        return None
    previous = signal.getsignal(signal.SIGTERM)
    if previous is identification._defer_interrupt or previous is None:
        return signal.SIG_DFL
    return previous


def _restore_signals(previous) -> None:
    """End the command's handling of signals: mark it ended (:data:`_ended`; its watch, :func:`_watch`,
    ends), drop a waiting Ctrl-C and a pending retry of a signal, and give SIGTERM its `previous` handler
    back (Ctrl-C keeps raising nothing: the run is about to end with its status)."""
    global _ended
    _ended = True
    _stop_waiting()
    if previous is None:
        return
    signal.setitimer(signal.ITIMER_REAL, 0)
    if signal.getsignal(signal.SIGALRM) is _raise_pending:
        signal.signal(signal.SIGALRM, signal.SIG_IGN)       # drops a retry already pending
        signal.signal(signal.SIGALRM, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, previous)


def _answer_early_interrupt() -> None:
    """Ctrl-C from here on raises KeyboardInterrupt (SIGTERM :class:`Terminated`, :func:`_previous_sigterm`); one
    that came while the program's modules were imported (:mod:`identification` defers both when it is the
    program) is raised now."""
    import identification

    if signal.getsignal(signal.SIGINT) is identification._defer_interrupt:
        signal.signal(signal.SIGINT, _raise_interrupt)
    early, identification._interrupted = identification._interrupted, 0
    if early == signal.SIGINT:
        raise KeyboardInterrupt
    if early == signal.SIGTERM:
        raise Terminated()


_FORK_GUARD = False
#: Whether this process is inside a fork (between its hooks): a signal's exception waits as in fragile code.
_forking = False
#: The code of the fork hooks: a signal whose handler runs in them (as the mask is restored) is deferred.
_FORK_HOOKS: set = set()


def _hold_signals_while_forking() -> None:
    """Block SIGINT, SIGTERM (and SIGTERM's retry, SIGALRM) in a thread that forks until the fork is done, in
    parent and child (once per process); a signal the restored mask lets through inside the hook is deferred
    there like one in fragile code.  The fork hooks of the standard library (the logging module's locks) run inside the fork: an
    exception a signal raised there is printed as "Exception ignored" and dropped (seen: Ctrl-C as a report
    started its worker processes).  Held, the signal comes just after the fork, where the command is."""
    global _FORK_GUARD
    if _FORK_GUARD or not hasattr(os, "register_at_fork") or not hasattr(signal, "pthread_sigmask"):
        return
    _FORK_GUARD = True
    held = {signal.SIGINT, signal.SIGTERM, signal.SIGALRM}      # (SIGALRM: SIGTERM's retry)
    saved: list = []

    def before():
        global _forking
        _forking = True
        saved.append(signal.pthread_sigmask(signal.SIG_BLOCK, held))

    def after():
        global _forking
        try:
            if saved:       # (a signal held meanwhile runs its handler in here, which defers it: _forking)
                signal.pthread_sigmask(signal.SIG_SETMASK, saved.pop())
        finally:
            _forking = False

    # hooks run before a fork in the reverse order of registration, after it in the order: registered after
    # the logging module's (imported here first), these block first and unblock last
    import logging  # noqa: F401
    os.register_at_fork(before=before, after_in_parent=after, after_in_child=after)
    _FORK_HOOKS.update((before.__code__, after.__code__))      # a signal let through there waits (fragile)
