"""The ``fgf`` command line.

Each subcommand lives in its own module of this package and provides
``register(subparsers)``, which adds its parser and sets ``func`` to a
function ``run(args) -> int``. Errors from fgf (bad parameters, bad scene
files) and from the operating system (missing files, permissions) are
printed as one line ``fgf <command>: error: ...`` with exit code 2; never as
a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys

# Subcommand modules, in the order ``fgf --help`` lists them.
COMMANDS = ["transmittance", "field", "render", "ensemble", "truth", "figures"]


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__

    parser = argparse.ArgumentParser(
        prog="fgf",
        description="Fractional Gaussian fields for modeling and rendering spatially-correlated media.",
    )
    parser.add_argument("--version", action="version", version=f"fgf {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"{__name__}.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from .. import FgfError

    try:
        return int(args.func(args) or 0)
    except FgfError as e:
        print(f"fgf {args.command}: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"fgf {args.command}: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"fgf {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
