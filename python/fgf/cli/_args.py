"""Argument types shared by every ``fgf`` subcommand.

:func:`harden` walks a finished parser and gives every option a checked
type, so that no value typed on the command line reaches the native module
unchecked: integers get the range of the parameter they feed (a value past
32 or 64 bits is refused in one line, not as an ``OverflowError`` deep in
the binding), output paths must be non-empty and encodable, and ``-D``
values must be UTF-8 (Mitsuba scene files are). Every refusal goes through
argparse, so it is one ``fgf <command>: error: ...`` line with exit code 2.
Options added later by a subcommand get the same treatment without being
listed here: an ``int`` option gets at least the 64-bit range.
"""

from __future__ import annotations

import argparse
import math
from typing import Any, Callable

#: Longest echo of a user value in a message; longer values are cut.
ECHO_MAX = 80

U32_MAX = 2**32 - 1
U64_MAX = 2**64 - 1
I64_MIN, I64_MAX = -(2**63), 2**63 - 1

#: Valid range of each integer option, by option string (any subcommand).
INT_RANGES: dict[str, tuple[int, int]] = {
    "--spp": (1, U32_MAX),
    "--threads": (1, 4096),
    "--realizations": (1, U32_MAX),
    "--resolution": (2, 65536),
    "--rows": (2, 1_000_000),
    "--points": (2, 10_000_000),
    "--shape": (1, 2**62),
    "--seed": (0, U64_MAX),
}

#: Options naming an output file or directory.
PATH_OPTIONS = ("-o", "--output", "--png", "--variance", "--stderr", "--out", "--scene-dir", "--checkpoint")


class OptionError(Exception):
    """A bad option value: :func:`fgf.cli.main` prints it as one line, exit 2.

    Deliberately not a ``ValueError``: argparse would turn that into a
    usage message and drop the reason."""

    def __init__(self, option: str, message: str) -> None:
        super().__init__(f"argument {option}: {message}")


def echo(value: str, limit: int = ECHO_MAX) -> str:
    """``repr(value)``, cut to ``limit`` characters with the length said."""
    if len(value) <= limit:
        return repr(value)
    return f"{value[:limit]!r}... ({len(value)} characters)"


def int_in(lo: int, hi: int) -> Callable[[str], int]:
    """An argparse type: an integer in ``[lo, hi]``."""

    def parse(text: str) -> int:
        try:
            # int() itself refuses more than 4300 digits with a ValueError.
            v = int(text.strip(), 10)
        except ValueError:
            # Not a number at all: argparse's usage message (it is a typo).
            raise argparse.ArgumentTypeError(f"invalid integer {echo(text)} (valid: {lo} to {hi})") from None
        if not lo <= v <= hi:
            shown = str(v) if len(str(v)) <= 24 else f"a {len(str(abs(v)))}-digit integer"
            raise _Bad(f"{shown} is out of range (valid: {lo} to {hi})")
        return v

    parse.__name__ = "integer"
    return parse


def real(text: str) -> float:
    """An argparse type: a float (finiteness is each command's check, which names the range)."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid number {echo(text)}") from None


real.__name__ = "number"


def _encodable(text: str, what: str) -> str:
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        raise _Bad(f"{what} {echo(text)} is not valid UTF-8") from None
    if "\0" in text:
        raise _Bad(f"{what} {echo(text)} contains a NUL character")
    return text


def path(text: str) -> str:
    """An argparse type: a non-empty, UTF-8 file name."""
    if not text:
        raise _Bad("empty file name")
    return _encodable(text, "file name")


path.__name__ = "path"


def define(text: str) -> str:
    """An argparse type: ``NAME=VALUE`` for ``-D``, UTF-8 (echoed values are cut)."""
    _encodable(text, "-D value")
    name, sep, _ = text.partition("=")
    if not sep or not name:
        raise _Bad(f"define {echo(text)}: expected name=value")
    return text


define.__name__ = "define"


class _Bad(Exception):
    """Raised by the types below; :func:`_named` adds the option name."""


def _named(action: argparse.Action, parse: Callable[[str], Any]) -> Callable[[str], Any]:
    option = "/".join(action.option_strings) or action.dest

    def typed(text: str) -> Any:
        try:
            return parse(text)
        except _Bad as e:
            raise OptionError(option, str(e)) from None

    typed.__name__ = getattr(parse, "__name__", "value")
    return typed


def _retype(action: argparse.Action) -> None:
    _retype_plain(action)
    if callable(action.type) and not isinstance(action.type, type):
        action.type = _named(action, action.type)


def _retype_plain(action: argparse.Action) -> None:
    opts = action.option_strings
    if action.type is int:
        lo, hi = next((INT_RANGES[o] for o in opts if o in INT_RANGES), (I64_MIN, I64_MAX))
        action.type = int_in(lo, hi)
    elif action.type is float:
        action.type = real
    elif action.dest == "defines":
        action.type = define
    elif action.type is None and isinstance(action, argparse._StoreAction):
        if any(o in PATH_OPTIONS for o in opts):
            action.type = path
        elif not opts:
            # A positional file (the scene).
            action.type = path


def harden(parser: argparse.ArgumentParser) -> None:
    """Give every option of ``parser`` and of its subcommands a checked type."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            choices: dict[str, Any] = action.choices
            for sub in choices.values():
                harden(sub)
        elif isinstance(action, (argparse._StoreAction, argparse._AppendAction)):
            _retype(action)


def finite(option: str, value: float) -> float:
    """``value`` if finite, else ``fgf.ParameterError`` naming ``option``."""
    from .. import ParameterError

    if not math.isfinite(value):
        raise ParameterError(f"invalid {option} = {value}: must be finite")
    return value
