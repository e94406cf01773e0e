"""`submit_batch` / `cpu.claimed`: whole views claimed by several Python threads, bit-identical to
`render_batch` and `render` whichever thread renders which view."""

import threading
import time

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.render.api import open_batch, render_batch, submit_batch
from morphosim_gym.render.cpu.batch import batch_view
from morphosim_gym.render.cpu.claimed import ClaimedBatch, RenderHelpers
from tests.render.test_batched import _SPECS, _assert_same, _views


@pytest.mark.parametrize("helpers", [0, 1, 2])
def test_claimed_views_are_bit_identical_to_single_renders(helpers):
    views = _views(_SPECS)
    pool = RenderHelpers(helpers)
    try:
        outs = submit_batch(views, helpers=pool).result()
        again = submit_batch(views, helpers=pool).result()      # the helper threads serve batch after batch
    finally:
        pool.close()
    assert len(outs) == len(views)
    for (g, cam, bg), out, out2 in zip(views, outs, again):
        single = ms.render(g, cam, background=bg)
        _assert_same(out, single)
        _assert_same(out2, single)


def test_claimed_views_with_features_and_culling_match_render_batch():
    views = _views(_SPECS[:4], d=3)
    pool = RenderHelpers(1)
    try:
        for cull in (False, True):
            got = submit_batch(views, helpers=pool, features=True, cull=cull).result()
            ref = render_batch(views, features=True, cull=cull)
            for a, b in zip(got, ref):
                _assert_same(a, b, features=True)
    finally:
        pool.close()


def test_two_threads_claiming_one_batch_split_its_views_and_match():
    # both threads call work() on one batch at once: each view is rendered exactly once, by
    # whichever thread claims it, and every image is the serial one
    views = _views(_SPECS)
    bvs = [batch_view([g], c.world_to_camera, c.K, c.near, c.width, c.height, bg) for g, c, bg in views]
    ref = ClaimedBatch(bvs)
    assert ref.work() == len(views) and ref.finished and ref.work() == 0
    ref_out = ref.outputs()
    for _ in range(5):
        batch = ClaimedBatch(bvs)
        counts = []
        worker = threading.Thread(target=lambda: counts.append(batch.work()))
        worker.start()
        counts.append(batch.work())
        worker.join()
        assert sum(counts) == len(views) and batch.finished
        for a, b in zip(batch.outputs(), ref_out):
            for k in ("rgb", "depth", "alpha", "instance"):
                assert np.array_equal(a[k], b[k]), k


def test_outputs_before_every_view_is_rendered_and_bad_helper_counts_are_refused():
    views = _views(_SPECS[:2])
    bvs = [batch_view([g], c.world_to_camera, c.K, c.near, c.width, c.height, bg) for g, c, bg in views]
    batch = ClaimedBatch(bvs)
    with pytest.raises(RuntimeError, match="every view rendered"):
        batch.outputs()
    for bad in (-1, 1.5, True):
        with pytest.raises(ValueError, match="helpers"):
            RenderHelpers(bad)
    assert ClaimedBatch([]).work() == 0 and ClaimedBatch([]).outputs() == []


@pytest.mark.parametrize("helpers", [0, 1])
def test_partial_outputs_come_view_range_by_range_and_match(helpers):
    # the vector env finishes env i as soon as its views are rendered: partial(lo, hi) renders or
    # waits for exactly those views and gives what the whole batch gives for them
    views = _views(_SPECS)
    ref = render_batch(views)
    pool = RenderHelpers(helpers)
    try:
        pending = submit_batch(views, helpers=pool)
        got = pending.partial(0, 3, 30) + pending.partial(3, 4, 30) + pending.partial(4, len(views), 30)
    finally:
        pool.close()
    for a, b in zip(got, ref):
        _assert_same(a, b)
    bvs = [batch_view([g], c.world_to_camera, c.K, c.near, c.width, c.height, bg) for g, c, bg in views]
    batch = ClaimedBatch(bvs)
    assert batch.work(limit=2) == 2 and batch.views_done(0, 2) and not batch.views_done(0, 3)
    assert len(batch.outputs(0, 2)) == 2
    with pytest.raises(RuntimeError, match="every view rendered"):
        batch.outputs(0, 3)


