"""A layer's alpha split into objects (ssn_engine.objects)."""

from __future__ import annotations

import numpy as np
import pytest
from engine_helpers import disc, pawn_scene

from ssn_engine.framing import EmptyAlphaError, alpha_bbox
from ssn_engine.objects import MAX_OBJECTS, split_objects

W, H = 1000, 600


def covers(objects, index: int, alpha: np.ndarray, part: np.ndarray) -> bool:
    """Whether object ``index`` holds every visible pixel of ``part``."""
    return bool(np.all(objects.alpha_of(index, alpha)[part > 3] == alpha[part > 3]))


def test_two_pawns_of_different_sizes_are_two_objects():
    big, small = pawn_scene(W, H, [(400, 560, 250), (200, 480, 750)])
    layer = np.maximum(big, small)
    objects = split_objects(layer)
    assert len(objects.objects) == 2
    assert covers(objects, 0, layer, big) and covers(objects, 1, layer, small)  # largest first
    assert not objects.alpha_of(0, layer)[small > 0].any()  # each alone
    x0, y0, x1, y1 = objects.objects[1].bbox
    assert x0 <= 750 - 60 and x1 >= 750 + 60 and y0 <= 280 and y1 >= 480


def test_a_detached_small_part_stays_with_its_object():
    (pawn,) = pawn_scene(W, H, [(400, 560, 400)])
    hand = disc(W, H, 560, 330, 18)  # a hand held out beside the body, not touching it
    assert not (hand & pawn).any()
    layer = np.maximum(pawn, hand)
    objects = split_objects(layer)
    assert len(objects.objects) == 1
    assert covers(objects, 0, layer, hand) and covers(objects, 0, layer, pawn)


def test_a_detached_part_with_a_second_object_goes_to_the_nearer_one():
    big, small = pawn_scene(W, H, [(400, 560, 250), (200, 480, 750)])
    hand = disc(W, H, 690, 400, 10)  # beside the small pawn, far from the big one
    layer = np.maximum.reduce([big, small, hand])
    objects = split_objects(layer)
    assert len(objects.objects) == 2
    assert covers(objects, 1, layer, hand) and not objects.alpha_of(0, layer)[hand > 0].any()


def test_a_large_piece_inside_an_objects_box_belongs_to_it():
    (pawn,) = pawn_scene(W, H, [(400, 560, 400)])
    piece = np.zeros((H, W), np.uint8)
    piece[170:290, 485:515] = 255  # beside the head, inside the pawn's box, 30 % of its height
    assert not (piece & pawn).any()
    layer = np.maximum(pawn, piece)
    objects = split_objects(layer)
    assert len(objects.objects) == 1


def test_a_ball_across_the_floor_is_an_object_but_a_speck_casts_nothing():
    (pawn,) = pawn_scene(W, H, [(400, 560, 300)])
    ball = disc(W, H, 850, 530, 30)
    speck = disc(W, H, 900, 40, 2)
    layer = np.maximum.reduce([pawn, ball, speck])
    objects = split_objects(layer)
    assert len(objects.objects) == 2
    assert covers(objects, 1, layer, ball)
    assert not any(objects.alpha_of(i, layer)[speck > 0].any() for i in range(2))


def test_many_parts_are_capped_by_joining_the_nearest():
    layer = np.zeros((H, W), np.uint8)
    for i in range(MAX_OBJECTS + 4):
        layer[100:500, 20 + 80 * i : 60 + 80 * i] = 255  # equal posts, far apart
    objects = split_objects(layer)
    assert len(objects.objects) == MAX_OBJECTS
    assert np.array_equal(np.maximum.reduce([objects.alpha_of(i, layer) for i in range(MAX_OBJECTS)]), layer)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32])
def test_alpha_depths_and_a_large_canvas_are_split_alike(dtype):
    big, small = pawn_scene(W, H, [(400, 560, 250), (200, 480, 750)])
    layer = np.maximum(big, small).astype(np.float32) / 255
    if dtype != np.float32:
        layer = np.rint(layer * np.iinfo(dtype).max).astype(dtype)
    assert len(split_objects(layer).objects) == 2
    wide = np.kron(np.maximum(big, small), np.ones((3, 3), np.uint8))  # 3000 x 1800: found on a coarser grid
    objects = split_objects(wide)
    assert objects.cell > 1 and len(objects.objects) == 2


def test_an_empty_alpha_is_refused():
    with pytest.raises(EmptyAlphaError):
        split_objects(np.zeros((50, 50), np.uint8))


def test_specks_only_are_one_object():
    rng = np.random.default_rng(0)
    noise = ((rng.random((H, W)) > 0.995) * 255).astype(np.uint8)  # scattered single pixels
    objects = split_objects(noise)
    assert len(objects.objects) == 1 and np.array_equal(objects.alpha_of(0, noise), noise)


@pytest.mark.parametrize("seed", range(12))
def test_random_blobs_split_into_objects_that_each_cast(seed):
    """Whatever the alpha, every object of a split casts (its alpha frames: no EmptyAlphaError) and objects do not
    share pixels."""
    rng = np.random.default_rng(seed)
    h, w = (int(v) for v in rng.integers(40, 1400, 2))
    layer = np.zeros((h, w), np.uint8)
    for _ in range(int(rng.integers(1, 30))):  # rectangles and discs of all sizes, some tiny
        cy, cx, r = rng.random() * h, rng.random() * w, rng.random() ** 3 * min(h, w) / 3 + 0.5
        layer = np.maximum(layer, disc(w, h, cx, cy, r))
    if not layer.any():
        layer[h // 2, w // 2] = 255
    try:
        objects = split_objects(layer)
    except EmptyAlphaError:  # a layer too small to cast at all
        return
    alphas = [objects.alpha_of(i, layer) for i in range(len(objects.objects))]
    assert np.all(np.sum([a > 0 for a in alphas], axis=0) <= 1)
    if len(alphas) > 1:
        for alpha in alphas:
            alpha_bbox(alpha)
