"""The realistic simulated camera (`realism: real`): each imperfection shows in a rendered frame with about
its configured magnitude (board plane offset and tilt, noise growing with range, holes and flying pixels
at edges and on dark faces, the side band without depth, drifting colour, a shadowing light, clutter the
judge never sees); `ideal` gives the exact depth; the `--realism` switch reaches the workcell."""

import math

import numpy as np
import pytest

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.devices.sim.config import REALISM_ENV, load_camera_config, load_sim_config, resolve_realism
from armlab.scene import Scene, SceneObject

CAMERA = load_camera_config()
REAL = CAMERA.realism
TAGS_CENTRE_M = (0.0, 0.125)  # the rx200_armlab board tags' centre (config/workcells/rx200_armlab.yaml)


def board_points(cell, depth_mm):
    """Camera-frame points (mm) of the pixels whose rays meet the true board away from the arm, the tags,
    the clutter and the image's sides, with their pixels' (row, col) and whether the depth is valid."""
    truth = cell.truth()["camera"]
    T = np.array(truth["T_world_camera"])
    k = CAMERA.intrinsics
    v, u = np.mgrid[0:CAMERA.height, 0:CAMERA.width]
    rays = np.dstack([(u - k.cx) / k.fx, (v - k.cy) / k.fy, np.ones(u.shape)])
    world_dirs = rays @ T[:3, :3].T
    scale = -T[2, 3] / world_dirs[..., 2]
    hit = T[:3, 3] + world_dirs * scale[..., None]
    x, y = hit[..., 0], hit[..., 1]
    keep = (np.abs(x) < 0.38) & (y > 0.0) & (y < 0.38) & (np.hypot(x, y) > 0.2)  # clear of the arm and the clutter
    keep &= (u > 100) & (u < CAMERA.width - 100)
    for tx, ty in ((-0.25, -0.025), (0.25, -0.025), (0.25, 0.275), (-0.25, 0.275)):
        keep &= np.hypot(x - tx, y - ty) > 0.04
    z = depth_mm.astype(float)
    points = rays * z[..., None]
    return points, keep, T


def fit_plane(points):
    centre = points.mean(axis=0)
    normal = np.linalg.svd(points - centre, full_matrices=False)[2][2]
    return normal if normal[2] > 0 else -normal, centre


def plane_offset_and_tilt(cell, depth_mm):
    """The depth's board plane against the true board: its height (mm, negative: behind) along the true
    normal at the board tags' centre, and the angle between the planes (deg)."""
    points, keep, T = board_points(cell, depth_mm)
    selected = points[keep & (depth_mm > 0)]
    normal, centre = fit_plane(selected[::5])
    residual = (selected - centre) @ normal
    normal, centre = fit_plane(selected[np.abs(residual) < 3.0][::3])
    true_normal = T[:3, :3].T @ np.array([0.0, 0.0, 1.0])  # world +z (toward the camera) in the camera frame
    board_centre = T[:3, :3].T @ (np.array([*TAGS_CENTRE_M, 0.0]) - T[:3, 3]) * 1000.0
    ray = board_centre / np.linalg.norm(board_centre)
    on_depth_plane = ray * float(normal @ centre) / float(normal @ ray)
    offset_mm = float(true_normal @ (on_depth_plane - board_centre))
    tilt_deg = math.degrees(math.acos(min(1.0, abs(float(normal @ true_normal)))))
    return offset_mm, tilt_deg


def patch_noise_mm(depth_mm, keep, patch=16):
    """Median residual std after a plane fit in each patch of valid board pixels."""
    stds = []
    for v0 in range(0, depth_mm.shape[0] - patch, patch):
        for u0 in range(0, depth_mm.shape[1] - patch, patch):
            window = depth_mm[v0:v0 + patch, u0:u0 + patch].astype(float)
            mask = keep[v0:v0 + patch, u0:u0 + patch] & (window > 0)
            if mask.sum() < 0.95 * patch * patch:
                continue
            vv, uu = np.nonzero(mask)
            A = np.column_stack([uu, vv, np.ones_like(uu)])
            z = window[mask]
            stds.append(np.std(z - A @ np.linalg.lstsq(A, z, rcond=None)[0]))
    return float(np.median(stds))


