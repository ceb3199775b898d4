"""The compatibility corpus: public Mitsuba 3 scenes nobody on this project
wrote, loaded unchanged (listed with their sources in
``docs/compatibility.md``; the files are in ``tests/corpus/``).

Each scene either renders and agrees with the ``mitsuba`` package
(``scalar_rgb``) — image mean within 3 standard errors per channel and
8x8 blocks by Welch's t with Holm's correction, over K = 16 seeds each, as
in ``tests/test_render_mitsuba.py`` — or is refused in one line that names
the feature fgf lacks (``expect`` below). The scenes are rendered at 32x32:
the corpus is copied to a temporary directory and every film's ``width``
and ``height`` are set to 32 there, for both renderers alike.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

import fgf
from test_render_mitsuba import compare

pytest.importorskip("mitsuba")

CORPUS = Path(__file__).resolve().parent / "corpus"
MD = "mitsuba-data"
SPP = 16

# (scene, None to render and compare, or the refusal's feature name)
SCENES: list[tuple[str, str | None]] = [
    (f"{MD}/scenes/cbox/cbox.xml", None),
    (f"{MD}/scenes/cbox/cbox-rgb.xml", None),
    (f"{MD}/scenes/cbox/cbox-spectral.xml", None),
    (f"{MD}/scenes/hello.xml", None),
    (f"{MD}/docs/scenes/integrator_depth_1.xml", None),
    (f"{MD}/docs/scenes/integrator_depth_2.xml", None),
    (f"{MD}/docs/scenes/integrator_depth_3.xml", None),
    (f"{MD}/docs/scenes/integrator_depth_inf.xml", None),
    (f"{MD}/docs/scenes/bsdf_twosided_cbox.xml", None),
    (f"{MD}/docs/scenes/bsdf_twosided_cbox_onesided.xml", None),
    (f"{MD}/docs/scenes/variants_cbox_rgb.xml", None),
    (f"{MD}/docs/scenes/variants_cbox_spectral.xml", None),
    (f"{MD}/docs/scenes/sampler_independent_16spp.xml", "envmap"),
    (f"{MD}/docs/scenes/sampler_independent_25spp.xml", "envmap"),
    (f"{MD}/docs/scenes/sampler_stratified_16spp.xml", "envmap"),
    (f"{MD}/docs/scenes/sampler_multijitter_16spp.xml", "envmap"),
    (f"{MD}/docs/scenes/sampler_orthogonal_25spp.xml", "envmap"),
    (f"{MD}/docs/scenes/sampler_ldsampler_16spp.xml", "envmap"),
    (f"{MD}/docs/scenes/medium_homogeneous_sss.xml", "roughdielectric"),
    (f"{MD}/scenes/matpreview/matpreview.xml", "envmap"),
    (f"{MD}/tests/scenes/participating_media/test_homo_emitter_inside_medium_volpath.xml", "envmap"),
    (f"{MD}/tests/scenes/participating_media/test_hetero_sigmat_volpath.xml", "envmap"),
    (f"{MD}/tests/scenes/participating_media/test_homo_area_light_volpath.xml", "checkerboard"),
]

FILM_SIZE = re.compile(r'(<integer\s+name\s*=\s*["\'](?:width|height)["\']\s+value\s*=\s*["\'])[^"\']*(["\'])')


@pytest.fixture(scope="module")
def small_corpus(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The corpus with every film at 32x32."""
    root = tmp_path_factory.mktemp("corpus")
    shutil.copytree(CORPUS, root, dirs_exist_ok=True)
    for xml in root.rglob("*.xml"):
        text = xml.read_text()
        xml.write_text(FILM_SIZE.sub(r"\g<1>32\g<2>", text))
    return root


def test_corpus_has_at_least_20_scenes_and_most_render() -> None:
    assert len(SCENES) >= 20
    assert all((CORPUS / s).exists() for s, _ in SCENES)


@pytest.mark.parametrize("scene,missing", SCENES, ids=[Path(s).stem for s, _ in SCENES])
def test_corpus_scene(small_corpus: Path, scene: str, missing: str | None) -> None:
    path = small_corpus / scene
    if missing is None:
        compare(path, {}, SPP)
        return
    with pytest.raises(fgf.SceneError) as e:
        fgf.render(path, spp=1, progress=False)
    msg = str(e.value)
    assert "\n" not in msg, msg
    assert missing in msg, msg
