"""Small things a user hits (issue 9 item 6), on a fresh station: the detections list says why it is empty
before calibration; the hover readout gives pixel u, v, raw depth and the right z, on the top-down view too,
where the Tags and Grid layers draw; the move-time input refuses text and uses the server's limit; a
double-click in grab mode sends one grab; the e-stop banner reads cleanly; the depth view has a colour scale."""

from __future__ import annotations

import pytest
import yaml

from browser_helpers import REPO, canvas_point, open_page, wait_frames
from conftest import running_server

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def fresh(tmp_path_factory):
    with running_server(tmp_path_factory.mktemp("fresh")) as srv:
        yield srv


@pytest.fixture(scope="module")
def page(browser, fresh):
    page = open_page(browser, f"{fresh.base_url}/?token={fresh.token}")
    wait_frames(page, 2)
    page.wait_for_function("window.armlab.status && window.armlab.connected")
    page.requests = []
    page.on("request", lambda r: page.requests.append((r.method, r.url)))
    yield page
    page.close()


def posts_to(page, path: str) -> int:
    page.evaluate("0")  # a round trip: Playwright delivers the request events it has received
    return sum(1 for method, url in page.requests if method == "POST" and url.split("?")[0].endswith(path))


def truth_blocks(server) -> list[dict]:
    truth = server.get("/api/sim/truth")
    return [o for o in truth["objects"] if o.get("type", "block") == "block"]


def calibrate(page, server) -> None:
    page.click("#btn-calibrate")
    server.wait_status(lambda s: s["calibrated"] and s["state"] == "idle", 60.0, "calibrated")
    page.wait_for_function("document.getElementById('calib-badge').dataset.ok === 'true'", timeout=10_000)
    page.wait_for_function("window.armlab.detections.length >= 3", timeout=20_000)


def test_detections_list_says_why_it_is_empty_before_calibration(page, fresh):
    assert not fresh.get("/api/status")["calibrated"]
    page.wait_for_function("document.getElementById('det-body').textContent.length > 0", timeout=10_000)
    assert "calibrat" in page.text_content("#det-body").lower()
    calibrate(page, fresh)
    assert "calibrat" not in page.text_content("#det-body").lower()
    assert page.errors == []


def test_hover_readout_gives_pixel_depth_and_z_on_camera_and_top_down_views(page, fresh):
    top_mm = [1000 * (b["position_m"][2] + 0.019) for b in truth_blocks(fresh)]  # large cubes: 38 mm
    det = page.evaluate("window.armlab.detections[0]")
    x, y = canvas_point(page, *det["center_px"])
    page.mouse.move(x, y)
    page.wait_for_function("document.getElementById('hover-world').dataset.pixel !== undefined", timeout=5_000)
    u, v, depth_mm = page.evaluate("JSON.parse(document.getElementById('hover-world').dataset.pixel)")
    assert abs(u - det["center_px"][0]) < 3 and abs(v - det["center_px"][1]) < 3
    assert 500 < depth_mm < 1500, depth_mm  # the camera is ~1 m above the board
    assert f"u {round(u)} v {round(v)}" in page.text_content("#hover-world")
    z_mm = 1000 * page.evaluate("JSON.parse(document.getElementById('hover-world').dataset.positionM)[2]")
    assert min(abs(z_mm - t) for t in top_mm) < 6, (z_mm, top_mm)

    page.click("#view-select button[data-view='topdown']")
    page.wait_for_function("document.getElementById('live').dataset.view === 'topdown'", timeout=15_000)
    block = truth_blocks(fresh)[0]
    point = page.evaluate(
        """([x, y]) => {
            const live = window.armlab.live, c = document.getElementById('live'), r = c.getBoundingClientRect();
            const b = live.topdownBounds();
            const fu = (x - b.xMin) / (b.xMax - b.xMin) * c.width, fv = (b.yMax - y) / (b.yMax - b.yMin) * c.height;
            const s = Math.min(r.width / c.width, r.height / c.height);
            return [r.left + (r.width - c.width * s) / 2 + fu * s, r.top + (r.height - c.height * s) / 2 + fv * s];
        }""",
        block["position_m"][:2],
    )
    page.evaluate("delete document.getElementById('hover-world').dataset.pixel")
    page.mouse.move(*point)
    page.wait_for_function("document.getElementById('hover-world').dataset.pixel !== undefined", timeout=5_000)
    z_mm = 1000 * page.evaluate("JSON.parse(document.getElementById('hover-world').dataset.positionM)[2]")
    assert abs(z_mm - 1000 * (block["position_m"][2] + 0.019)) < 6, z_mm
    assert page.errors == []


def count_green(page) -> int:
    """Canvas pixels in the page's top-down layer colour (#00ff66), after the next frame is drawn."""
    frames = int(page.eval_on_selector("#live", "c => Number(c.dataset.frames)"))
    wait_frames(page, frames + 1)
    return page.evaluate(
        """() => {
            const c = document.getElementById('live');
            const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
            let n = 0;
            for (let i = 0; i < d.length; i += 4) if (d[i] < 20 && d[i + 1] > 235 && d[i + 2] > 80 && d[i + 2] < 125) n++;
            return n;
        }"""
    )


def test_top_down_tags_and_grid_layers_draw(page, fresh):
    if page.evaluate("document.getElementById('live').dataset.view") != "topdown":
        page.click("#view-select button[data-view='topdown']")
        page.wait_for_function("document.getElementById('live').dataset.view === 'topdown'", timeout=15_000)
    for layer in ("tags", "grid"):
        page.set_checked(f"#layer-{layer}", False)
    none = count_green(page)
    page.set_checked("#layer-grid", True)
    grid = count_green(page)
    page.set_checked("#layer-grid", False)
    page.set_checked("#layer-tags", True)
    tags = count_green(page)
    assert grid > none + 200 and tags > none + 50, (none, grid, tags)
    page.click("#view-select button[data-view='color']")
    assert page.errors == []


