"""Options shared by the commands that can run on a Dask cluster (`fgf render`,
`fgf ensemble`, `fgf truth`): ``--cluster``, ``--chunk-spp``, ``--checkpoint``
(``docs/cluster.md``)."""

from __future__ import annotations

import argparse
import contextlib
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, Optional

if TYPE_CHECKING:
    from distributed import Client


def add_cluster_options(p: argparse.ArgumentParser, chunks: bool = True) -> None:
    """``--cluster ADDRESS``, ``--checkpoint FILE`` and (if ``chunks``) ``--chunk-spp K``."""
    p.add_argument(
        "--cluster",
        default=None,
        metavar="ADDRESS",
        help="run on Dask: local[:N] (N worker processes, default one per core) or tcp://host:port "
        "(a running `dask scheduler`); needs pip install 'fgf[cluster]'",
    )
    if chunks:
        p.add_argument(
            "--chunk-spp",
            type=int,
            default=None,
            metavar="K",
            help="samples per pixel per work unit (default: sized so each takes about 2 s); does not change the image",
        )
    p.add_argument(
        "--checkpoint",
        default=None,
        metavar="FILE",
        help="save finished work to FILE as it arrives and resume from it on a rerun with the same arguments",
    )


def check_cluster_options(args: argparse.Namespace) -> None:
    from .. import ParameterError

    k = getattr(args, "chunk_spp", None)
    if k is not None and k < 1:
        raise ParameterError(f"--chunk-spp {k}: need at least 1 sample per pixel per chunk")
    if args.checkpoint is not None:
        folder = Path(args.checkpoint).parent if str(Path(args.checkpoint).parent) else Path(".")
        if not folder.is_dir():
            raise ParameterError(f"--checkpoint {args.checkpoint}: the directory {folder} does not exist")


def wants_chunks(args: argparse.Namespace) -> bool:
    """Whether the run goes through ``fgf.cluster`` (any of the three options given)."""
    return any(getattr(args, n, None) is not None for n in ("cluster", "chunk_spp", "checkpoint"))


@contextlib.contextmanager
def client_for(args: argparse.Namespace) -> Iterator[Optional["Client"]]:
    """The Dask client of ``--cluster`` (``None`` without it), closed on exit."""
    if args.cluster is None:
        yield None
        return
    import logging

    from ..cluster import open_client

    # The command reports a lost scheduler in one line itself: Dask's own
    # tracebacks of its reconnection attempts would only bury it.
    def quiet() -> None:
        for name in ["distributed", *logging.root.manager.loggerDict]:
            if name == "distributed" or name.startswith("distributed."):
                logging.getLogger(name).setLevel(logging.CRITICAL)

    quiet()
    with open_client(args.cluster) as client:
        quiet()  # loggers created while connecting
        yield client


def summary_lost(command: str, lost: Optional[str], written: str, what: str, checkpoint: Optional[str] = None) -> Any:
    """Print the one line for a lost cluster; return exit code 2 (or None if not lost)."""
    import sys

    if lost is None:
        return None
    kept = f" and {checkpoint} (rerun to resume)" if checkpoint else ""
    print(f"fgf {command}: error: {lost}; wrote {what} finished to {written}{kept}", file=sys.stderr)
    return 2