@pytest.fixture(scope="module")
def real_cell():
    """A real camera over one block, its plane offset and tilt set to 0: edges and noise are then measured
    against the clean render directly (the offset and tilt have their own test)."""
    block = SceneObject(id="b1", type="block", color="red", size="large", position_m=(0.15, 0.2, 0.019))
    config = SimWorkcellConfig(seed=3, realism="real", depth_offset_m=0.0, depth_tilt_deg=0.0)
    with SimWorkcell(config, scene=Scene(objects=[block])) as cell:
        yield cell


@pytest.mark.parametrize("offset_m,tilt_deg", [(-0.011, 1.4), (0.007, 0.8)])
def test_board_plane_offset_and_tilt_as_configured(offset_m, tilt_deg):
    with SimWorkcell(SimWorkcellConfig(seed=1, realism="real", depth_offset_m=offset_m, depth_tilt_deg=tilt_deg)) as cell:
        offset_mm, measured_tilt_deg = plane_offset_and_tilt(cell, cell.render().depth_mm)
    assert offset_mm == pytest.approx(1000.0 * offset_m, abs=0.5)
    assert measured_tilt_deg == pytest.approx(tilt_deg, abs=0.15)


def test_ideal_depth_is_exact_and_flat():
    with SimWorkcell(SimWorkcellConfig(seed=1, realism="ideal", depth_noise=False, color_noise=False)) as cell:
        raw = cell.render_raw()
        frame = cell.render()
        offset_mm, tilt_deg = plane_offset_and_tilt(cell, frame.depth_mm)
    assert np.array_equal(frame.depth_mm, np.floor(raw.depth_m * 1000.0 + 0.5).astype(np.uint16))
    assert np.array_equal(frame.color_bgr, raw.rgb[..., ::-1])
    assert abs(offset_mm) < 0.3 and tilt_deg < 0.05


def test_depth_noise_grows_with_range(real_cell):
    near = real_cell.render().depth_mm
    points, keep, _ = board_points(real_cell, near)
    near_range_mm = float(np.median(near[keep & (near > 0)]))
    near_std = patch_noise_mm(near, keep)
    real_cell.knock_camera([0.0, 0.0, -0.6], [0.0, 0.0, 0.0])  # 0.6 m further back along the optical axis
    try:
        far = real_cell.render().depth_mm
        _, far_keep, _ = board_points(real_cell, far)
        far_range_mm = float(np.median(far[far_keep & (far > 0)]))
        far_std = patch_noise_mm(far, far_keep)
    finally:
        real_cell.knock_camera([0.0, 0.0, 0.6], [0.0, 0.0, 0.0])
    quantisation = 1.0 / 12.0  # the 1 mm steps of the uint16 depth add this variance
    for range_mm, std in ((near_range_mm, near_std), (far_range_mm, far_std)):
        expected = REAL.noise_std_at_1m_mm * (range_mm / 1000.0) ** REAL.noise_range_exponent
        assert math.sqrt(max(0.0, std ** 2 - quantisation)) == pytest.approx(expected, rel=0.2), (range_mm, std)
    assert far_std > near_std * 1.15


def test_holes_and_flying_pixels_at_edges_and_on_dark_faces(real_cell):
    raw = real_cell.render_raw()
    depth = real_cell.render().depth_mm.astype(float)
    clean = raw.depth_m * 1000.0
    import cv2

    kernel = np.ones((2 * REAL.edge_band_px + 1,) * 2, np.uint8)
    near, far = cv2.erode(clean, kernel), cv2.dilate(clean, kernel)
    inner = np.zeros(depth.shape, bool)
    inner[20:-20, 20:CAMERA.width - 20 - REAL.no_depth_columns[1]] = True
    band = (far - near > REAL.edge_step_mm + 5.0) & inner
    holes = float((depth[band] == 0).mean())
    off_surface = (depth > 0) & (np.abs(depth - clean) > 3.0)  # a reading 3 mm off the true surface
    flying = float(off_surface[band].mean())
    assert holes == pytest.approx(REAL.edge_hole_fraction + CAMERA.depth.dropout_fraction, abs=0.03)
    assert 0.6 * REAL.edge_flying_fraction < flying <= REAL.edge_flying_fraction + 0.03
    grey = cv2.cvtColor(raw.rgb, cv2.COLOR_RGB2GRAY)
    dark = (grey < REAL.dark_level - 5) & ~(far - near > 3.0) & inner
    assert dark.sum() > 2000  # the arm's dark links
    assert float((depth[dark] == 0).mean()) == pytest.approx(REAL.dark_hole_fraction, abs=0.02)
    light = (grey > REAL.dark_level + 20) & ~(far - near > 3.0) & inner
    assert float((depth[light] == 0).mean()) < 0.01  # elsewhere only the rare dropout
    assert not depth[:, CAMERA.width - REAL.no_depth_columns[1]:].any()


