"""The command line, ``cleatfmu <command> ...``: one thin module per command over the Python API.

:mod:`~identification.cli.command_line` parses the command line and runs the command; each command's module
(``identify``, ``export``, ``simulate``, ``diagnose``, ``report``, ``comfort``, ``ride``, ``static``,
``ssp``, ``rig``) adds its parser and calls the stages below.  Nothing but this package imports it.
"""

from .command_line import EXIT_CLOSED_PIPE, build_parser, main

__all__ = ["main", "build_parser", "EXIT_CLOSED_PIPE"]
