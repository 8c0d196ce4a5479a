"""Take control from the page (issue 10 item 3): the top bar shows who holds the control lease, another
page takes it with its button, and the page that held it is told and stops offering commands."""

from __future__ import annotations

import pytest

from browser_helpers import OPERATOR, open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser

OTHER = "bench-2"


def test_take_control_moves_the_lease_and_the_previous_controller_sees_it(browser, server):
    ready_idle(server)
    server.post("/api/control/take")  # the operator (this page's name) holds the lease
    first = open_page(browser, f"{server.base_url}/?token={server.token}")
    second = open_page(browser, f"{server.base_url}/?token={server.token}&controller={OTHER}")
    try:
        for page in (first, second):
            wait_frames(page, 2)
            page.wait_for_function("window.armlab.status && window.armlab.connected")
        first.wait_for_function("document.getElementById('control-holder').dataset.mine === 'true'", timeout=5_000)
        assert first.is_disabled("#btn-take-control")
        second.wait_for_function("document.getElementById('control-holder').textContent.includes('operator')", timeout=5_000)
        assert second.is_disabled("#btn-home")  # someone else commands: no command buttons here
        assert not second.is_disabled("#btn-estop")

        second.click("#btn-take-control")
        server.wait_status(lambda s: s["controller"] == OTHER, 5.0, "the second page to hold control")
        second.wait_for_function("!document.getElementById('btn-home').disabled", timeout=5_000)
        first.locator(".toast", has_text="control taken").first.wait_for(timeout=5_000)
        first.wait_for_function(f"document.getElementById('control-holder').textContent.includes('{OTHER}')", timeout=5_000)
        assert first.is_disabled("#btn-home")

        first.click("#btn-take-control")
        server.wait_status(lambda s: s["controller"] == OPERATOR, 5.0, "the first page to take control back")
        first.wait_for_function("!document.getElementById('btn-home').disabled", timeout=5_000)
        second.locator(".toast", has_text="control taken").first.wait_for(timeout=5_000)
        assert first.errors == [] and second.errors == []
    finally:
        second.close()
        first.close()