def test_views_claimed_from_both_ends_are_each_rendered_once_and_match():
    # the vector env's thread takes views from the last while a helper takes them from the first:
    # every view once, by either, and the serial images
    views = _views(_SPECS)
    bvs = [batch_view([g], c.world_to_camera, c.K, c.near, c.width, c.height, bg) for g, c, bg in views]
    ref = ClaimedBatch(bvs)
    ref.work()
    batch = ClaimedBatch(bvs)
    assert batch.work(limit=2, last_first=True) == 2
    assert batch.views_done(len(views) - 2, len(views)) and not batch.views_done(0, 1)   # the last two
    assert batch.work(limit=1) == 1 and batch.views_done(0, 1)                           # then the first
    for _ in range(5):
        batch = ClaimedBatch(bvs)
        counts = []
        worker = threading.Thread(target=lambda: counts.append(batch.work()))
        worker.start()
        while batch.work(1, last_first=True):
            counts.append(1)
        worker.join()
        assert sum(counts) == len(views) and batch.finished and not batch.claimable
        for a, b in zip(batch.outputs(), ref.outputs()):
            for k in ("rgb", "depth", "alpha", "instance"):
                assert np.array_equal(a[k], b[k]), k


@pytest.mark.parametrize("helpers", [0, 1])
def test_first_ready_gives_a_span_whose_views_are_rendered(helpers):
    views = _views(_SPECS)
    ref = render_batch(views)
    pool = RenderHelpers(helpers)
    try:
        pending = submit_batch(views, helpers=pool)
        left = [(k, k + 1) for k in range(len(views))]
        got = {}
        while left:
            lo, hi = left.pop(pending.first_ready(left, 30))
            got[lo] = pending.partial(lo, hi, 30)[0]
        if helpers == 0:                            # this thread alone: from the last view to the first
            assert list(got) == list(range(len(views)))[::-1]
        with pytest.raises(RuntimeError, match="closed batch"):
            open_batch(helpers=pool).first_ready([(0, 1)])
        with pytest.raises(ValueError, match="at least one span"):
            pending.first_ready([], 30)
    finally:
        pool.close()
    for k, b in enumerate(ref):
        _assert_same(got[k], b)


def _wait(cond, seconds: float = 60.0) -> bool:
    deadline = time.monotonic() + seconds
    while not cond():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.001)
    return True


def test_an_open_batch_renders_each_view_as_it_is_added():
    # the vector env adds env i's view right after advancing env i: a helper renders it while the
    # batch is still open (before the next view is even added), and the outputs are render_batch's
    views = _views(_SPECS[:3])
    ref = render_batch(views)
    pool = RenderHelpers(1)
    try:
        pending = open_batch(helpers=pool, capacity=(3, 10_000, 3 * 100 * 100))
        pending.add(views[0])
        batch = pending._where[0][0]
        assert _wait(lambda: batch.views_done(0, 1)) and not batch.closed
        pending.add(views[1])                      # the helper, asleep since view 0, wakes for it
        assert _wait(lambda: batch.views_done(0, 2)) and not batch.closed
        pending.add(views[2])
        with pytest.raises(RuntimeError, match="closed batch"):
            pending.partial(0, 1)
        pending.close()
        got = pending.result()
    finally:
        pool.close()
    for a, b in zip(got, ref):
        _assert_same(a, b)


@pytest.mark.parametrize("capacity", [None, (1, 10, 10), (2, 100, 100)])
def test_views_past_the_capacity_go_to_further_batches_and_match(capacity):
    views = _views(_SPECS)
    ref = render_batch(views)
    pool = RenderHelpers(1)
    try:
        pending = open_batch(helpers=pool, capacity=capacity)
        for view in views:
            pending.add(view)
        pending.close()
        got = pending.partial(0, 2, 30) + pending.partial(2, len(views), 30)
        batches = {id(w[0]) for w in pending._where}
    finally:
        pool.close()
    assert len(batches) > 1
    assert pending.staged == (len(views), sum(len(g.means) for g, _, _ in views),
                              sum(c.width * c.height for _, c, _ in views))
    for a, b in zip(got, ref):
        _assert_same(a, b)


def test_a_bad_view_is_refused_and_leaves_the_open_batch_usable():
    views = _views(_SPECS[:2])
    pool = RenderHelpers(1)
    try:
        pending = open_batch(helpers=pool, capacity=(2, 10_000, 2 * 84 * 84))
        pending.add(views[0])
        with pytest.raises(ValueError, match="Camera"):
            pending.add((views[1][0], "not a camera"))
        with pytest.raises(ValueError, match="background"):
            pending.add((views[1][0], views[1][1], (2.0, 0.0, 0.0)))
        pending.add(views[1])
        got = pending.result()                      # result() closes the batch
        with pytest.raises(ValueError, match="open batch"):
            pending.add(views[0])
    finally:
        pool.close()
    assert len(got) == 2
    for a, b in zip(got, render_batch(views)):
        _assert_same(a, b)


