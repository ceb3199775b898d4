"""`fgf render`: placeholder until its issue lands."""

from __future__ import annotations


def register(sub) -> None:
    p = sub.add_parser("render", help="(not yet implemented)")
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import FgfError

    raise FgfError("'fgf render' is not implemented yet")
