"""Settings: a resting object's footprint is carved out of the ground beneath it."""

import numpy as np

import morphosim_gym as ms
from morphosim_gym.generate.settings import carve_under
from morphosim_gym.scene.parts import SurfaceCloud
from morphosim_gym.scene.rotations import normal_quats


def _ground(sigma: float = 0.03, half: float = 0.5) -> SurfaceCloud:
    g = np.arange(-half, half + 1e-9, sigma * 1.2)
    xy = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    n = len(xy)
    return SurfaceCloud(np.c_[xy, np.zeros(n)], normal_quats(np.tile([0.0, 0.0, 1.0], (n, 1)), np.random.default_rng(0)),
                        np.tile([sigma, sigma, 0.3 * sigma], (n, 1)), np.full(n, 0.98),
                        np.tile([0.6, 0.4, 0.2], (n, 1)), np.zeros(n, np.int64), ["setting"])


def _disc(radius: float, spacing: float) -> np.ndarray:
    g = np.arange(-radius, radius + 1e-9, spacing)
    xy = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    xy = xy[np.linalg.norm(xy, axis=1) <= radius]
    return np.c_[xy, np.zeros(len(xy))]


def test_nothing_large_reaches_under_the_base_and_the_ground_around_stays():
    ground, spacing, radius = _ground(), 0.01, 0.14
    carved = carve_under(ground, _disc(radius, spacing), spacing)
    r = np.linalg.norm(carved.means[:, :2], axis=1)
    reach = 2.0 * carved.scales[:, :2].max(axis=1)
    small = reach <= 3 * spacing
    # no large Gaussian reaches under the base; the small ones that replace them near its rim
    # do not lie deep under it
    assert np.all(r[~small] - reach[~small] > radius - spacing)
    assert small.any() and not np.any(r < radius - 4 * spacing)
    # far fewer than one small Gaussian per grid step over the whole parents' area
    assert small.sum() < 700
    far = np.linalg.norm(ground.means[:, :2], axis=1) > radius + 2.5 * 0.06
    assert {tuple(p) for p in ground.means[far]} <= {tuple(p) for p in carved.means}
    # every point of the ground around the base is still within one sigma of a Gaussian
    ring = np.stack([np.cos(a := np.linspace(0, 2 * np.pi, 90)), np.sin(a)], -1)
    for rr in (radius + 0.005, radius + 0.03, radius + 0.08):
        d = np.linalg.norm((rr * ring)[:, None] - carved.means[None, :, :2], axis=-1) / carved.scales[None, :, 0]
        assert np.all(d.min(axis=1) < 1.0), rr


def test_no_base_or_a_base_elsewhere_changes_nothing():
    ground = _ground()
    assert carve_under(ground, np.zeros((0, 3)), 0.01) is ground
    out = carve_under(ground, _disc(0.1, 0.01) + [5.0, 5.0, 0.0], 0.01)
    assert len(out) == len(ground)


def test_the_table_never_shows_through_the_plate():
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=96, height=96, num_frames=9), reconstruction="oracle")
    clip = sim.generate_clip("a red cube moves to the plate while the camera circles the table", seed=0)
    plate = next(o.id for o in clip.ground_truth.objects if o.name == "plate")
    holes, area = 0, 0
    for i in range(clip.num_frames):
        state = clip.ground_truth.at(i / clip.fps)
        alone = ms.render(state.subset(state.object_ids == plate), clip.cameras[i])
        solid = alone.alpha > 0.999
        solid[1:-1, 1:-1] &= solid[:-2, 1:-1] & solid[2:, 1:-1] & solid[1:-1, :-2] & solid[1:-1, 2:]
        # where the plate is solid and nothing else is in front of it (the cube), the mask says plate
        front = clip.masks[i] != next(o.id for o in clip.ground_truth.objects if o.name == "cube")
        holes += int((solid & front & (clip.masks[i] != plate)).sum())
        area += int((solid & front).sum())
    assert area > 200 and holes <= 0.005 * area, (holes, area)


def test_an_object_above_the_ground_hides_nothing():
    ground = _ground()
    assert len(carve_under(ground, _disc(0.14, 0.01) + [0.0, 0.0, 0.5], 0.01)) == len(ground)


def test_walled_settings_get_no_sky_and_open_ones_may():
    # one table (language.vocabulary.SETTING_LAYOUTS) says which settings are closed by walls: the
    # generator gives them no sky panorama, and reconstruction keeps their backdrop (priors.prepare)
    from morphosim_gym.generate.real_assets import SETTING_SKIES
    from morphosim_gym.generate.settings import SETTING_NAMES
    from morphosim_gym.language.vocabulary import SETTING_LAYOUTS
    from morphosim_gym.priors.prepare import CLOSED_SETTINGS

    assert set(SETTING_LAYOUTS) == set(SETTING_NAMES)
    assert set(CLOSED_SETTINGS) == {n for n, layout in SETTING_LAYOUTS.items() if layout.walls} == {"table", "indoor"}
    assert not set(SETTING_SKIES) & set(CLOSED_SETTINGS)
    assert set(SETTING_SKIES) | set(CLOSED_SETTINGS) | {"underwater"} == set(SETTING_NAMES)