def test_cancel_leaves_no_helper_on_the_batch():
    views = _views(_SPECS[:4])
    pool = RenderHelpers(1)
    try:
        pending = open_batch(helpers=pool, capacity=(4, 20_000, 4 * 100 * 100))
        pending.add(views[0])
        pending.add(views[3])
        pending.cancel()
        batch = pending._where[0][0]
        assert batch.finished and batch._done.is_set()
    finally:
        pool.close()


def test_an_open_batch_is_not_rendered_on_the_calling_thread():
    # the calling thread may only join in on a closed batch: on an open one it could wait for a view
    # that only it would add
    views = _views(_SPECS[:1])
    bvs = [batch_view([g], c.world_to_camera, c.K, c.near, c.width, c.height, bg) for g, c, bg in views]
    batch = ClaimedBatch(capacity=(2, 10_000, 2 * 84 * 84))
    assert batch.add(bvs[0]) and not batch.add(batch_view([views[0][0]] * 5, views[0][1].world_to_camera,
                                                          views[0][1].K, 0.01, 84, 84))
    pool = RenderHelpers(0)
    with pytest.raises(RuntimeError, match="open"):
        pool.partial(batch, 0, 1)
    with pytest.raises(RuntimeError, match="open"):
        pool.complete(batch)
    batch.close()
    out = pool.complete(batch)
    assert len(out) == 1 and np.array_equal(out[0]["rgb"], _rendered(bvs)[0]["rgb"])


def _rendered(bvs):
    b = ClaimedBatch(bvs)
    b.work()
    return b.outputs()


def test_views_of_several_parts_stream_as_render_composites_them():
    # a scene plus an agent: parts composited in order, ids -1 over a part that has none
    views = _views(_SPECS[:3])
    g0, g1 = views[0][0], views[1][0]
    bare = ms.Gaussians(means=g1.means, quats=g1.quats, scales=g1.scales, opacities=g1.opacities, colors=g1.colors)
    assert g0.object_ids is not None and bare.object_ids is None
    parts_views = [([g0, bare], views[2][1], views[2][2]), ([bare, g0, bare], views[0][1], views[0][2])]
    pool = RenderHelpers(1)
    try:
        pending = open_batch(helpers=pool, capacity=(1, 10, 10))        # the second view opens a second batch
        for view in parts_views:
            pending.add(view)
        got = pending.result()
    finally:
        pool.close()
    for (parts, cam, bg), out in zip(parts_views, got):
        _assert_same(out, ms.render(parts, cam, background=bg))


def test_closing_the_helpers_does_not_wait_for_an_open_batch():
    # a helper asleep on a batch nobody closed (a caller that raised mid-step) must still stop
    views = _views(_SPECS[:1])
    pool = RenderHelpers(1)
    pending = open_batch(helpers=pool, capacity=(3, 10_000, 3 * 100 * 100))
    pending.add(views[0])
    batch = pending._where[0][0]
    assert _wait(lambda: batch.views_done(0, 1)) and not batch.closed
    closer = threading.Thread(target=pool.close, daemon=True)
    closer.start()
    closer.join(30.0)
    assert not closer.is_alive() and batch.closed


def _frozen(g: ms.Gaussians) -> ms.Gaussians:
    """A copy of g whose arrays are read-only, as `Scene4D.at` gives them."""
    arrays = {k: np.array(getattr(g, k)) for k in ("means", "quats", "scales", "opacities", "colors", "object_ids")}
    for a in arrays.values():
        a.setflags(write=False)
    return ms.Gaussians(**arrays)


def test_frozen_parts_are_read_in_place_and_writable_ones_copied_at_add():
    # a view's read-only float32 parts are not copied (the kernels read them where they are); a
    # part the caller may still write is copied when it is added, so a later change never shows
    views = _views(_SPECS[:4])
    frozen = [(_frozen(g), cam, bg) for g, cam, bg in views[:2]]
    writable = [(ms.Gaussians(means=g.means.copy(), quats=g.quats.copy(), scales=g.scales.copy(),
                              opacities=g.opacities.copy(), colors=g.colors.copy(), object_ids=g.object_ids.copy()),
                 cam, bg) for g, cam, bg in views[2:]]
    pending = open_batch(capacity=(4, 20_000, 4 * 100 * 100))
    for view in frozen + writable:
        pending.add(view)
    batch = pending._where[0][0]
    kept = [a for part in batch._kept for a in part]
    assert any(a is frozen[0][0].means for a in kept) and any(a is frozen[1][0].colors for a in kept)
    assert not any(a is writable[0][0].means for a in kept)
    for g, _, _ in writable:                      # the caller reuses its buffers before the render
        g.colors[:] = 0.0
        g.means[:] += 5.0
    pending.close()
    for (g, cam, bg), out in zip(views, pending.result()):
        _assert_same(out, ms.render(g, cam, background=bg))


