"""Command-line interface: ``cleatfmu <command> ...``.

Every user error (bad file, bad option value) ends with one line on stderr,
``cleatfmu: error: <file>: <problem>``, and exit status 2; nothing is written
(an output folder created for the run is removed again).  Output folders are
created as needed.  When stdout is a pipe closed before the output is written
(``cleatfmu identify --example | head -1``) the command ends silently with
status 141 (:data:`EXIT_CLOSED_PIPE`).  Every ``--help`` states the options'
defaults (:class:`identification.cli.util.DefaultsHelpFormatter`).
"""

from __future__ import annotations

import argparse
import errno
import importlib
import io
import os
import signal
import sys

from .. import __version__
from .util import OutputFolders, Parser, read_recording_arg
from ..errors import InputError

__all__ = ["main", "build_parser", "EXIT_CLOSED_PIPE", "EXIT_TERMINATED", "Terminated"]

#: Modules that add a sub-command: each has ``add_parser(subparsers)``, which
#: registers the command with ``set_defaults(func=...)``; ``func(args)``
#: returns the exit status and raises InputError for user errors.
_COMMAND_MODULES: list[str] = [".identify", ".rig", ".export", ".simulate", ".diagnose", ".report", ".comfort", ".ride",
                               ".static", ".ssp", ".map", ".seat"]
#: The module of each command: a command line naming one of these loads only its module (the others may
#: import scipy, numba or matplotlib, seconds of start-up an ``export`` does not need).
_COMMAND_MODULE_OF: dict[str, str] = {"identify": ".identify", "rig": ".rig", "export": ".export", "simulate": ".simulate",
                                      "diagnose": ".diagnose", "demo": ".report", "report": ".report",
                                      "comfort": ".comfort", "ride": ".ride", "static": ".static", "ssp": ".ssp", "map": ".map",
                                      "seat": ".seat"}


#: The recording of a command (positional REC.csv or ``--example``); kept under this name for the commands
#: that import it from here.
_recording_arg = read_recording_arg


def _command_of(argv) -> str | None:
    """The command named by `argv` (its first argument, when that is no option), else None."""
    argv = sys.argv[1:] if argv is None else list(argv)
    return argv[0] if argv and not str(argv[0]).startswith("-") else None


def _parts(command: str | None) -> list[str]:
    """The command modules the parser needs for `command`."""
    module = _COMMAND_MODULE_OF.get(command)
    if module is not None and module in _COMMAND_MODULES:
        return [module]
    return list(_COMMAND_MODULES)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser of every command, or only of `command` (if it is a known one).

    Parameters
    ----------
    command : str, optional
        A command name: only its sub-parser is built and only its module imported (the start-up
        time of one command).  None, or an unknown name: every command (``--help`` lists them,
        and a misspelt command gets argparse's list of choices).

    Returns
    -------
    argparse.ArgumentParser
        The parser.
    """
    modules = _parts(command)
    parser = Parser(prog="cleatfmu", description="Tire stiffness and damping from cleat tests, "
                    "exported as FMI 2.0 and 3.0 co-simulation FMUs.")
    parser.add_argument("--version", action="version", version=f"cleatfmu {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in modules:
        importlib.import_module(module, __package__).add_parser(sub)
    return parser


#: Exit status when stdout is closed before the output is written (``cleatfmu ... | head -1``): 128 + SIGPIPE,
#: what a shell reports for a program that a closed pipe stopped.
EXIT_CLOSED_PIPE = 141


def _parse(parser: argparse.ArgumentParser, argv):
    """``parser.parse_args(argv)``; positionals that follow options extend the list named by ``trailing``.

    A command whose positionals are a list (``simulate FMU... REC.csv``) sets the default ``trailing`` to
    that list's name, so that ``simulate FL.fmu --tire FL REC.csv`` reads as ``simulate FL.fmu REC.csv
    --tire FL``; any other argument left over is an error, as with ``parse_args``.
    """
    args, extra = parser.parse_known_args(argv)
    trailing = getattr(args, "trailing", None)
    if extra and trailing and not any(item.startswith("-") for item in extra):
        getattr(args, trailing).extend(extra)
    elif extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    return args


def _flush_stdout() -> None:
    """Flush stdout, so that a closed pipe shows as BrokenPipeError here rather than at interpreter exit."""
    if sys.stdout is not None:
        sys.stdout.flush()


def _stdout_is_a_pipe() -> bool:
    """Whether stdout is a pipe or socket (or cannot be told), i.e. may be what a BrokenPipeError came from."""
    import stat

    try:
        mode = os.fstat(sys.stdout.fileno()).st_mode
    except (AttributeError, OSError, ValueError, io.UnsupportedOperation):
        return True
    return stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)


def _silence_stdout() -> None:
    """Point stdout at the null device: what is still buffered goes nowhere instead of failing at exit."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError, io.UnsupportedOperation):
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, fd)
    finally:
        os.close(devnull)


