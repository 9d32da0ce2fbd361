"""Analytic cases for the occlusion-basis renderer: sphere, box, thin pole, disc AO, texel weights."""

from __future__ import annotations

import numpy as np
import pytest

from ssn_engine.hemisphere import stratified_directions, texel_edges, texel_weights
from training.data import meshes, procedural
from training.data import render_bases as rb

from helpers import hard_shadow, light_direction


def _normalised(mesh):
    return meshes.normalise(meshes.clean(mesh))


@pytest.mark.parametrize("elevation,azimuth", [(30.0, 90.0), (50.0, 0.0), (20.0, -135.0)])
def test_sphere_shadow_is_the_analytic_ellipse(elevation, azimuth):
    mesh = _normalised(procedural.uv_sphere(1.0, (0, 1.0, 0), rings=64, segments=128))
    r = 0.5 / np.sqrt(3)  # AABB diagonal 1: cube of side 2r
    cam = rb.view_camera(mesh.vertices, 192, 45.0, 30.0)
    w = light_direction(cam, elevation, azimuth)
    occ = hard_shadow(mesh, cam, w)
    g, down = cam.ground_points()
    # Ellipse: centre = sphere centre projected along w, semi-axes r (across) and r / sin(e) (along).
    centre = np.array([0.0, r, 0.0]) - w * r / w[1]
    along = np.array([w[0], 0.0, w[2]]) / np.hypot(w[0], w[2])
    across = np.array([-along[2], 0.0, along[0]])
    d = g - centre
    rho = np.sqrt((d @ along / (r / np.sin(np.radians(elevation)))) ** 2 + (d @ across / r) ** 2)
    inside, outside = down & (rho < 0.99), ~down | (rho > 1.01)
    assert occ[inside].all() and not occ[outside].any()
    assert inside.sum() > 500  # the ellipse covers many pixels
    # Its area in pixels matches the analytic count within the faceting tolerance.
    assert abs(int(occ.sum()) - int((down & (rho < 1)).sum())) <= 0.02 * (rho < 1).sum()


def test_box_shadow_matches_the_slab_test_everywhere():
    mesh = _normalised(procedural.box((0.6, 0.9, 0.4)))
    cam = rb.view_camera(mesh.vertices, 160, 50.0, 15.0)
    lo, hi = mesh.vertices.min(0), mesh.vertices.max(0)
    g, down = cam.ground_points()
    for elevation, azimuth in [(25.0, 60.0), (70.0, -20.0), (10.0, 180.0), (40.0, 0.0)]:
        w = light_direction(cam, elevation, azimuth)
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = (lo - g) / w, (hi - g) / w
        tmin = np.nanmax(np.minimum(t1, t2), axis=-1)
        tmax = np.nanmin(np.maximum(t1, t2), axis=-1)
        exact = down & (tmax >= np.maximum(tmin, 0.0))
        occ = hard_shadow(mesh, cam, w).astype(bool)
        assert exact.sum() > 100
        assert (occ != exact).sum() <= 2, (elevation, azimuth)  # only pixel centres exactly on an edge may differ


def test_thin_pole_casts_a_full_length_thin_shadow():
    radius = 0.008
    mesh = _normalised(procedural.cylinder(radius, 1.0, 16))
    height = mesh.vertices[:, 1].max()
    r = radius * height  # the normalisation scales by 1 / diagonal ~ 1 / height
    cam = rb.view_camera(mesh.vertices, 256, 45.0, 30.0)
    g, down = cam.ground_points()
    elevation = 58.0  # the shadow's tip stays inside the frame
    w = light_direction(cam, elevation, 0.0)  # light ahead, behind the pole: shadow along +z, down the frame
    occ = hard_shadow(mesh, cam, w).astype(bool)
    length = height / np.tan(np.radians(elevation))
    pts = g[occ]
    assert len(pts) > 50
    assert np.all(np.abs(pts[:, 0]) <= r + 1e-9)  # within the strip x in [-r, r]
    assert np.all((pts[:, 2] >= -r - 1e-9) & (pts[:, 2] <= length + r + 1e-9))
    rows = np.flatnonzero(occ.any(axis=1))
    assert np.array_equal(rows, np.arange(rows[0], rows[-1] + 1))  # unbroken from base to tip
    spacing = np.abs(np.diff(g[:, 128, 2]))[rows[0] - 1 : rows[-1] + 1].max()
    assert g[-1, 128, 2] > length + 0.05
    assert pts[:, 2].max() > length - 2 * spacing  # reaches the tip


