"""The Recording panel in real Chromium on the real server: Record starts a recording and shows its duration and
size growing, Stop ends it and lists it with a download link to its MCAP file."""

from __future__ import annotations

import httpx
import pytest

from browser_helpers import open_page

pytestmark = pytest.mark.browser


def test_record_shows_duration_and_size_then_lists_the_recording(browser, server):
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        page.wait_for_function("window.armlab !== undefined && document.querySelector('#btn-record').textContent.includes('Record')")
        page.click("#btn-record")
        page.wait_for_function("document.querySelector('#rec-status').textContent.startsWith('REC ')", timeout=30_000)
        first = page.text_content("#rec-status")
        page.wait_for_function("(first) => { const t = document.querySelector('#rec-status').textContent;"
                               " return t.startsWith('REC 0:0') && t !== first && !t.startsWith('REC 0:00'); }", arg=first, timeout=30_000)
        status = page.text_content("#rec-status")
        assert "MB" in status or "kB" in status
        assert httpx.get(server.base_url + "/api/recordings", timeout=10).json()["active"] is not None
        page.click("#btn-record")
        page.wait_for_function("document.querySelector('#btn-record').dataset.recording === 'false'"
                               " && document.querySelectorAll('#rec-list a').length > 0", timeout=30_000)
        href = page.get_attribute("#rec-list a", "href")
        listing = httpx.get(server.base_url + "/api/recordings", timeout=10).json()
        assert listing["active"] is None and href == f"/api/recordings/{listing['data'][0]['id']}"
        assert httpx.get(server.base_url + href, timeout=30).content.startswith(b"\x89MCAP0\r\n")
    finally:
        page.close()