class Terminated(BaseException):
    """SIGTERM, raised where the command is, so that it unwinds as after Ctrl-C: its output undone
    (:class:`~identification._files.OutputFolders`), its temporary folders removed, its workers stopped."""


#: Exit status after SIGTERM: 128 + 15, what a shell reports for a program SIGTERM stopped.
EXIT_TERMINATED = 143


#: The exit status of a signal that came while the command ran (0: none): a library that catches the
#: exception a signal raised and raises its own (a compiler wrapping it) still ends as that signal's run.
_signalled = 0


#: Seconds a terminated command has to unwind before it is ended where it stands.
TERMINATE_GRACE_S = 10.0

#: The timer of :data:`TERMINATE_GRACE_S` (None: no SIGTERM yet); cancelled once the command has ended.
_grace_timer = None


def _force_exit() -> None:
    """End a terminated run that did not unwind in time (a library that swallowed the exception, or holds a
    lock the unwinding needs): its output under way is undone first, from this timer's thread
    (:func:`identification._files.undo_at_forced_exit`)."""
    try:
        files = sys.modules.get("identification._files")
        if files is not None:
            files.undo_at_forced_exit()
        sys.stderr.write("cleatfmu: terminated\n")
        sys.stderr.flush()
    finally:
        os._exit(EXIT_TERMINATED)


#: Standard-library code where an exception raised by a signal handler is ignored ("Exception ignored in")
#: or leaves a lock held: the logging module's locks (taken around every fork), the import machinery, the
#: abstract base classes' subclass checks (called from C, which drops the exception), the weak references'
#: callbacks (called by the garbage collector, which drops it too).
_FRAGILE = ("logging" + os.sep + "__init__.py", "<frozen importlib", "<frozen abc>", os.sep + "_weakrefset.py",
            os.sep + "weakref.py")
#: Functions whose exceptions the interpreter drops wherever they are defined: finalizers.
_FRAGILE_FUNCTIONS = ("__del__",)


def _in_the_standard_library(frame) -> bool:
    """Whether `frame`, or a frame that called it, runs code in which a signal's exception must not be
    raised (:data:`_FRAGILE`, the fork hooks): a plain function called from the logging module's fork hook
    (a weak set's iterator) is as fragile as the hook."""
    if _forking:
        return True
    while frame is not None:
        code = frame.f_code
        if code in _FORK_HOOKS or code.co_name in _FRAGILE_FUNCTIONS or any(part in code.co_filename
                                                                           for part in _FRAGILE):
            return True
        frame = frame.f_back
    return False


def _raise_now_or_soon(code: int, frame) -> None:
    """Raise the exception of `code` (:class:`Terminated` for 143, KeyboardInterrupt for 130) where the
    command is; in fragile standard-library code (:data:`_FRAGILE`: an exception there is printed as
    "Exception ignored" and dropped, or leaves a lock held) arm a retry 20 ms later instead
    (:func:`_raise_pending`, on SIGALRM)."""
    if _in_the_standard_library(frame):
        if signal.getsignal(signal.SIGALRM) is not _raise_pending:
            signal.signal(signal.SIGALRM, _raise_pending)
        signal.setitimer(signal.ITIMER_REAL, 0.02)
        return
    raise Terminated() if code == EXIT_TERMINATED else KeyboardInterrupt