def test_disc_ao_is_the_view_factor():
    radius, height = 0.4, 0.12
    mesh = procedural.disc(radius, height, 256)
    topo = meshes.topology(mesh)
    rend = rb.render_view(mesh, topo, 0.0, 30.0, 45.0, 96, 16, 16, np.random.default_rng(1))
    g, down = rend.camera.ground_points()
    d = np.hypot(g[..., 0], g[..., 2])
    # View factor from a horizontal ground element at offset d to the parallel disc above it.
    q = height**2 + d**2
    blocked = 0.5 * (1 - (q - radius**2) / np.sqrt((q + radius**2) ** 2 - 4 * radius**2 * d**2))
    a = rend.ao.astype(np.float64) ** 3
    near = down & (d < 1.0)
    assert near.sum() > 1000
    err = np.abs(a - (1 - blocked))[near]
    assert err.mean() < 0.004 and err.max() < 0.03
    assert np.all(rend.ao[~down] == 1.0)


def test_texel_weights_and_samples():
    for h in (8, 16):
        w = texel_weights(h)
        assert abs(w.sum() - np.pi) < 1e-12
        e, _ = texel_edges(h)
        # each band's exact integral of cos(theta) dw = pi (sin^2 e_top - sin^2 e_bottom)
        np.testing.assert_allclose(w.sum(axis=1), np.pi * (np.sin(e[:-1]) ** 2 - np.sin(e[1:]) ** 2), rtol=1e-12)
    d = stratified_directions(16, 16, np.random.default_rng(0))
    elev = np.degrees(np.arcsin(d[..., 1]))
    row_top = 90 * (1 - np.arange(16) / 16)
    assert np.all(elev <= row_top[:, None, None] + 1e-9) and np.all(elev >= row_top[:, None, None] - 90 / 16 - 1e-9)


def test_rows_above_the_horizon_have_no_shadow_and_full_ao():
    mesh = _normalised(procedural.box((0.5, 1.0, 0.5)))
    rend = rb.render_view(mesh, meshes.topology(mesh), 0.0, 0.0, 50.0, 64, 16, 16, np.random.default_rng(0))
    _, down = rend.camera.ground_points()
    assert (~down).sum() > 0
    assert rend.counts[..., ~down].max() == 0 and np.all(rend.ao[~down] == 1.0)
    assert rend.ao[down].min() < 0.2  # next to the box the ground is strongly occluded


def test_mask_is_exact_coverage_of_a_box():
    mesh = _normalised(procedural.box((0.7, 0.7, 0.1)))
    cam = rb.view_camera(mesh.vertices, 64, 40.0, 0.0)
    topo = meshes.topology(mesh)
    m = rb.mask_coverage(mesh.vertices, mesh.faces, topo, cam, 16)
    uv = cam.project(mesh.vertices)
    front = mesh.vertices[:, 2] > 0  # the face towards the camera bounds the silhouette at pitch 0
    c0, r0 = uv[front].min(0)
    c1, r1 = uv[front].max(0)
    assert abs(r0 - round(0.03 * 64)) < 1e-9  # framing: top on row round(0.03 N)
    assert abs(m.sum() - (c1 - c0) * (r1 - r0)) < 0.05 * (c1 - c0) * (r1 - r0) ** 0.5
    assert m.min() == 0.0 and m.max() == 1.0 and 0 < m[int(r0), int(c0)] < 1  # antialiased corner
