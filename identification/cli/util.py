"""Helpers shared by the command-line commands: argument checks (one-line InputErrors), output folders, help.

Output folders
--------------
A command may write into folders that do not exist yet: :func:`check_output`
(or :func:`make_folders`) creates the missing ones.  :func:`identification.cli.main`
runs every command inside an :class:`OutputFolders` block, which removes again
the folders created for a command that fails (raises, or returns a non-zero
status), so that a failed run leaves nothing behind.  Only empty folders are
removed: a file that a successful write put there (e.g. by another run) stays.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from .._files import OutputFolders, check_folder, make_folders
from ..errors import InputError

__all__ = ["announce_compilation", "choose_tire", "normalize_tire", "check_output", "check_folder", "make_folders", "OutputFolders",
           "write_files", "add_example_option", "read_recording_arg", "DefaultsHelpFormatter", "Parser"]

#: The tire names of a cleat recording (:data:`identification.recording.TIRES`, repeated here so that the
#: argument helpers import no numpy).
_TIRES = ("FL", "FR", "RL", "RR")


# ----------------------------------------------------------------------------- tires

def announce_compilation() -> None:
    """Say on stderr, before a command steps the model, that its compiled code is built first (once per
    version of the package: a first run takes some seconds longer, and nothing else would say why)."""
    import sys

    from .._compile import user_cache_dir
    from ..model.kernels import compiled_on_disk
    if not compiled_on_disk():
        print(f"cleatfmu: compiling the model's stepping code for this version (once, about 5-10 s; kept in "
              f"{user_cache_dir()})...", file=sys.stderr, flush=True)


def normalize_tire(name: str) -> str:
    """A tire name as the recordings spell it: ``"fl"`` -> ``"FL"`` (surrounding blanks dropped)."""
    return str(name).strip().upper()


def choose_tire(rec, tire: str | None) -> str:
    """The channel to work on: the one given (any letter case), or the recording's only one.

    Parameters
    ----------
    rec : Recording
        The recording.
    tire : str, optional
        The tire named on the command line (``FL`` or ``fl``); None: the recording must hold one channel.

    Returns
    -------
    str
        The channel name, as the recording spells it.

    Raises
    ------
    InputError
        No tire given for a recording of several channels, or a tire the recording does not hold.
    """
    if tire is None:
        if len(rec.tires) != 1:
            raise InputError(rec.source, f"holds channels {', '.join(rec.tires)}; choose one with --tire")
        return rec.tires[0]
    name = normalize_tire(tire)
    if name not in rec.accel_m_s2:
        raise InputError(rec.source, f"tire {name} is not in the recording (channels: {', '.join(rec.tires)})")
    return name


# ----------------------------------------------------------------------------- recordings

def add_example_option(parser, *, bare: bool = True) -> None:
    """Add ``--example NAME``: an embedded recording instead of the positional REC.csv.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's parser (its positional ``recording`` is optional, ``nargs="?"``).
    bare : bool
        Whether ``--example`` alone means the 7 km/h recording (not for a command whose positionals
        could be taken for the example's name).
    """
    from ..recording.examples import EXAMPLES

    names = ", ".join(EXAMPLES)
    if bare:
        parser.add_argument("--example", nargs="?", const="7kmh", metavar="NAME",
                            help=f"use an embedded recording instead of REC.csv ({names}; '--example' "
                                 f"alone: 7kmh)")
    else:
        parser.add_argument("--example", metavar="NAME",
                            help=f"use an embedded recording instead of REC.csv ({names})")


def recording_name_arg(args) -> str | None:
    """The name (file name without ``.csv``) of the recording a command was given, without reading it:
    to pick that recording's files where a folder or a report summary holds several; None if unknown."""
    from pathlib import Path

    from ..recording.examples import example_path

    if getattr(args, "example", None) is not None:
        try:
            return example_path(args.example).stem
        except InputError:            # an unknown example: refused when the recording is read
            return None
    return Path(args.recording).stem if getattr(args, "recording", None) is not None else None


def read_recording_arg(args):
    """The recording of a command: the positional ``args.recording`` or ``args.example``, exactly one of them.

    Raises
    ------
    InputError
        Both or neither given, an unknown example, or an unreadable recording.

    A command whose ``--cutoff-hz`` was not given gets :func:`identification.recording.preprocess.default_cutoff_hz`
    of the recording's sampling rate in ``args.cutoff_hz``.
    """
    from ..recording.examples import example_path
    from ..recording.preprocess import default_cutoff_hz
    from ..recording import read_recording

    if args.example is not None:
        if args.recording is not None:
            raise InputError("--example", "give either a recording or --example, not both")
        rec = read_recording(example_path(args.example))
    elif args.recording is None:
        raise InputError(None, "no recording given (a REC.csv path, or --example NAME)")
    else:
        rec = read_recording(args.recording)
    if hasattr(args, "cutoff_hz") and args.cutoff_hz is None:
        args.cutoff_hz = default_cutoff_hz(rec.sample_rate_hz)
    return rec


def check_output(path, suffix: str, what: str, *, create: bool = True) -> None:
    """Check an output file name; create its folder if missing.

    Call it once the command's other arguments are checked: a folder it creates
    is removed again only if the command then fails inside an
    :class:`OutputFolders` block (as every ``cleatfmu`` command runs).

    Parameters
    ----------
    path : path-like or None
        The output file (None: nothing to check).
    suffix : str
        Its required suffix, e.g. ``".png"`` (any letter case).
    what : str
        What the file is, for the message ("plot").
    create : bool
        False: only check (the folder is created later, with :func:`make_folders`).

    Raises
    ------
    InputError
        Wrong suffix, an existing directory of that name, or a folder that cannot be created.
    """
    if path is None:
        return
    if not str(path).lower().endswith(suffix):
        raise InputError(path, f"the {what} file name must end with {suffix}")
    if os.path.isdir(path):
        raise InputError(path, f"is a directory (give a {suffix} file name)")
    folder = Path(path).parent
    if create:
        make_folders(folder)
    else:
        check_folder(folder)


def write_files(files) -> list[Path]:
    """Write ``{path: bytes}`` all-or-nothing (atomically), creating missing folders; return the paths.

    Raises
    ------
    InputError
        A file or folder cannot be written (naming it).
    """
    from .._files import atomic_write_bytes

    files = {Path(p): data for p, data in files.items()}
    for path in files:
        make_folders(path.parent)
    try:
        atomic_write_bytes(files)
    except OSError as exc:
        where = Path(exc.filename).parent if exc.filename else next(iter(files), None)
        raise InputError(where, f"cannot write: {exc.strerror or exc}") from None
    return list(files)


# ----------------------------------------------------------------------------- help

class DefaultsHelpFormatter(argparse.HelpFormatter):
    """Help that states every option's default: ``(default: X)`` is added where the help does not say it.

    Nothing is added for a default of None or False (an option that is off unless given), nor where
    the help already mentions a default.
    """

    def _get_help_string(self, action):
        text = action.help or ""
        default = action.default
        if (default is None or default is False or default is argparse.SUPPRESS or "default" in text.lower()
                or not (action.option_strings or action.nargs in (argparse.OPTIONAL, argparse.ZERO_OR_MORE))):
            return text
        return f"{text} (default: %(default)s)" if text else "default: %(default)s"


class Parser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` whose help states defaults (:class:`DefaultsHelpFormatter`).

    Sub-command parsers made by its ``add_subparsers`` are of this class too.
    """

    def __init__(self, *args, formatter_class=DefaultsHelpFormatter, **kwargs):
        super().__init__(*args, formatter_class=formatter_class, **kwargs)

    def error(self, message):
        """A usage error in one line, ``cleatfmu: error: <option>: <problem>`` (``--help`` shows the usage),
        exit status 2."""
        text = " ".join(str(message).split())
        if text.startswith("argument "):
            option, _, problem = text[len("argument "):].partition(": ")
            text = f"{option.split('/')[-1]}: {problem}" if problem else text
        self.exit(2, f"cleatfmu: error: {text}\n")
