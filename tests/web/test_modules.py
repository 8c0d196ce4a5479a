"""The page's pure modules, run in real Chromium as the page loads them (served by the real server):
frame-message parsing, view geometry, the rate meter, and markup names against the generated wire types."""

from __future__ import annotations

import json
import struct

import pytest

from browser_helpers import open_page

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def page(browser, server):
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    page.wait_for_function("window.armlab !== undefined")
    yield page
    page.close()


def test_parse_frame_message_splits_header_and_jpeg(page):
    header = {"type": "frame", "seq": 41, "capture_time_s": 1.5, "width": 4, "height": 2, "view": "depth"}
    header_bytes = json.dumps(header).encode()
    jpeg = bytes([0xFF, 0xD8, 0x01, 0x02, 0xFF, 0xD9])
    message = list(struct.pack("<I", len(header_bytes)) + header_bytes + jpeg)
    parsed = page.evaluate(
        """async (bytes) => {
            const { parseFrameMessage } = await import('/js/stream.js');
            const buf = new Uint8Array(bytes).buffer;
            const { header, jpeg } = parseFrameMessage(buf);
            const errors = [];
            for (const bad of [new ArrayBuffer(3), buf.slice(0, 10)]) {
                try { parseFrameMessage(bad); errors.push(null); } catch (e) { errors.push(e.message); }
            }
            return { header, jpeg: [...jpeg], errors };
        }""",
        message,
    )
    assert parsed["header"] == header
    assert parsed["jpeg"] == list(jpeg)
    assert "shorter" in parsed["errors"][0]
    assert "exceeds" in parsed["errors"][1]


def test_pointer_to_image_pixels_under_object_fit_contain(page):
    result = page.evaluate(
        """async () => {
            const g = await import('/js/geometry.js');
            // A 1000x650 image in a 1600x900 element: height-limited, pillarboxed by 100 px each side.
            const inside = g.elementToImagePx(100 + 692.3 * 0.5, 450, 1600, 900, 1000, 650);
            const corner = g.elementToImagePx(100 + 692.3, 900, 1600, 900, 1000, 650);
            const outside = g.elementToImagePx(50, 450, 1600, 900, 1000, 650);
            const back = g.imagePxToElement(250, 100, 1600, 900, 1000, 650);
            const again = g.elementToImagePx(back.x, back.y, 1600, 900, 1000, 650);
            return { inside, corner, outside, back, again };
        }"""
    )
    scale = 900 / 650
    offset_x = (1600 - 1000 * scale) / 2
    assert result["outside"] is None
    assert result["back"]["x"] == pytest.approx(offset_x + 250 * scale)
    assert result["back"]["y"] == pytest.approx(100 * scale)
    assert result["again"]["u"] == pytest.approx(250) and result["again"]["v"] == pytest.approx(100)
    assert result["inside"]["v"] == pytest.approx(325)


def test_topdown_pixels_map_to_the_board_and_back(page):
    result = page.evaluate(
        """async () => {
            const g = await import('/js/geometry.js');
            const workcell = { board: { x_range_m: [-0.5, 0.5], y_range_m: [-0.175, 0.475] },
                               block_edges_m: { large: 0.038, small: 0.025 } };
            const b = g.boardBoundsFromWorkcell(workcell);
            const corners = [g.topdownPxToWorld(0, 0, 1000, 650, b), g.topdownPxToWorld(1000, 650, 1000, 650, b)];
            const p = g.worldToTopdownPx(0.123, -0.05, 1000, 650, b);
            const w = g.topdownPxToWorld(p.u, p.v, 1000, 650, b);
            return {
                b, corners, p, w, headerBounds: typeof g.boundsFromHeader,
                noWorkcell: [g.boardBoundsFromWorkcell(null), g.boardBoundsFromWorkcell({ board: { x_range_m: [1, 0], y_range_m: [0, 1] } })],
                noBounds: [g.topdownPxToWorld(1, 1, 10, 10, null), g.worldToTopdownPx(0, 0, 10, 10, null)],
                edges: [g.blockEdgeM(workcell, "small"), g.blockEdgeM(workcell, "huge"), g.blockEdgeM(null, "large")],
            };
        }"""
    )
    assert result["b"] == {"xMin": -0.5, "xMax": 0.5, "yMin": -0.175, "yMax": 0.475}
    (x0, y0, _), (x1, y1, _) = result["corners"]
    assert (x0, y0) == pytest.approx((-0.5, 0.475)) and (x1, y1) == pytest.approx((0.5, -0.175))
    assert result["p"]["u"] == pytest.approx(623) and result["p"]["v"] == pytest.approx(525)
    assert result["w"][:2] == pytest.approx([0.123, -0.05])
    # the frame header carries no bounds (FrameHeader): the warp's bounds are the hello's board, nothing else
    assert result["headerBounds"] == "undefined"
    assert result["noWorkcell"] == [None, None] and result["noBounds"] == [None, None]
    assert result["edges"] == [0.025, None, None]


def test_nearest_detection_and_formatting(page):
    result = page.evaluate(
        """async () => {
            const g = await import('/js/geometry.js');
            const dets = [{ center_px: [100, 100] }, { center_px: [130, 100] }, { center_px: null }];
            return {
                near: g.nearestDetection(dets, 120, 101, 40),
                none: g.nearestDetection(dets, 400, 400, 40),
                mm: [g.fmtMm(0.1234), g.fmtMm(-0.0004), g.fmtMm(NaN)],
                deg: g.fmtDeg(Math.PI / 2),
            };
        }"""
    )
    assert result["near"] == 1 and result["none"] == -1
    assert result["mm"] == ["+123", "+0", "—"]
    assert result["deg"] == "90.0"


def test_rate_meter_counts_frames_per_second(page):
    rates = page.evaluate(
        """async () => {
            const { RateMeter } = await import('/js/stream.js');
            const m = new RateMeter(2.0);
            for (let i = 0; i <= 20; i++) m.tick(10 + i * 0.1);   // 10 Hz for 2 s
            const steady = m.rate(12.0);
            const stale = m.rate(30.0);                            // nothing in the last 2 s
            return { steady, stale };
        }"""
    )
    assert rates["steady"] == pytest.approx(10.0, rel=0.01)
    assert rates["stale"] == 0


def test_markup_uses_only_wire_protocol_names(page):
    assert page.evaluate("window.armlab.unknownWireNames()") == []
    # And the check is real: a bogus command name is reported.
    bogus = page.evaluate(
        """() => {
            const b = document.createElement('button');
            b.dataset.command = 'launch_rocket';
            document.body.append(b);
            const names = window.armlab.unknownWireNames();
            b.remove();
            return names;
        }"""
    )
    assert bogus == ["launch_rocket"]
