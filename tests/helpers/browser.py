"""Debian's headless Chromium under selenium, for the browser tests; skips cleanly where
chromium, its driver or selenium is absent (``.ci/run`` installs them where apt works)."""
from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

import pytest


def chromium(download_dir: Path):
    """A headless Chromium WebDriver that saves downloads into ``download_dir``."""
    webdriver = pytest.importorskip("selenium.webdriver", reason="needs selenium (test extra)")
    from selenium.webdriver.chrome.service import Service
    binary = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    if binary is None or driver is None:
        pytest.skip("needs chromium and chromedriver on PATH (apt-get install chromium "
                    "chromium-driver)")
    opts = webdriver.ChromeOptions()
    opts.binary_location = binary
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                "--window-size=1400,900", "--force-device-scale-factor=1"):
        opts.add_argument(arg)
    opts.add_experimental_option("prefs", {"download.default_directory": str(download_dir),
                                           "download.prompt_for_download": False})
    # both paths given: selenium never looks for (or fetches) a driver of its own
    browser = webdriver.Chrome(service=Service(driver), options=opts)
    browser.execute_cdp_cmd("Page.setDownloadBehavior",
                            {"behavior": "allow", "downloadPath": str(download_dir)})
    return browser


def wait_for(check, timeout: float = 30.0, what: str = "the page"):
    """Poll ``check()`` until it returns something true; fail naming ``what``."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = check()
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


def screenshot_dir(tmp_path: Path) -> Path:
    """Where the screenshots go: ``$MOTIONLANG_SCREENSHOTS`` if set, else ``tmp_path``."""
    folder = Path(os.environ.get("MOTIONLANG_SCREENSHOTS") or tmp_path / "screenshots")
    folder.mkdir(parents=True, exist_ok=True)
    return folder