def _raise_pending(signum, frame):
    """SIGALRM: the retry of a signal that came in fragile code (:func:`_raise_now_or_soon`); nothing once the
    command has ended (:data:`_ended`)."""
    if _signalled and not _ended:
        _raise_now_or_soon(_signalled, frame)


def _raise_terminated(signum, frame):
    """SIGTERM: raise :class:`Terminated` where the command is (or soon, :func:`_raise_now_or_soon`); after
    :data:`TERMINATE_GRACE_S` end the run where it stands.  Once the command has ended (:data:`_ended`) a
    SIGTERM is only remembered."""
    global _signalled, _grace_timer
    if _ended:
        _signalled = _signalled or EXIT_TERMINATED
        return
    if _grace_timer is None:
        import threading

        _grace_timer = threading.Timer(TERMINATE_GRACE_S, _force_exit)
        _grace_timer.daemon = True
        _grace_timer.start()
    _signalled = EXIT_TERMINATED
    _raise_now_or_soon(EXIT_TERMINATED, frame)


def _raise_interrupt(signum, frame):
    """Ctrl-C: raise KeyboardInterrupt where the command is, or, in fragile standard-library code (an import
    lock's callback drops it), at the next call outside it (:func:`_raise_at_the_next_safe_call`); once the
    command has ended (:data:`_ended`), only remember it."""
    global _signalled
    if _ended:
        _signalled = _signalled or 130
        return
    _signalled = 130
    if _in_the_standard_library(frame):
        _raise_at_the_next_safe_call()
        return
    raise KeyboardInterrupt


def _raise_at_the_next_safe_call() -> None:
    """Raise KeyboardInterrupt at the next call or return outside fragile code (:data:`_FRAGILE`), through
    a profile hook of the main thread that removes itself: no timer, no further signal."""
    own = (_raise_interrupt.__code__, _raise_at_the_next_safe_call.__code__)
    pid = os.getpid()

    def hook(frame, event, arg):
        if os.getpid() != pid:      # a child forked meanwhile inherits the hook: the Ctrl-C is not its own
            sys.setprofile(None)
            return
        if event in ("call", "return") and frame.f_code not in own and frame.f_code is not hook.__code__ \
                and not _in_the_standard_library(frame):
            sys.setprofile(None)
            if not _ended:
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
    """End the command's handling of signals: mark it ended (:data:`_ended`), cancel a pending retry of a
    signal and the grace timer, and give SIGTERM its `previous` handler back (Ctrl-C keeps raising nothing: the run is about to
    end with its status)."""
    global _ended, _grace_timer
    _ended = True
    if sys.getprofile() is not None and getattr(sys.getprofile(), "__qualname__", "").startswith(
            "_raise_at_the_next_safe_call"):
        sys.setprofile(None)
    if _grace_timer is not None:
        _grace_timer.cancel()
        _grace_timer = None
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


