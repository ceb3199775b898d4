"""Property test of the CLI's argument layer: random integers, floats and
strings in every option of every subcommand end with exit code 0 or 2 (130
for an interrupt), never a traceback.

The options are read from the real parser, so options added later are
fuzzed too. The work behind a command is kept tiny: the native entry points
get the caller's arguments checked as usual, but at most 2 samples per pixel,
2 realizations and small grids (a legitimately huge request would be slow,
not wrong); ``fgf figures`` stops after its argument checks.
"""

from __future__ import annotations

import argparse
import contextlib
import io
from pathlib import Path
from typing import Any

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import fgf  # noqa: E402
from fgf import _core, cli  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
SCENE = str(REPO / "scenes" / "reference" / "cube-homogeneous.xml")
FGF_SCENE = str(REPO / "scenes" / "fgf-cube-pink.xml")
KFBM_SCENE = str(REPO / "scenes" / "fgf-cube-2fbm.xml")


def _options() -> dict[str, list[argparse.Action]]:
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {name: [a for a in p._actions if a.option_strings and a.dest != "help"] for name, p in sub.choices.items()}


OPTIONS = _options()

ints = st.one_of(st.integers(-5, 70), st.integers(-(2**70), 2**70)).map(str)
floats = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.floats(-10, 10)).map(repr)
texts = st.one_of(
    st.text(max_size=12),
    st.sampled_from(["", "-", "nan", "inf", "1e400", "0x10", "1,2,3", "a=b", "res=4", "9" * 50, "x.exr", "x.png"]),
)


def _value(draw: Any, action: argparse.Action, tmp: Path) -> list[str]:
    if action.nargs == 0:
        return []
    kind = draw(st.sampled_from(["int", "float", "text", "path"]))
    if action.dest == "defines" and draw(st.booleans()):
        # Half the -D values are well formed, so that adding options does
        # not push most examples into argparse's usage errors.
        v = draw(st.sampled_from(["res=4", "res=5", "seed=1"]))
    elif kind == "int":
        v = draw(ints)
    elif kind == "float":
        v = draw(floats)
    elif kind == "text":
        v = draw(texts)
    else:
        v = str(tmp / draw(st.sampled_from(["o.exr", "o.png", "o.npy", "o.csv", "o.vol", "sub/o.exr", "o"])))
    n = 3 if action.nargs == "+" and draw(st.booleans()) else 1
    return [v] * n


def argv_base(command: str, tmp: Path) -> list[str]:
    """Valid required options for `command` (what every example starts from)."""
    base = {
        "render": [SCENE, "-o", str(tmp / "r.exr"), "-D", "res=4", "--quiet"],
        "ensemble": [FGF_SCENE, "-n", "2", "-o", str(tmp / "e.exr"), "-D", "res=4", "--quiet"],
        "field": ["--shape", "8", "8", "--hurst", "-0.2", "-o", str(tmp / "f.npy"), "-q"],
        "transmittance": ["--sigma-t", "1", "--hurst", "-0.2", "--sw", "1", "-q"],
        "figures": ["--out", str(tmp / "figs")],
        "truth": [KFBM_SCENE, "-o", str(tmp / "t.exr"), "-D", "res=4", "--quiet"],
    }
    return [command, *base.get(command, [])]


@st.composite
def argv(draw: Any, command: str, tmp: Path) -> list[str]:
    out = [command]
    # Valid required options first (the drawn ones come later and win), so
    # that most examples get past argparse into the command's own checks.
    out += argv_base(command, tmp)[1:]
    for action in draw(st.lists(st.sampled_from(OPTIONS[command]), max_size=6)):
        out += [draw(st.sampled_from(action.option_strings)), *_value(draw, action, tmp)]
    if command == "transmittance" and "-o" not in out and draw(st.booleans()):
        out += ["-o", str(tmp / "t.csv")]
    return out


class _Stop(Exception):
    pass


@pytest.fixture
def tiny_work(monkeypatch):
    real_render, real_ensemble, real_synth = _core.render_scene, _core.ensemble_scene, _core.synthesize
    real_plan, real_node = _core.truth_plan, _core.render_truth_node

    def render_scene(scene: Any, **kw: Any) -> Any:
        kw["spp"] = 2
        return real_render(scene, **kw)

    def ensemble_scene(scene: Any, n: Any, **kw: Any) -> Any:
        kw.update(spp=1, resolution=4)
        return real_ensemble(scene, min(n, 2), **kw)

    def synthesize(shape: Any, *a: Any) -> Any:
        n = 1
        for s in shape:
            n *= s
        if n > 4096:
            raise fgf.ParameterError(f"test: shape {shape} larger than the fuzz test's 4096 samples")
        return real_synth(shape, *a)

    def truth_plan(scene: Any, nodes: Any = None, defines: Any = None) -> Any:
        return real_plan(scene, nodes=None if nodes is None else min(nodes, 2), defines=defines)

    def render_truth_node(scene: Any, node: Any, nodes: Any = None, **kw: Any) -> Any:
        kw["spp"] = 1
        return real_node(scene, node, nodes=None if nodes is None else min(nodes, 2), **kw)

    def make_figures(*a: Any, **kw: Any) -> Any:
        raise _Stop

    monkeypatch.setattr(_core, "render_scene", render_scene)
    monkeypatch.setattr(_core, "ensemble_scene", ensemble_scene)
    monkeypatch.setattr(_core, "synthesize", synthesize)
    monkeypatch.setattr(_core, "truth_plan", truth_plan)
    monkeypatch.setattr(_core, "render_truth_node", render_truth_node)
    import fgf.figures

    monkeypatch.setattr(fgf.figures, "make_figures", make_figures)


def _run(args: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = cli.main(args)
        except SystemExit as e:  # argparse: usage errors (2), --help (0)
            code = int(e.code or 0)
        except _Stop:
            code = 0
    return code, err.getvalue()


@pytest.mark.parametrize("command", sorted(OPTIONS))
def test_random_options_exit_0_or_2(command, tmp_path_factory, tiny_work, monkeypatch):
    tmp = tmp_path_factory.mktemp(command)
    # Drawn text values become relative output paths (`--checkpoint A`):
    # they land in the temporary folder, not in the working tree.
    monkeypatch.chdir(tmp)

    @settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
    @given(argv(command, tmp))
    def check(args: list[str]) -> None:
        code, err = _run(args)
        assert code in (0, 2, 130), (args, code, err)
        assert "Traceback" not in err and "panicked" not in err, (args, err)
        if code == 2:
            assert err.strip(), args
        codes.append(code)
        # Past argparse: the command ran, or its own checks refused a value.
        reached.append(code == 0 or not err.lstrip().startswith("usage:"))

    codes: list[int] = []
    reached: list[bool] = []
    check()
    # The property is only worth something if many examples get past
    # argparse into the command, and the valid base command succeeds.
    assert sum(reached) >= len(reached) // 4, (sum(reached), len(reached))
    assert _run(argv_base(command, tmp))[0] == 0, argv_base(command, tmp)
