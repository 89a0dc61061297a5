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

from .. import __version__, _files
from . import signals
from .signals import EXIT_TERMINATED, Terminated
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
            if signals._signalled:  # a signal whose exception some library swallowed: the run still ends as
                raise Terminated() if signals._signalled == EXIT_TERMINATED else KeyboardInterrupt  # its (undone)
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
    signals._signalled, signals._ended, signals._command_pid = 0, False, os.getpid()
    signals._watch_the_command()
    _escape_unprintable_output()
    signals._hold_signals_while_forking()
    previous = None
    folders = _files.note_temp_folders()    # (its own, made before this command: a notebook's, a test's)
    unraisable = sys.unraisablehook
    sys.unraisablehook = _quiet_after_a_signal(unraisable)
    try:
        previous = signals._previous_sigterm()
        if previous is not None:
            signal.signal(signal.SIGTERM, signals._raise_terminated)
        signals._answer_early_interrupt()
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
        if not signals._signalled:
            raise
        print("cleatfmu: " + ("terminated" if signals._signalled == EXIT_TERMINATED else "interrupted"),
              file=sys.stderr)
        return signals._signalled
    finally:
        signals._ended = True   # (set here, before a call gives a pending signal the chance to run)
        signals._restore_signals(previous)
        _files.remove_open_temporaries()    # a signal between a temporary's creation and its writer's try
        _files.remove_temp_folders(_files.own_temp_folders() - folders)     # and a folder's and its owner's
        if signals._signalled:
            import gc

            gc.collect()    # what the signal cut in half is finalized now, while its noise is dropped
        sys.unraisablehook = unraisable


def _quiet_after_a_signal(previous):
    """An unraisable-exception hook that drops what comes once a signal has stopped the command and passes
    the rest to `previous`: an object a Ctrl-C cut in half as a library built it (seen: numba's compiler
    engine, whose finalizer then fails with AttributeError) would print "Exception ignored ... Traceback"
    after the command's one line."""
    def hook(unraisable):
        if not signals._signalled:
            previous(unraisable)
    return hook


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