def test_white_balance_and_exposure_drift_within_their_bounds(real_cell):
    real = real_cell.camera._noise.real
    gains = np.array([real.color_gains(t) for t in np.linspace(0.0, 3.0 * REAL.drift_period_s, 400)])
    base = np.array(REAL.white_balance_gains)
    relative = gains / base
    bound = (1.0 + np.array(REAL.white_balance_drift)) * (1.0 + REAL.exposure_drift)
    assert np.all(relative <= bound + 1e-9) and np.all(relative >= (2.0 - bound) * (1.0 - REAL.exposure_drift) - 1e-9)
    assert np.ptp(gains[:, 0] / gains[:, 1]) > REAL.white_balance_drift[0]  # R/G wanders over the period
    assert np.ptp(gains[:, 1]) > REAL.exposure_drift  # exposure wanders


def test_the_colour_gains_scale_each_channel_rounded_and_saturated(real_cell):
    real = real_cell.camera._noise.real
    rgb = np.random.default_rng(3).integers(0, 256, (40, 60, 3), dtype=np.uint8)
    for t in (0.0, 0.37 * REAL.drift_period_s, 2.1 * REAL.drift_period_s):
        gains = np.array(real.color_gains(t))
        expected = np.clip(np.rint(rgb * gains), 0, 255).astype(np.uint8)  # R by the R gain, G by G, B by B
        np.testing.assert_array_equal(real.color(rgb, t), expected)


def test_real_frame_colour_cast_light_and_clutter(real_cell):
    import cv2

    real = real_cell.render().color_bgr.astype(float)
    with SimWorkcell(SimWorkcellConfig(seed=3, realism="ideal", color_noise=False, depth_noise=False),
                     scene=real_cell.scene) as ideal_cell:
        ideal = ideal_cell.render().color_bgr.astype(float)
        _, keep, _ = board_points(ideal_cell, ideal_cell.render().depth_mm)
    board = keep & (cv2.cvtColor(ideal.astype(np.uint8), cv2.COLOR_BGR2GRAY) > 120)
    real_bgr, ideal_bgr = real[board].mean(axis=0), ideal[board].mean(axis=0)
    b_over_g = (real_bgr[0] / real_bgr[1]) / (ideal_bgr[0] / ideal_bgr[1])
    assert b_over_g == pytest.approx(REAL.white_balance_gains[2], abs=REAL.white_balance_drift[2] + 0.02)
    # The second light and its shadows make the board uneven (the real frames: 9-32 % over a 3x3 grid).
    grey_real = cv2.cvtColor(real.astype(np.uint8), cv2.COLOR_BGR2GRAY).astype(float)
    grey_ideal = cv2.cvtColor(ideal.astype(np.uint8), cv2.COLOR_BGR2GRAY).astype(float)
    rows, cols = np.nonzero(board)
    def spread(grey):
        cells = []
        for rs in np.array_split(np.unique(rows), 3):
            for cs in np.array_split(np.unique(cols), 3):
                sel = board & np.isin(np.arange(grey.shape[0])[:, None], rs) & np.isin(np.arange(grey.shape[1])[None, :], cs)
                if sel.sum() > 500:
                    cells.append(grey[sel].mean())
        return (max(cells) - min(cells)) / np.mean(cells)
    assert spread(grey_real) > 0.08 > spread(grey_ideal) + 0.03
    # Clutter: drawn where the configured items lie, absent from the scene and the judge's truth.
    assert real_cell.model.ngeom > ideal_cell.model.ngeom
    assert [obj["id"] for obj in real_cell.truth()["objects"]] == ["b1"]
    clutter = [i for i in range(real_cell.model.ngeom) if (real_cell.model.geom(i).name or "").startswith("clutter:")]
    assert clutter and all(real_cell.model.geom_contype[i] == 0 and real_cell.model.geom_conaffinity[i] == 0 for i in clutter)


