"""`fgf transmittance`: placeholder until its issue lands."""

from __future__ import annotations


def register(sub) -> None:
    p = sub.add_parser("transmittance", help="(not yet implemented)")
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import FgfError

    raise FgfError("'fgf transmittance' is not implemented yet")
