"""The ``fgf`` command line.

Each subcommand lives in its own module of this package and provides
``register(subparsers)``, which adds its parser and sets ``func`` to a
function ``run(args) -> int``. Errors from fgf (bad parameters, bad scene
files) and from the operating system (missing files, permissions) are
printed as one line ``fgf <command>: error: ...`` with exit code 2; never as
a traceback. Ctrl-C at any stage (imports, argument parsing, scene loading,
rendering, writing) exits with code 130 and one line: the package installs
an exit-on-SIGINT handler before its heavy imports when it is run as the
``fgf`` command (see ``fgf/__init__.py``), and :func:`main` hands SIGINT
back to Python's ``KeyboardInterrupt`` once it is ready to catch it. Once
the command's outcome is known, Ctrl-C no longer changes it: the process
exits with the command's own code.
"""

from __future__ import annotations

import argparse
import importlib
import signal
import sys

# Subcommand modules, in the order ``fgf --help`` lists them.
COMMANDS = ["transmittance", "field", "render", "ensemble", "truth", "figures"]


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__, _core

    parser = argparse.ArgumentParser(
        prog="fgf",
        description="Fractional Gaussian fields for modeling and rendering spatially-correlated media.",
    )
    parser.add_argument("--version", action="version", version=f"fgf {__version__} ({_core.simd})")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"{__name__}.{name}").register(sub)
    from ._args import harden

    harden(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line ``argv`` (default: the process's own) and return
    its exit code. Without ``argv`` this is the ``fgf`` process itself: once
    the command's outcome is known, Ctrl-C is ignored, so that an interrupt
    while the message is printed or the interpreter shuts down cannot turn
    the exit code into death by the signal."""
    command = "fgf"
    try:
        # From here on Ctrl-C is a KeyboardInterrupt, caught below; the
        # native module polls for it during long jobs.
        if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        from ._args import OptionError

        parser = build_parser()
        message = None
        try:
            args = parser.parse_args(argv)
        except OptionError as e:
            words = sys.argv[1:] if argv is None else argv
            sub = next((w for w in words if w in COMMANDS), None)
            code, message = 2, f"fgf{' ' + sub if sub else ''}: error: {e}"
        else:
            command = f"fgf {args.command}"
            from .. import FgfError

            try:
                code = int(args.func(args) or 0)
            except (FgfError, OSError) as e:
                code, message = 2, f"{command}: error: {_one_line(str(e))}"
        if argv is None:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        if message is not None:
            print(message, file=sys.stderr)
        return code
    except KeyboardInterrupt:
        if argv is None:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        print(f"{command}: interrupted", file=sys.stderr)
        return 130


def _one_line(message: str, limit: int = 2000) -> str:
    """The message on one line, cut to ``limit`` characters."""
    message = " ".join(message.split("\n"))
    if len(message) > limit:
        message = f"{message[:limit]}... ({len(message)} characters)"
    return message


if __name__ == "__main__":
    sys.exit(main())