def test_realism_is_chosen_by_caller_then_environment_then_config(monkeypatch):
    sim = load_sim_config().model_copy(update={"realism": "real"})
    monkeypatch.delenv(REALISM_ENV, raising=False)
    assert resolve_realism(None, sim) == "real"
    assert resolve_realism(None, sim.model_copy(update={"realism": "ideal"})) == "ideal"
    monkeypatch.setenv(REALISM_ENV, "ideal")
    assert resolve_realism(None, sim) == "ideal"
    assert resolve_realism("real", sim) == "real"
    monkeypatch.setenv(REALISM_ENV, "sometimes")
    with pytest.raises(ValueError, match=REALISM_ENV):
        resolve_realism(None, sim)


def test_realism_flag_reaches_the_workcell():
    from armlab.cli import build_parser
    from armlab.cli.serve_cmd import build_station_config
    from armlab.tasks.evaluate import run_one

    args = build_parser().parse_args(["serve", "--realism", "real"])
    assert build_station_config(args).sim.realism == "real"
    args = build_parser().parse_args(["eval", "pick_sort", "--level", "3", "--seeds", "0", "--realism", "real"])
    assert args.realism == "real"
    # run_one hands the value on to the episode's SimWorkcellConfig: a bad one fails there, naming it.
    crashed = run_one("pick_sort", 3, 0, realism="sometimes")
    assert crashed["crashed"] and "realism" in crashed["failures"][-1]
    args = build_parser().parse_args(["serve", "--realism", "camera"])
    assert build_station_config(args).sim.realism == "camera"
    # None: the suite's $ARMLAB_REALISM (tests/conftest.py); camera: the real camera and board, the exact arm.
    for requested, expected, real_camera, real_arm in (("real", "real", True, True), ("camera", "camera", True, False),
                                                       (None, "ideal", False, False)):
        cell = SimWorkcell(SimWorkcellConfig(realism=requested))  # not started: no renderer needed
        try:
            assert cell.realism == expected and (cell.camera._noise.real is not None) == real_camera
            assert any((cell.model.geom(i).name or "").startswith("clutter:") for i in range(cell.model.ngeom)) == real_camera
            assert (cell._publisher is not None) == real_arm  # the real arm's joint-state publisher
        finally:
            cell.close()


def test_bad_realism_config_is_refused_naming_the_field():
    from pydantic import ValidationError

    from armlab.devices.sim.config import ClutterItem, SimCameraConfig

    with pytest.raises(ValidationError, match="points_m"):
        ClutterItem(kind="cable", points_m=[[0.0, 0.0]], rgba=[0, 0, 0, 1])
    data = CAMERA.model_dump()
    data["realism"].update(edge_hole_fraction=0.8, edge_flying_fraction=0.5)
    with pytest.raises(ValidationError, match="edge_hole_fraction"):
        SimCameraConfig.model_validate(data)


def test_noise_draws_are_the_bank_images_rolled_by_the_drawn_rows_and_columns():
    # The realistic depth's per-frame noise is a bank image rolled by random rows and columns; it is read as a window
    # of the image tiled two by two instead of np.roll's copy. Each draw is np.roll's image for the same draws, at
    # the edges too (a window one row or column off would shift a whole image of noise).
    from armlab.devices.sim.realism import RealCamera

    camera = RealCamera(CAMERA, REAL, np.random.default_rng(5), depth_noise=True)
    height, width = CAMERA.height, CAMERA.width
    for seed in range(6):
        camera._rng = np.random.default_rng(seed)
        drawn = camera._bank(camera._uniform)
        twin = np.random.default_rng(seed)  # the same draws: which image, then rows, then columns
        image = camera._uniform[int(twin.integers(len(camera._uniform)))][:height, :width]
        rolled = np.roll(image, (int(twin.integers(height)), int(twin.integers(width))), axis=(0, 1))
        assert drawn.shape == (height, width)
        np.testing.assert_array_equal(drawn, rolled)