def test_move_time_refuses_text_and_uses_the_servers_limit(page, fresh):
    limit_s = yaml.safe_load((REPO / "config" / "station.yaml").read_text())["max_moving_time_s"]
    page.wait_for_function("!document.getElementById('btn-send-joints').disabled", timeout=10_000)
    before = posts_to(page, "/api/arm/joints")
    for text, says in (("abc", "not a number"), (str(limit_s + 1), f"at most {limit_s:g} s")):
        page.fill("#jog-time", text)
        page.click("#btn-send-joints")
        page.locator(".toast", has_text=says).first.wait_for(timeout=5_000)
    assert posts_to(page, "/api/arm/joints") == before
    page.fill("#jog-time", "1.5")
    assert page.errors == []


def test_double_click_in_grab_mode_sends_one_grab(page, fresh):
    page.click("#click-mode button[data-mode='grab']")
    det = page.evaluate("window.armlab.detections[0]")
    before_job = (fresh.get("/api/status").get("job") or {}).get("id")
    before = posts_to(page, "/api/grab")
    page.mouse.dblclick(*canvas_point(page, *det["center_px"]))
    status = fresh.wait_status(
        lambda s: (s.get("job") or {}).get("id") not in (None, before_job) and s["job"]["state"] != "running"
        and s["state"] == "idle", 60.0, "the grab to end")
    assert posts_to(page, "/api/grab") == before + 1
    if status["gripper"]["holding"]:
        fresh.post("/api/drop?wait=true", {"position_m": det["position_m"]})
    page.click("#click-mode button[data-mode='inspect']")
    assert page.errors == []


def test_estop_banner_reads_cleanly(page, fresh):
    page.click("#btn-estop")
    page.wait_for_selector("#halt-banner:not([hidden])", timeout=5_000)
    text = page.text_content("#halt-text")
    assert text.lower().count("reset") == 1, text
    assert text[0].isupper() and text.endswith("."), text
    fresh.post("/api/reset")
    page.wait_for_selector("#halt-banner", state="hidden", timeout=5_000)
    assert page.errors == []


def test_depth_view_has_a_colour_scale(page, fresh):
    page.click("#view-select button[data-view='depth']")
    page.wait_for_function("document.getElementById('live').dataset.view === 'depth'", timeout=15_000)
    colours = page.evaluate(
        """() => {
            const c = document.getElementById('live'), ctx = c.getContext('2d');
            const x = Math.round(c.width * (1 - 1 / 64 - 8 / 1280) - 2), seen = new Set();
            for (let y = Math.round(c.height * 0.1); y < c.height * 0.9; y += 8) {
                const [r, g, b] = ctx.getImageData(x, y, 1, 1).data;
                seen.add(`${r >> 5},${g >> 5},${b >> 5}`);
            }
            return seen.size;
        }"""
    )
    assert colours >= 8, colours  # a ramp from warm to cold, not the board's flat depth
    # Near (warm, red) at the top of the scale, far (cold, blue) at its bottom, with the range in mm beside it.
    top, bottom = page.evaluate(
        """() => {
            const c = document.getElementById('live'), ctx = c.getContext('2d');
            const x = Math.round(c.width * (1 - 1 / 64 - 8 / 1280) - 2);
            return [Array.from(ctx.getImageData(x, Math.round(c.height * 0.08), 1, 1).data),
                    Array.from(ctx.getImageData(x, Math.round(c.height * 0.92), 1, 1).data)];
        }"""
    )
    assert top[0] > 2 * top[2] and bottom[2] > bottom[0], (top, bottom)
    # The scale's white frame: a light column just left of the bar over its whole height.
    light = page.evaluate(
        """() => {
            const c = document.getElementById('live'), ctx = c.getContext('2d'), w = c.width, h = c.height;
            const margin = Math.max(8, Math.floor(h / 40)), barW = Math.max(12, Math.floor(w / 64));
            const x = w - margin - barW - 1, top = margin + 24, bottom = h - margin - 24;
            let n = 0, total = 0;
            for (let y = top + 4; y < bottom - 4; y += 4) {
                const [r, g, b] = ctx.getImageData(x, y, 1, 1).data;
                total += 1;
                if (Math.min(r, g, b) > 150) n += 1;
            }
            return n / total;
        }"""
    )
    assert light > 0.8, light
    page.click("#view-select button[data-view='color']")
    assert page.errors == []


def test_scene_picker_shows_the_current_scene(page, fresh):
    # The fresh station was started with pick_sort level 1, scene seed 3 (conftest SCENE_ARGS).
    page.wait_for_function("document.getElementById('sim-current').dataset.scene === 'pick_sort/1/3'", timeout=10_000)
    assert page.input_value("#sim-event") == "pick_sort" and page.input_value("#sim-level") == "1"
    assert page.input_value("#sim-seed") == "3"
    fresh.post("/api/sim/scene", {"event": "pick_stack", "level": 2, "seed": 7})  # another client changes it
    page.wait_for_function("document.getElementById('sim-current').dataset.scene === 'pick_stack/2/7'", timeout=10_000)
    assert page.input_value("#sim-event") == "pick_stack" and page.input_value("#sim-seed") == "7"
    assert page.errors == []