def _run(argv) -> int:
    parser = build_parser(_command_of(argv))
    try:
        args = _parse(parser, argv)
    except SystemExit:  # --help, --version, a usage error: their output reaches a closed pipe here
        _flush_stdout()
        raise
    from .._files import clear_dead_temp_folders_once

    clear_dead_temp_folders_once()      # what SIGKILLed runs left in $TMPDIR
    try:
        with OutputFolders() as folders:
            status = args.func(args)
            if _signalled:      # a signal whose exception some library swallowed: the run still ends as its
                raise Terminated() if _signalled == EXIT_TERMINATED else KeyboardInterrupt   # (output undone)
            _flush_stdout()
            if status:              # a failed command keeps what it wrote (a report of the readable
                folders.keep()      # recordings), only the folders it made and left empty go
                folders.remove()
        return status
    except InputError as exc:
        print(f"cleatfmu: error: {exc.one_line()}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("cleatfmu: interrupted", file=sys.stderr)
        return 130
    except Terminated:
        print("cleatfmu: terminated", file=sys.stderr)
        return EXIT_TERMINATED
    except BrokenPipeError:
        raise
    except OSError as exc:
        # a file name the system refuses (too long), or stdout that cannot take the result (a full disk,
        # /dev/full): one line, exit 2, as for any output that cannot be written; anything else is a bug
        if exc.filename is not None and exc.errno in (errno.ENAMETOOLONG, errno.ELOOP):
            print(f"cleatfmu: error: {exc.filename}: {exc.strerror}", file=sys.stderr)
            return 2
        if exc.filename is None and exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EIO, errno.EFBIG,
                                                 errno.EBADF):
            _silence_stdout()
            print(f"cleatfmu: error: stdout: cannot write: {exc.strerror}", file=sys.stderr)
            return 2
        raise


def main(argv=None) -> int:
    """Run the CLI; returns the exit status (:func:`_main`).

    Run as the program (``cleatfmu``, ``python -m identification.cli``), an interrupted or terminated
    command ends the process at once with 130 or 143 once its own clean-up is done (its output undone, its
    workers stopped): the interpreter's shutdown would otherwise wait for the threads of a worker pool whose
    workers were killed (seen: a ``diagnose --workers 2`` stopped by Ctrl-C hung after "interrupted"), and
    re-raise a Ctrl-C that came during the imports as status -2.
    """
    try:
        status = _main(argv)
    except KeyboardInterrupt:           # a second signal while the first one's line was printed
        status = 130
    except Terminated:
        status = EXIT_TERMINATED
    if status in (130, EXIT_TERMINATED):
        import identification

        if identification._AS_PROGRAM:
            _end_now(status)
    return status


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


def _escape_unprintable_output() -> None:
    """Write what the output's encoding cannot hold (a lone surrogate of a file name not in UTF-8) as an escape
    instead of failing with UnicodeEncodeError after the work is done."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.reconfigure(errors="backslashreplace")
        except (AttributeError, ValueError, io.UnsupportedOperation):
            pass


def _end_now(status: int) -> None:
    """Flush what was written and end the process with `status`, skipping the interpreter's shutdown."""
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(status)


def _main(argv=None) -> int:
    """Run the CLI; returns the exit status.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 on success; 2 for a user error (one line on stderr, nothing written); 130 when interrupted
        (Ctrl-C) and :data:`EXIT_TERMINATED` (143) after SIGTERM, with the output undone;
        :data:`EXIT_CLOSED_PIPE` (141), silently, when stdout is a pipe closed before the output was
        written (``cleatfmu identify --example | head -1``).
    """
    if sys.stdout is None:     # started with stdout closed (``>&-``): every result would be lost
        print("cleatfmu: error: stdout: closed (the result would be lost); redirect it to a file or a pipe",
              file=sys.stderr)
        return 2
    global _signalled, _ended
    _signalled, _ended = 0, False
    _escape_unprintable_output()
    _hold_signals_while_forking()
    previous = None
    try:
        previous = _previous_sigterm()
        if previous is not None:
            signal.signal(signal.SIGTERM, _raise_terminated)
        _answer_early_interrupt()
        return _run(argv)
    except BrokenPipeError:
        if not _stdout_is_a_pipe():
            raise
        _silence_stdout()
        return EXIT_CLOSED_PIPE
    except KeyboardInterrupt:      # before the command ran (its imports): nothing was written
        print("cleatfmu: interrupted", file=sys.stderr)
        return 130
    except Terminated:
        print("cleatfmu: terminated", file=sys.stderr)
        return EXIT_TERMINATED
    except Exception:
        if not _signalled:
            raise
        print("cleatfmu: " + ("terminated" if _signalled == EXIT_TERMINATED else "interrupted"), file=sys.stderr)
        return _signalled
    finally:
        _ended = True           # (set here, before a call gives a pending signal the chance to run)
        _restore_signals(previous)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
