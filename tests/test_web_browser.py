"""motionlang serve in a real browser (Debian's headless Chromium, selenium): a sentence
typed, the motion drawn and moving, paused, scrubbed and orbited; a BVH uploaded and
described; a bad file's one line; a GLB downloaded and read back; a rig uploaded; an index
searched with a filter, the reasons shown and a hit played. Each step leaves a screenshot
(``$MOTIONLANG_SCREENSHOTS`` or the test's temporary folder)."""
from __future__ import annotations

import base64
import io
import time

import numpy as np
import pytest

from helpers.browser import chromium, screenshot_dir, wait_for
from helpers.grounded import hand_made, make_library
from helpers.rigs import RIGS, write
from helpers.web import SMALL
from motionlang.library.embedder import Embedder
from motionlang.web.options import ServeOptions

BLUE, ORANGE = (0x2A, 0x6F, 0xDB), (0xE0, 0x7B, 0x22)   # left and right bones (viewer.js)


def canvas_pixels(browser) -> np.ndarray:
    """(H, W, 3) uint8: what the viewer's canvas shows now."""
    from PIL import Image
    url = browser.execute_script("return document.getElementById('view').toDataURL('image/png')")
    png = base64.b64decode(url.split(",", 1)[1])
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def changed(browser, before: np.ndarray, pixels: int = 300) -> list | None:
    """``[now]`` if the canvas now differs from ``before`` in more than ``pixels`` pixels."""
    now = canvas_pixels(browser)
    return [now] if (now != before).any(axis=-1).sum() > pixels else None


def colour_count(pixels: np.ndarray, rgb: tuple[int, int, int]) -> int:
    return int((np.abs(pixels.astype(int) - rgb).max(axis=-1) < 24).sum())


def status_of(browser, element: str) -> tuple[str, bool]:
    el = browser.find_element("id", element)
    return el.text, "error" in (el.get_attribute("class") or "")


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    from motionlang.web.app import running
    from motionlang.web.studio import Studio
    downloads = tmp_path_factory.mktemp("downloads")
    browser = chromium(downloads)
    try:
        # the packaged M2L: the procedural one has seen no motion capture to describe
        studio = Studio(ServeOptions(**{**SMALL, "describe_model": "m2l"}))
        with running(studio) as url:
            browser.get(url)
            wait_for(lambda: browser.execute_script("return document.body.dataset.ready"),
                     what="the page to load its models list")
            yield browser, downloads
    finally:
        browser.quit()