def test_a_view_of_more_parts_than_a_batch_keeps_rows_for_is_composited_the_same():
    views = _views(_SPECS[:3])
    g0, g1 = _frozen(views[0][0]), views[1][0]
    parts = [g0, g1, g0, g1, g0, g1]              # more than the 4 source rows a one-view batch keeps
    cam, bg = views[2][1], views[2][2]
    pool = RenderHelpers(1)
    try:
        pending = open_batch(helpers=pool, capacity=(1, 10, 10))
        pending.add((parts, cam, bg))
        pending.add((parts[:2], views[0][1], views[0][2]))               # a second batch
        got = pending.result()
    finally:
        pool.close()
    _assert_same(got[0], ms.render(parts, cam, background=bg))
    _assert_same(got[1], ms.render(parts[:2], views[0][1], background=views[0][2]))


def test_a_batch_submitted_unposted_and_never_handed_over_is_still_rendered():
    # `submit(post=False)` leaves the post to `handover`; a helper looking for work without the GIL
    # must still take a batch nobody posts, once its look is over
    views = _views(_SPECS[:2])
    bvs = [batch_view([g], c.world_to_camera, c.K, c.near, c.width, c.height, bg) for g, c, bg in views]
    pool = RenderHelpers(1)
    try:
        for _ in range(3):
            batch = pool.submit(ClaimedBatch(bvs), post=False)
            assert _wait(lambda: batch.finished, 30.0)     # the helper alone renders it
            for out, (g, cam, bg) in zip(batch.outputs(), views):
                assert np.array_equal(out["rgb"], ms.render(g, cam, background=bg).rgb)
    finally:
        pool.close()


def test_a_helper_looking_for_the_next_batch_sees_a_post_and_reports_how_long_it_looked():
    from morphosim_gym.render.cpu.claimed import _bump, _wait_posted

    posted = np.zeros(1, np.int64)
    assert _wait_posted(posted, 0, 1000) == -1            # nothing posted: the whole look, then -1
    _bump(posted, 0)
    assert _wait_posted(posted, 0, 1000) == 0
    assert _wait_posted(posted, 1, 1000) == -1


@pytest.mark.parametrize("helpers", [0, 1, 2])
def test_views_with_skies_are_composited_where_they_render_and_match(helpers):
    # the thread that renders a view composites its sky (`sky.composite_view`): the same bits as
    # `render_batch` and `render`, which composite after the render; views of different skies and
    # none in one batch
    rng = np.random.default_rng(5)
    skies = [ms.scene.sky.check_sky(rng.random((16, 32, 3), dtype=np.float32)) for _ in range(2)]
    views = [(g, cam, None, skies[i % 3]) if i % 3 < 2 else (g, cam, bg)
             for i, (g, cam, bg) in enumerate(_views(_SPECS))]
    ref = render_batch(views)
    pool = RenderHelpers(helpers)
    try:
        got = submit_batch(views, helpers=pool).result()
    finally:
        pool.close()
    for view, a, b in zip(views, got, ref):
        _assert_same(a, b)
        _assert_same(a, ms.render(view[0], view[1], background=view[2], sky=view[3] if len(view) == 4 else None))
    shown = [np.mean(out.rgb[out.alpha < 0.5] > 0) for view, out in zip(views, got) if len(view) == 4]
    assert min(shown) > 0.9                                  # the sky is there, behind uncovered pixels


def test_a_view_with_a_bad_sky_is_refused_and_changes_nothing():
    (g, cam, bg), = _views(_SPECS[:1])
    batch = ClaimedBatch(capacity=(2, 10_000, 2 * 100 * 100))
    view = (cam.world_to_camera, cam.K, cam.near, cam.width, cam.height, np.zeros(3))
    with pytest.raises(ValueError, match="sky image"):
        batch.add_parts([g], *view, sky=(np.zeros((8, 8)), cam))
    assert batch.num_views == 0
    sky = ms.scene.sky.check_sky(np.full((4, 8, 3), 0.5, np.float32))
    assert batch.add_parts([g], *view, sky=(sky, cam)) and batch.num_views == 1
    batch.close()
    batch.work()
    got = batch.outputs()[0]
    _assert_same(ms.render(g, cam, sky=sky), render_batch([(g, cam, None, sky)])[0])
    np.testing.assert_array_equal(got["rgb"], ms.render(g, cam, sky=sky).rgb)
