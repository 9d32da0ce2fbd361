"""Small lights traced at the canvas's resolution (ssn_engine.hard_light): crisp, contact-hardened, following
the light, and through the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

from ssn_engine.cli import main
from ssn_engine import hard_light
from ssn_engine.framing import Framing, frame_alpha
from ssn_engine.hard_light import (
    CardTracer,
    ContactTracer,
    contact_bands,
    contact_line,
    depth_map,
    footprint_rise,
    local_radius,
    read_thickness,
    traced_share,
)
from ssn_engine.host_kit.light_map import GaussianLight, LightMap, disk_directions
from ssn_engine.light_plan import LightPlan
from training.metrics import zncc

W, H = 1024, 768
FOOT = 600  # the post's lowest row + 1
LEFT, RIGHT = 497, 527  # the post's columns


@pytest.fixture(scope="module")
def post() -> np.ndarray:
    """A canvas with an upright post, 30 x 300 pixels, standing on row 600."""
    alpha = np.zeros((H, W), np.uint8)
    alpha[FOOT - 300 : FOOT, LEFT:RIGHT] = 255
    return alpha


@pytest.fixture(scope="module")
def tracer(post) -> tuple[ContactTracer, Framing]:
    """The post's tracer, with the conventions' default camera, and its framing."""
    _, framing = frame_alpha(post, 256)
    x0, y0, x1, y1 = framing.bbox
    return ContactTracer(post[y0:y1, x0:x1].astype(np.float32) / 255, framing, None), framing


def _canvas(tracer: tuple[ContactTracer | CardTracer, Framing], u: float, v: float, angle: float) -> np.ndarray:
    """The shadow of a disk light on the whole canvas."""
    values, x, y = tracer[0].shadow(u, v, angle, tracer[1])
    out = np.zeros((H, W), np.float32)
    out[y : y + values.shape[0], x : x + values.shape[1]] = values
    return out


def _cast_at(card: CardTracer, framing: Framing, foot: float, row: float, u: float, v: float) -> np.ndarray:
    """Where (canvas x, y) the point that the post's centre pixel at canvas ``row`` shows, standing above the
    ground seen at canvas row ``foot`` (on that pixel's camera ray, as far ahead), casts its shadow along the
    light at map point (``u``, ``v``)."""
    cam, ahead = card.camera, hard_light.FORWARD
    centre = 0.5 * (LEFT + RIGHT)
    ray = cam.rays(*[np.array([c]) for c in framing.to_frame(centre, foot)])[0]
    distance = (cam.centre - cam.centre[1] / ray[1] * ray) @ ahead
    pixel = cam.rays(*[np.array([c]) for c in framing.to_frame(centre, row)])[0]
    point = cam.centre + (distance - cam.centre @ ahead) / (pixel @ ahead) * pixel
    w = hard_light.light_direction(u, v)
    ground = point - point[1] / w[1] * w
    return np.array(framing.to_canvas(*[float(c[0]) for c in cam.project_xyz(*[np.array([g]) for g in ground])]))


def _far_end(s: np.ndarray) -> np.ndarray:
    """Where (canvas x, y) a shadow falling away up the canvas ends: the middle of its top rows (s > 0.5), the
    shadow of the post's top edge."""
    yy, xx = np.nonzero(s > 0.5)
    return np.array([xx[yy <= yy.min() + 2].mean(), yy.min() + 0.5])


def _edge_width(row: np.ndarray) -> float:
    """Pixels over which a row's profile across the shadow rises from 10 % to 90 % of its peak, on its left
    edge (the mean over both edges)."""
    peak = row.max()
    widths = []
    for side in (row, row[::-1]):
        first = np.argmax(side > 0.1 * peak)
        last = np.argmax(side > 0.9 * peak)
        widths.append(last - first)
    return float(np.mean(widths))


def test_a_sun_shadow_is_crisp_at_the_canvas_scale_and_a_big_light_soft_far_from_the_contact(tracer):
    """Light straight behind the post, low: the shadow runs down the canvas towards the viewer. A 0.53 degree
    sun keeps its edges within a few pixels even at the far end (its penumbra there: 0.53 degrees times the
    distance to the post's top); a 12 degree light's far edges are
    several times wider, while at the contact both are crisp (contact hardening)."""
    sun, big = _canvas(tracer, 0.5, 0.75, 0.53), _canvas(tracer, 0.5, 0.75, 12.0)
    rows = np.flatnonzero(sun.max(axis=1) > 0.5)
    assert rows[0] <= FOOT + 1 and rows[-1] > FOOT + 60  # from the foot down the canvas
    near, far = FOOT + 2, int(rows[0] + 0.9 * (rows[-1] - rows[0]))
    assert sun[near].max() > 0.99 and sun[far].max() > 0.99  # the umbra: fully dark
    assert _edge_width(sun[far]) <= 4.0
    assert _edge_width(big[far]) >= 4 * max(_edge_width(sun[far]), 1.0)
    assert _edge_width(big[near]) <= 2.0  # no penumbra at the contact
    assert big[near].max() > 0.99  # and dark there


def test_the_blur_matches_the_mean_of_hard_shadows_over_the_disk(tracer):
    """The contact-hardened blur stands for the mean of the hard shadows along the disk's directions."""
    light = GaussianLight.disk(0.42, 0.7, 12.0)
    traced = _canvas(tracer, light.u, light.v, light.angle)
    mean = np.zeros_like(traced)
    for u, v, share in disk_directions(light, 150):
        mean += share * _canvas(tracer, u, v, 0.1)
    assert zncc(traced, mean) > 0.95  # the depth swept after the blur: a little softer at its far end
    assert np.abs(traced - mean).mean() < 0.01


@pytest.mark.parametrize(
    "u, where",
    [(0.5, "below"), (0.1, "above"), (0.35, "right"), (0.65, "left")],
)
def test_the_shadow_follows_the_light(tracer, u, where):
    """Behind the object (u = 0.5) the shadow comes towards the viewer, below the foot; from behind the camera
    (u = 0.1: and from its left, so that the post does not hide it) it falls away, above it; a light left of
    centre casts it right, and vice versa."""
    s = _canvas(tracer, u, 0.6, 0.53)
    s[FOOT - 300 : FOOT, LEFT:RIGHT] = 0  # the ground hidden by the post
    yy, xx = np.mgrid[0:H, 0:W]
    cy, cx = (s * yy).sum() / s.sum(), (s * xx).sum() / s.sum()
    centre = 0.5 * (LEFT + RIGHT)
    expected = {"below": cy > FOOT, "above": cy < FOOT, "right": cx > centre + 20, "left": cx < centre - 20}
    assert expected[where], (cx, cy)


def test_a_light_from_the_side_casts_a_shadow_not_a_line(tracer):
    s = _canvas(tracer, 0.25, 0.6, 0.53)  # azimuth -90: in the card's plane
    assert (s > 0.5).sum() > 2000


def test_the_contact_line_spans_from_foot_to_foot_and_rises_with_a_part_standing_farther_back():
    """Two legs under a body: the line runs level under the gap between them (the body does not stand on its
    belly). A second block standing farther back (its foot 60 rows higher): the line rises towards it, and the
    cutout is cut into cards standing at different rows."""
    alpha = np.zeros((200, 300), np.float32)
    alpha[20:120, 20:280] = 1.0  # the body
    alpha[120:200, 20:40] = alpha[120:200, 260:280] = 1.0  # the legs
    line = contact_line(alpha)
    assert np.allclose(line[20:280], 200.0)
    assert len(contact_bands(alpha)) == 1  # one card, as before
    alpha = np.zeros((200, 300), np.float32)
    alpha[100:200, 0:100] = 1.0  # near
    alpha[40:140, 200:300] = 1.0  # far, 60 rows higher
    line = contact_line(alpha)
    assert line[50] == pytest.approx(200.0) and line[299] == pytest.approx(140.0, abs=1.0)
    assert 140.0 < line[250] < 170.0  # the hull rises from the near foot to the far one
    feet = [foot for _, _, foot in contact_bands(alpha)]
    assert max(feet) == 200 and min(feet) <= 150


def test_a_tail_or_a_sphere_s_side_is_no_ground():
    """A contact line steeper than a row per column is no ground: it stays level from the lowest point."""
    alpha = np.zeros((200, 300), np.float32)
    alpha[100:200, 50:250] = 1.0
    alpha[20:30, 250:300] = 1.0  # a tail sticking out at the top right
    assert np.allclose(contact_line(alpha)[50:300], 200.0)


def test_a_ball_seen_along_the_ground_stands_on_its_lowest_point_and_a_can_seen_from_above_on_its_base():
    """A footprint on the ground is foreshortened by how steeply the camera looks down on it: seen along the
    ground (horizon through the ball's middle) a ball's rising underside is no ground, its contact line stays
    level within a few rows; seen from above, the elliptic outline of a can's round base is its footprint."""
    canvas = np.zeros((H, W), np.float32)
    yy, xx = np.mgrid[:H, :W]
    canvas[(yy - 400) ** 2 + (xx - 500) ** 2 <= 150**2] = 1.0  # a ball, its lowest row 550
    _, framing = frame_alpha(canvas, 256)
    x0, y0, x1, y1 = framing.bbox
    ball = canvas[y0:y1, x0:x1]
    focal = 0.5 * 256 / np.tan(np.radians(10.0))  # 20 degrees across the frame
    level = footprint_rise(ball, framing, (400 * framing.scale + framing.offset_y, focal))
    steep = footprint_rise(ball, framing, (-300 * framing.scale + framing.offset_y, focal))
    assert level is not None and steep is not None and level < 0.2 < 0.4 < steep
    line = contact_line(ball, level)
    bottom = line[ball.shape[1] // 2]
    assert np.nanmin(line) >= bottom - level * 150 - 1 > bottom - 32  # level within 0.2 rows per column
    assert np.nanmin(contact_line(ball)) < bottom - 40  # without the camera: the underside, up to slope 1
    can = np.zeros((300, 200), np.float32)
    can[:250, :] = 1.0
    can[(yy[:300, :200] - 250) ** 2 / 50**2 + (xx[:300, :200] - 100) ** 2 / 100**2 <= 1.0] = 1.0  # its base
    line = contact_line(can, steep)
    assert line[100] == pytest.approx(300.0, abs=1.0) and line[5] < 285.0  # the base's sides stand farther back


def test_an_object_is_as_deep_as_a_round_cross_section_of_its_local_width():
    alpha = np.zeros((100, 100), np.float32)
    alpha[:, 20:80] = 1.0  # a 60-pixel-wide column touching the array's top and bottom: open there
    alpha[:, 85:91] = 1.0  # a 6-pixel leg beside it
    depth = depth_map(alpha)
    assert depth[50, 50] == pytest.approx(60.0, abs=2.0)  # as deep as it is wide at its middle
    # 5 pixels in from its edge, a circle of radius 30 is 2 sqrt(5 * 55) deep: round, steep at the edges
    assert depth[50, 24] == pytest.approx(2 * np.sqrt(4.5 * 55.5), rel=0.1)
    assert depth[50, 10] == depth[50, 20]  # the fringe takes its nearest solid depth
    assert depth[50, 85:91].max() == pytest.approx(6.0, abs=1.5)  # the leg as deep as it is wide, not the body
    big = depth_map(np.kron(alpha, np.ones((8, 8), np.float32)))  # reduced, worked out, enlarged: the same shape
    assert big[400, 400] == pytest.approx(8 * depth[50, 50], rel=0.05)


def test_a_disk_is_as_deep_as_a_sphere_and_reads_as_thick_as_it_is_wide():
    """The round cross-section of a disk is a ball: each pixel as deep as the sphere's chord through it (the
    local radius is the disk's own, not a step below it), so a ball's shadow is the ellipse it casts."""
    yy, xx = np.mgrid[0:200, 0:200] + 0.5
    rho = np.hypot(xx - 100, yy - 100)
    disk = (rho < 80).astype(np.float32)
    depth = depth_map(disk)
    inner = rho < 72  # the chord is steep at the rim: compared within 0.9 of the radius
    chord = 2 * np.sqrt(np.maximum(80**2 - rho**2, 0))
    assert np.abs(depth - chord)[inner].max() < 0.05 * 160
    assert np.abs(depth - chord)[inner].mean() < 0.01 * 160
    assert read_thickness(disk, depth) == pytest.approx(1.0, abs=0.03)


def test_a_pixel_s_local_radius_is_the_largest_inscribed_disk_that_holds_it():
    """A dumbbell: a pixel of the bar near a ball lies in the ball's disk only where that disk reaches it."""
    yy, xx = np.mgrid[0:100, 0:200] + 0.5
    ball = np.hypot(xx - 50, yy - 50) < 40
    bar = (np.abs(yy - 50) < 10) & (xx > 50) & (xx < 190)
    solid = np.pad(ball | bar, 1)
    d = ndimage.distance_transform_edt(solid).astype(np.float32)
    radius = local_radius(d)[1:-1, 1:-1]
    assert radius[50, 50] == pytest.approx(40, abs=1.0)
    assert radius[30, 30] == pytest.approx(40, abs=1.0)  # off the centre, still in the ball's disk
    assert radius[50, 150] == pytest.approx(10, abs=1.0)  # the bar's half-width
    assert radius[45, 85] == pytest.approx(40, abs=1.0)  # the bar's start, within the ball's disk


def test_under_a_light_from_the_side_a_deep_object_shades_a_band_as_deep_as_itself(post):
    """A light from the card's side: the flat card (turned by ``MIN_INCIDENCE``) casts a sliver; the object,
    reaching behind its card as deep as it is wide, a band of ground."""
    _, framing = frame_alpha(post, 256)
    x0, y0, x1, y1 = framing.bbox
    crop = post[y0:y1, x0:x1].astype(np.float32) / 255
    areas = []
    for tracer in (CardTracer(crop, framing, None), ContactTracer(crop, framing, None)):
        values, x, y = tracer.shadow(0.25, 0.6, 0.53, framing)
        s = np.zeros((H, W), np.float32)
        s[y : y + values.shape[0], x : x + values.shape[1]] = values
        s[FOOT - 300 : FOOT, LEFT:RIGHT] = 0  # the ground hidden by the post
        areas.append(int((s > 0.5).sum()))
    assert areas[1] > 3 * areas[0], areas


def test_small_lights_are_traced_and_broad_ones_left_to_the_network():
    sun, haze = GaussianLight.disk(0.3, 0.6, 0.53), GaussianLight(0.5, 0.2, 0.0004)
    sky = GaussianLight(0.5, 0.2, 0.05)
    plan = LightPlan.of(LightMap([sun, haze, sky]))
    assert plan.traced == (sun, haze) and plan.broad.lights == [sky]
    assert LightPlan.of(LightMap([GaussianLight.disk(0.3, 0.6, 0.53, 0.0)])).traced == ()  # no light, no trace


def test_a_light_between_small_and_broad_is_shared_so_that_resizing_it_never_jumps():
    """A 16-degree disk: half traced, half the network's, the power kept; the share falls steadily with size."""
    softbox = GaussianLight.disk(0.5, 0.3, 16.0, 2.0)
    plan = LightPlan.of(LightMap([softbox]))
    (traced,), broad = plan.traced, plan.broad
    assert traced.intensity == pytest.approx(1.0) and broad.lights[0].intensity == pytest.approx(1.0)
    assert traced.angle == broad.lights[0].angle == 16.0
    shares = [traced_share(a) for a in np.linspace(0.1, 40.0, 400)]
    assert shares[0] == 1.0 and shares[-1] == 0.0 and np.all(np.diff(shares) <= 0)
    assert max(abs(np.diff(shares))) < 0.05


def test_the_command_line_renders_an_angle_light_file_crisply(tmp_path, post):
    """The conventions' canvas-level entry point with a disk light: a crisp shadow on the canvas (the network's
    soft shadow of the sun as a Gaussian around it where that is darker: a crisp step remains)."""
    rgba = np.zeros((H, W, 4), np.uint8)
    rgba[..., 3] = post
    cutout, lights, layer = tmp_path / "cutout.png", tmp_path / "sun.json", tmp_path / "layer.png"
    Image.fromarray(rgba, "RGBA").save(cutout)
    sun = {"u": 0.5, "v": 0.75, "angle": 0.53, "intensity": 1.0}
    lights.write_text(json.dumps({"format": "ssn-shadow-elm", "version": 1, "lights": [sun]}))
    args = ["render", str(cutout), "--light-map", str(lights), "--opacity", "1", "--layer", str(layer)]
    assert main([*args, "--horizon", "300", "--fov", "40"]) == 0
    s = np.asarray(Image.open(layer))[..., 3].astype(np.float32) / 255
    assert s.shape == (H, W)
    rows = np.flatnonzero(s[FOOT:].max(axis=1) > 0.5) + FOOT
    # dark from the contact (within a row of R = 128 of the foot: where the surface model stands the post's base)
    assert rows.size > 40 and s[FOOT + 3, LEFT + 5 : RIGHT - 5].min() > 0.95
    far = int(rows[int(0.8 * (rows.size - 1))])
    assert np.abs(np.diff(s[far])).max() > 0.2  # a crisp edge: a step of a fifth of full darkness in a pixel


def test_a_card_swept_on_a_reduced_copy_casts_the_shadow_it_casts_when_swept_whole():
    """A cutout larger than ``SWEEP_SIZE`` is swept through its depth on a reduced copy and warped from it, the
    card itself warped crisp beside it: its shadow on a canvas twice the size, halved, is the shadow of the
    same scene at half the size, swept whole."""
    shadows = []
    for scale in (1, 2):
        alpha = np.zeros((H * scale, W * scale), np.uint8)
        alpha[(FOOT - 240) * scale : FOOT * scale, (LEFT - 60) * scale : (RIGHT + 60) * scale] = 255  # a fat post
        _, framing = frame_alpha(alpha, 256)
        x0, y0, x1, y1 = framing.bbox
        tracer = ContactTracer(alpha[y0:y1, x0:x1].astype(np.float32) / 255, framing, None)
        values, x, y = tracer.shadow(0.25, 0.6, 0.53, framing)  # from the side: the depth's band is the shadow
        out = np.zeros((H * scale, W * scale), np.float32)
        out[y : y + values.shape[0], x : x + values.shape[1]] = values
        shadows.append(out.reshape(H, scale, W, scale).mean(axis=(1, 3)))
    whole, reduced = shadows
    ground = np.ones((H, W), bool)
    ground[FOOT - 240 : FOOT, LEFT - 60 : RIGHT + 60] = False  # the ground the post hides
    assert whole[ground].sum() > 2000  # a shadow reaching well past the post
    assert zncc(reduced[ground], whole[ground]) > 0.97
    assert np.abs(reduced - whole)[ground].sum() < 0.06 * whole[ground].sum()


@pytest.mark.parametrize("u, v", [(0.5, 0.8), (0.0, 0.75), (0.1, 0.55), (0.3, 0.9)])
def test_the_warp_resamples_every_pixel_the_card_can_reach(tracer, u, v):
    """The warp resamples only the columns of each band that the card's rows can reach (cut where a shadow
    runs behind the camera, a light in front of the object) and, for the crisp card, only where its swept copy
    is partial: the shadow is what resampling every output pixel gives."""
    card = tracer[0].cards[0]
    framing = tracer[1]
    w = hard_light.light_direction(u, v)
    source = card._source(framing.scale)
    blurred = card._blurred(source, card._sigma_rows(source, w, 0.53))
    hmat = card._homography(w, framing, source, (0, 0))
    size = (W, H)
    full = np.asarray(
        Image.fromarray(blurred, "L").transform(
            size, Image.Transform.PERSPECTIVE, tuple((hmat / hmat[2, 2]).ravel()[:8]), Image.Resampling.BILINEAR
        ),
        np.float32,
    ) * np.float32(1 / 255)
    assert full.sum() > 500  # the card casts a shadow onto the canvas
    assert np.array_equal(hard_light._warp(blurred, hmat, size), full)
    under = np.clip(full * 1.5, 0.0, 1.0)  # partial where the card's edges are, dark inside
    got = hard_light._warp(blurred, hmat, size, under.copy(), within=True)
    assert np.array_equal(got, np.maximum(under, full))


@pytest.mark.parametrize("back", [0, 40])
def test_a_surface_read_behind_the_card_casts_from_where_it_stands(post, back):
    """Each pixel's surface placed by its foot's row (``feet``): the post read as standing ``back`` rows above its
    lowest row (farther from the camera) casts its top's shadow where a post standing there casts it, the
    surface's point on the top pixel's own ray above that foot, cast along the light; read as standing on its own
    lowest row, the flat card's shadow."""
    _, framing = frame_alpha(post, 256)
    x0, y0, x1, y1 = framing.bbox
    crop = post[y0:y1, x0:x1].astype(np.float32) / 255
    u, v = 0.1, 0.6  # from behind the camera and its left: the shadow falls away, up the canvas
    card = CardTracer(crop, framing, None, feet=np.full(crop.shape, FOOT - y0 - back, np.float32))
    s = _canvas((card, framing), u, v, 0.53)
    if back == 0:
        assert np.abs(s - _canvas((CardTracer(crop, framing, None), framing), u, v, 0.53)).max() < 2 / 255
    # where the top's shadow lies: the ground below the foot's row, the top pixel's ray at its distance
    centre = 0.5 * (LEFT + RIGHT)
    tip = _cast_at(card, framing, FOOT - back, FOOT - 300 + 0.5, u, v)
    measured = _far_end(s)
    length = np.hypot(*(tip - (centre, FOOT - back)))
    assert length > 100
    assert np.hypot(*(measured - tip)) < 0.03 * length, (measured, tip)


def test_a_surface_read_in_front_of_the_card_casts_from_there_within_its_own_depth(post):
    """A surface whose foot lies below the card's (a ball's front: nearer the camera than where the object
    touches the ground, with air beneath it) casts its shadow from where it stands: the post read as standing
    20 rows in front of its lowest row, deep enough to reach back to its card, casts its lowest pixel's shadow
    where that pixel's point (on its ray above that nearer foot) casts it along the light, nearer the camera
    than the card's shadow starts; with no depth it stays on its card (a part reaches back to the card)."""
    _, framing = frame_alpha(post, 256)
    x0, y0, x1, y1 = framing.bbox
    crop = post[y0:y1, x0:x1].astype(np.float32) / 255
    u, v = 0.1, 0.6  # from behind the camera and its left: the shadow falls away, up the canvas
    feet = np.full(crop.shape, FOOT - y0 + 20, np.float32)
    flat = _canvas((CardTracer(crop, framing, None), framing), u, v, 0.53)
    card = CardTracer(crop, framing, None, thickness=np.full(crop.shape, 200.0, np.float32), feet=feet)
    front = _canvas((card, framing), u, v, 0.53)
    start = _cast_at(card, framing, FOOT + 20, FOOT - 0.5, u, v)[1]
    centre = 0.5 * (LEFT + RIGHT)
    column = slice(int(centre) - 2, int(centre) + 3)

    def near_end(s: np.ndarray) -> float:  # one past the shadow's row nearest the camera, down the post's centre
        return np.flatnonzero((s[:, column] > 0.5).any(axis=1)).max() + 1.0

    assert near_end(flat) == FOOT
    assert start > FOOT + 5
    assert abs(near_end(front) - start) < 1.5, (near_end(front), start)
    assert card.front > 0
    thin = _canvas((CardTracer(crop, framing, None, feet=feet), framing), u, v, 0.53)  # no depth: on the card
    assert np.abs(thin - flat).max() < 2 / 255


def test_a_far_surface_read_ends_each_pixel_s_depth_there_unless_the_artist_gives_the_thickness(post):
    """Pixel heights of two surfaces (a surface model reading the object's depth): the post's visible surface on
    its lowest row, its far surface 40 rows farther back. Each pixel reaches from the one to the other: under a
    light from behind the camera the shadow starts at the post's foot and ends where the top of a post standing
    40 rows back casts it. A thickness the artist gives replaces the reading (the round cross-section, scaled); the
    thickness read, shown beside it, is the reading's."""
    _, framing = frame_alpha(post, 256)
    x0, y0, x1, y1 = framing.bbox
    crop = post[y0:y1, x0:x1].astype(np.float32) / 255
    u, v = 0.1, 0.6  # from behind the camera and its left: the shadow falls away, up the canvas
    rows = np.arange(framing.n, dtype=np.float32) + 0.5
    near = np.repeat((framing.to_frame(0.0, FOOT)[1] - rows)[:, None], framing.n, axis=1)
    heights = np.stack([near, near - 40 * framing.scale])  # frame rows
    deep = ContactTracer(crop, framing, None, heights)
    s = _canvas((deep, framing), u, v, 0.53)
    centre = 0.5 * (LEFT + RIGHT)
    column = slice(int(centre) - 2, int(centre) + 3)
    assert np.flatnonzero((s[:, column] > 0.5).any(axis=1)).max() + 1 == FOOT  # from the visible surface
    tip = _cast_at(deep.cards[0], framing, FOOT - 40, FOOT - 300 + 0.5, u, v)
    measured = _far_end(s)
    length = np.hypot(*(tip - (centre, FOOT)))
    assert length > 100
    assert np.hypot(*(measured - tip)) < 0.03 * length, (measured, tip)  # to the far one
    given = ContactTracer(crop, framing, None, heights, thickness=0.5)
    plain = ContactTracer(crop, framing, None, heights[:1], thickness=0.5)
    assert np.abs(_canvas((given, framing), u, v, 0.53) - _canvas((plain, framing), u, v, 0.53)).max() < 2 / 255
    # the thickness read is the reading's (its deepest segment over the post's width), set or not
    assert plain.thickness_read == pytest.approx(1.0, abs=0.1)  # the round cross-section: as deep as wide
    assert given.thickness_read == deep.thickness_read > 2.0


def test_each_span_of_depth_is_covered_by_its_copies_from_its_start_to_its_end():
    """A pixel's span of depth is drawn as one or two copies of a segment a power of two long: together they
    start at its start and end at its end, with no gap (a span shorter than a unit: one unit from its start)."""
    rng = np.random.default_rng(3)
    start = rng.uniform(0, 50, 400)
    end = start + np.concatenate([rng.uniform(0, 1, 100), rng.uniform(1, 300, 300)])
    at, j, of = hard_light._segments(start, end, 1.0)
    stop = at + 2.0**j
    for i in range(start.size):
        mine = of == i
        assert np.isclose(at[mine].min(), start[i])
        assert np.isclose(stop[mine].max(), max(end[i], start[i] + 1.0))
        assert at[mine].max() <= stop[mine].min() + 1e-9  # the copies overlap or touch


def test_a_pixel_s_shadow_starts_and_ends_where_its_own_depths_say_whatever_the_others():
    """Pixels whose spans of depth differ, one reaching far deeper than the rest, each cast their copies from
    their own surface's depth to their own far end, within a pixel (a sweep in bands of the deepest one's depth
    put every end on a band's edge: a staircase along a shadow's far edge)."""
    rng = np.random.default_rng(5)
    k, col = 40, 500
    near = np.zeros((k, col + 1), np.float32)
    far = np.zeros((k, col + 1), np.float32)
    card = np.zeros((k, col + 1), np.uint8)
    card[:, col] = 255
    near[:, col] = rng.uniform(0, 60, k)
    far[:, col] = near[:, col] + rng.uniform(0, 120, k)
    far[0, col] = near[0, col] + 440  # the deepest
    step = np.array([1.0, 0.0])  # a pixel of depth moves a copy a pixel to the left

    def lines(rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p0 = np.stack([cols, rows, np.ones_like(cols)], axis=1)
        return p0, np.tile([1.0, 0.0, 0.0], (cols.size, 1))

    cells = [(0, k, 0, col + 1, step)]
    out, (ox, oy) = hard_light._swept_card(card, near, far, np.zeros(k), cells, step[None], lines)
    for r in range(k):
        covered = np.flatnonzero(out[r + oy] > 0) - ox
        assert covered.size == covered[-1] - covered[0] + 1  # one run, no holes
        assert abs(covered[-1] - (col - near[r, col])) <= 1.0
        assert abs(covered[0] - (col - far[r, col])) <= 1.5


def test_no_part_of_a_floating_object_reaches_below_its_lowest_point(post):
    """The post lifted 100 rows, read as very deep and looked at from above: each pixel's depth runs along its own
    camera ray, which descends, and ends no lower than the post's lowest point (the object floats whole); the same
    post resting reaches down to the ground."""
    _, framing = frame_alpha(post, 256)
    x0, y0, x1, y1 = framing.bbox
    crop = post[y0:y1, x0:x1].astype(np.float32) / 255
    lowest = FOOT - y0  # rows of the crop
    deep = np.full(crop.shape, 2000.0, np.float32)
    camera = (-150.0, 300.0)  # horizon above the frame, focal length (frame pixels): looking down
    for lift in (0, 100):
        card = CardTracer(crop, framing, camera, foot=lowest + lift, thickness=deep, lift=lift)
        source = card._full
        heights = card._row_heights(source)
        drop = -card._depth_ray(heights)[:, 1] * card._world_per_pixel  # world height lost per pixel of depth
        _, far = card._sweep_depths(source, 1)
        rows = np.flatnonzero(source.alpha.any(axis=1))
        ends = heights[rows] - far[rows].max(axis=1) * drop[rows]  # the height where each row's depth ends
        assert drop[rows].min() > 0  # looking down
        bottom = card._frame_row_geometry(np.array([(y0 + lowest) * framing.scale + framing.offset_y]))[0][0]
        if lift:
            assert bottom > 0.1 * card.height and ends.min() >= bottom - 1e-6, (ends.min(), bottom)
        else:
            assert ends.min() < 1e-3 * card.height


@pytest.mark.parametrize("u, v", [(0.1, 0.6), (0.45, 0.7), (0.9, 0.7)])
def test_a_part_read_behind_its_card_leaves_no_line_where_the_card_stands(post, u, v):
    """The post read as standing 40 rows behind its lowest row casts its shadow from there; the blurred edges of
    its copy (its sides, at the crop's border) go back with it, so nothing is left on the ground where the card's
    own shadow would lie: before, its two edges stayed, thin lines up to 0.35 dark that a low sun drew out into a
    dotted line (the README horse's)."""
    _, framing = frame_alpha(post, 256)
    x0, y0, x1, y1 = framing.bbox
    crop = post[y0:y1, x0:x1].astype(np.float32) / 255
    behind = _canvas(
        (CardTracer(crop, framing, None, feet=np.full(crop.shape, FOOT - y0 - 40, np.float32)), framing), u, v, 0.53
    )
    flat = _canvas((CardTracer(crop, framing, None), framing), u, v, 0.53)
    where_the_card_casts = ndimage.binary_dilation(flat > 0.02, iterations=2)
    away_from_its_shadow = ~ndimage.binary_dilation(behind > 0.5, iterations=8)
    left = behind[where_the_card_casts & away_from_its_shadow]
    assert left.size > 2000  # the two shadows lie apart
    assert left.max() < 1 / 255
