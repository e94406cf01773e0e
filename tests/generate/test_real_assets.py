"""Real assets in the generator: seed-determined picks, recolour keeping texture, the off switch."""

import numpy as np
import pytest

from morphosim_gym.generate.compose import GenerationConfig, compose_scene
from morphosim_gym.generate.real_assets import asset_candidates, asset_index
from morphosim_gym.language import parse


@pytest.fixture
def real(monkeypatch):
    monkeypatch.delenv("MORPHOSIM_ASSET_SOURCES", raising=False)
    if len(asset_candidates("chair")) < 2:
        pytest.skip("needs the Sweet Home 3D furniture (apt install sweethome3d-furniture)")
    return asset_index()


def _chair(seed, assets="auto", text="a chair"):
    return compose_scene(parse(text), seed, GenerationConfig(assets=assets)).scene


def test_deterministic_by_seed_and_diverse(real):
    a, b = _chair(0), _chair(0)
    assert a.objects[1].asset is not None and a.objects[1].category == "chair" and a.objects[1].name == "chair"
    np.testing.assert_array_equal(a.gaussians.means, b.gaussians.means)
    assert len({_chair(s).objects[1].asset for s in range(4)}) > 1


def test_off_switch_is_procedural(real, monkeypatch):
    off = _chair(0, "off")
    monkeypatch.setenv("MORPHOSIM_ASSET_SOURCES", "")
    env_off = _chair(0, "auto")
    assert off.objects[1].asset is None
    np.testing.assert_array_equal(off.gaussians.means, env_off.gaussians.means)
    np.testing.assert_array_equal(off.gaussians.colors, env_off.gaussians.colors)


def test_recolour_keeps_texture(real):
    def spread(scene):
        return float(scene.gaussians.colors[scene.gaussians.object_ids == 1].std(0).mean())
    seed = next((s for s in range(12) if spread(_chair(s)) > 0.03), None)
    if seed is None:
        pytest.skip("no textured chair among the first picks")
    plain, red = _chair(seed), _chair(seed, text="a red chair")
    assert plain.objects[1].asset == red.objects[1].asset
    c0 = plain.gaussians.colors[plain.gaussians.object_ids == 1]
    c1 = red.gaussians.colors[red.gaussians.object_ids == 1]
    assert c1[:, 0].mean() > c1[:, 1].mean() + 0.2
    assert c1.std(0).mean() > 0.3 * c0.std(0).mean()


def test_edit_on_real_asset_scene(real):
    from morphosim_gym.edit import SceneEditor
    scene = _chair(0, text="a chair and a table")
    out = SceneEditor().edit(scene, "remove the chair")
    assert not np.any(out.gaussians.object_ids == 1)
    assert all(o.asset is not None for o in out.objects if o.role == "object")


def test_sky_seen_in_a_novel_view_and_saved(real, tmp_path):
    from morphosim_gym.render import render
    from morphosim_gym.scene import Camera, load_scene, save_scene
    from morphosim_gym.scene.sky import sky_background
    scene = _chair(0, text="a chair on the grass")
    if scene.sky is None:
        pytest.skip("needs Blender's sky panoramas (apt install blender-data)")
    up = Camera.look_at((0, -1, 1), (0, 0, 40), 32, 32, 60)     # looking at the zenith, over everything
    out = render(scene, up, 0.0)
    np.testing.assert_allclose(out.rgb, sky_background(scene.sky, up), atol=0.05)
    save_scene(scene, tmp_path / "s.msim")
    np.testing.assert_array_equal(load_scene(tmp_path / "s.msim").sky, scene.sky)


def test_envs_see_the_sky_and_the_vector_env_matches_single_envs(real):
    """An outdoor real-asset scene's sky reaches every env camera ray: the top rows of the
    observation are the panorama, not the flat background, and the batched vector env renders
    them exactly as single envs do."""
    import gymnasium as gym

    import morphosim_gym.envs  # noqa: F401  (registers the ids)
    from morphosim_gym.envs.native_vector import MorphoSimVectorEnv

    from morphosim_gym.render import render

    kw = dict(prompt="a red car drives from left to right", width=32, height=32)
    env = gym.make("MorphoSim/Track-v0", **kw)
    up = {"camera": {"look_at": [0.0, 30.0, 12.0]}}            # the tripod camera looks over the horizon
    obs, _ = env.reset(seed=0, options=up)
    u = env.unwrapped
    scene = u.world.scene
    assert scene.sky is not None
    cam = u.rig.camera(u.task.default_cameras[0], 32, 32)
    sources = u._sources(u.world.t)
    with_sky = render(sources, cam, background=scene.background, sky=scene.sky).rgb_uint8()
    flat = render(sources, cam, background=scene.background).rgb_uint8()
    assert np.abs(with_sky.astype(int) - flat).max() > 10      # the view shows sky where nothing is drawn
    np.testing.assert_array_equal(obs["rgb"], with_sky)
    singles = []
    for i in range(2):
        e = gym.make("MorphoSim/Track-v0", **kw)
        o, _ = e.reset(seed=5 + i, options=up)
        singles.append(o["rgb"])
        e.close()
    venv = MorphoSimVectorEnv(2, "track", **kw)
    vo, _ = venv.reset(seed=5, options=up)
    for i in range(2):
        np.testing.assert_array_equal(vo["rgb"][i], singles[i])
    venv.close()
    env.close()


def test_category_candidates_need_the_category_as_head_noun(real):
    # "Dog house" names a house and "Hot dog" (a compound WordNet knows) a food: neither is a dog
    names = {r.name.lower() for r in asset_candidates("dog")}
    assert "dog" in names and "dog house" not in names and "hot dog" not in names
    assert not any("cake" in r.name.lower() for r in asset_candidates("cup"))


def test_a_sibling_synonym_names_no_asset_of_the_category(real):
    # "stool" is a chair synonym in the vocabulary, but WordNet puts a stool beside a chair (both seats)
    names = {r.name.lower() for r in asset_candidates("chair")}
    assert "chair" in names and not any("stool" in n for n in names)
