"""`fgf field`: placeholder until its issue lands."""

from __future__ import annotations


def register(sub) -> None:
    p = sub.add_parser("field", help="(not yet implemented)")
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import FgfError

    raise FgfError("'fgf field' is not implemented yet")