def test_the_page_generates_plays_describes_and_downloads(page, tmp_path):
    browser, downloads = page
    shots = screenshot_dir(tmp_path)
    find = browser.find_element

    # a sentence typed, the motion drawn
    find("id", "text").send_keys("a person walks forward")
    find("id", "seconds").send_keys("6")
    find("id", "generate").click()
    wait_for(lambda: browser.execute_script("return document.body.dataset.take"),
             what="the generated motion")
    text, error = status_of(browser, "gen-status")
    assert not error and "75 frames" in text, text
    wait_for(lambda: browser.execute_script("return window.mlTimings.length") == 1,
             what="the first frame drawn")
    first = canvas_pixels(browser)
    browser.save_screenshot(str(shots / "1-generated.png"))
    assert colour_count(first, BLUE) > 150 and colour_count(first, ORANGE) > 150, \
        "no figure with left and right limbs on the canvas"

    # it moves: pixels differ between frames
    later = wait_for(lambda: changed(browser, first), timeout=5, what="the figure to move")[0]
    assert colour_count(later, BLUE) > 150
    browser.save_screenshot(str(shots / "2-playing.png"))

    # paused, it stands still; scrubbed, it moves to the frame asked for
    find("id", "play").click()
    assert find("id", "play").text == "Play"
    still = canvas_pixels(browser)
    time.sleep(0.3)
    assert changed(browser, still, 0) is None, "a paused figure moved"
    browser.execute_script("const s = document.getElementById('scrub'); s.value = 60;"
                           "s.dispatchEvent(new Event('input'));")
    assert find("id", "clock").text == "4.80 s"
    assert changed(browser, still) is not None

    # orbited by dragging, the view turns
    from selenium.webdriver import ActionChains
    before = canvas_pixels(browser)
    ActionChains(browser).move_to_element(find("id", "view")).click_and_hold() \
        .move_by_offset(120, 0).release().perform()
    assert changed(browser, before) is not None
    browser.save_screenshot(str(shots / "3-orbited.png"))

    # a GLB downloaded and read back: the take's frames and rate, the 21 joints
    find("id", "dl-glb").click()
    glb = wait_for(lambda: next(iter(downloads.glob("*.glb")), None), what="the GLB download")
    wait_for(lambda: "downloaded" in find("id", "dl-status").text, what="the download")
    from motionlang.formats.gltf_read import read_gltf_animation
    anim = read_gltf_animation(glb)
    assert glb.name == "a_person_walks_forward.glb"
    assert anim.positions.shape[0] == 75 and anim.fps == pytest.approx(12.5)
    assert "LK" in anim.names and "RK" in anim.names
    feet = anim.positions[:, [anim.names.index(n) for n in ("LF", "RF", "LA", "RA")], 1]
    assert np.all(feet.min(axis=1) < 0.12), "the figure floats above the floor"

    # a BVH uploaded and described
    bvh = write(RIGS["mixamo"], tmp_path, "walk", T=60)
    find("id", "describe-file").send_keys(str(bvh))
    find("id", "describe").click()
    wait_for(lambda: browser.find_elements("css selector", "#sentences li"),
             what="the description")
    sentences = [li.text for li in browser.find_elements("css selector", "#sentences li")]
    assert 1 <= len(sentences) <= 5 and all(sentences)
    text, error = status_of(browser, "describe-status")
    assert text.startswith("walk: 2.0") and not error
    browser.save_screenshot(str(shots / "4-described.png"))

    # a take whose header's rate its body contradicts: read at the body's, and said so
    from motionlang.formats import write_motion
    from motionlang.rendering.output import body_motion
    from test_rate_hint import _jumps
    jump = tmp_path / "jump.bvh"
    write_motion(body_motion(_jumps(120.0), 120.0)[0].replace(fps=25.0), jump)
    find("id", "describe-file").clear()
    find("id", "describe-file").send_keys(str(jump))
    find("id", "describe").click()
    wait_for(lambda: status_of(browser, "describe-status")[0].startswith("jump:"),
             what="the rate's note")
    text, error = status_of(browser, "describe-status")
    assert text.startswith("jump: 4.0 s (jump.bvh: its header says 25 Hz") and \
        text.endswith("read at 120 Hz)") and not error
    browser.save_screenshot(str(shots / "4b-described-at-its-rate.png"))

    # a broken file: the reader's one line in the page
    bad = tmp_path / "broken.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n")
    find("id", "describe-file").clear()
    find("id", "describe-file").send_keys(str(bad))
    find("id", "describe").click()
    wait_for(lambda: status_of(browser, "describe-status")[1], what="the error line")
    text = status_of(browser, "describe-status")[0]
    assert text.startswith("broken.bvh") and "\n" not in text and "Traceback" not in text
    browser.save_screenshot(str(shots / "5-bad-file.png"))

    # a rig uploaded: the next take is drawn on its skeleton
    rig = write(RIGS["cmu-bvh"], tmp_path, "my_rig", T=4)
    find("id", "rig-file").send_keys(str(rig))
    find("id", "rig-upload").click()
    wait_for(lambda: "my_rig" in find("id", "rig-status").text, what="the rig")
    browser.execute_script("document.body.dataset.take = ''")
    find("id", "generate").click()
    wait_for(lambda: browser.execute_script("return document.body.dataset.take"),
             what="the motion on the rig")
    assert "on my_rig" in find("id", "gen-status").text
    from motionlang.formats import read_motion
    assert browser.execute_script("return viewer.motion.J") == \
        len(read_motion(rig).skeleton.joints)
    browser.save_screenshot(str(shots / "6-on-rig.png"))


def test_the_search_panel_filters_says_why_and_plays_a_hit(tmp_path, monkeypatch):
    from motionlang.web.app import running
    from motionlang.web.studio import Studio
    _, index = make_library(tmp_path)
    monkeypatch.setattr(Embedder, "load", classmethod(lambda cls, model=None: hand_made()))
    shots = screenshot_dir(tmp_path)
    browser = chromium(tmp_path / "downloads")
    try:
        with running(Studio(ServeOptions(**SMALL, index=str(index)))) as url:
            browser.get(url)
            wait_for(lambda: browser.execute_script("return document.body.dataset.ready"),
                     what="the page to load")
            find = browser.find_element
            assert find("id", "panel-search").is_displayed()
            find("id", "query").send_keys("someone sits down")
            find("id", "search").click()
            wait_for(lambda: find("id", "hits").find_elements("tag name", "li"),
                     what="the hits")
            first = find("id", "hits").find_elements("tag name", "li")[0].text
            assert "chairs/sit.bvh" in first and "(sits: " in first, first
            browser.save_screenshot(str(shots / "search-1-why.png"))
            # a filter: only takes where the analysis sees walking
            find("id", "where").send_keys("walks")
            find("id", "search").click()
            wait_for(lambda: [li.text for li in find("id", "hits").find_elements(
                "tag name", "li")] and all("walk.bvh" in li.text for li in find(
                    "id", "hits").find_elements("tag name", "li")), what="filtered hits")
            # a bad filter is its one line, in the panel
            find("id", "where").clear()
            find("id", "where").send_keys("happily")
            find("id", "search").click()
            wait_for(lambda: status_of(browser, "search-status")[1], what="the error")
            assert "names no action" in status_of(browser, "search-status")[0]
            find("id", "where").clear()
            find("id", "search").click()
            wait_for(lambda: "chairs/sit.bvh" in find("id", "hits").text, what="the hits")
            before = canvas_pixels(browser)
            find("id", "hits").find_elements("tag name", "li")[0].click()
            wait_for(lambda: changed(browser, before), what="the hit drawn")
            browser.save_screenshot(str(shots / "search-2-played.png"))
    finally:
        browser.quit()
