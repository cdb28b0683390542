"""``motionlang serve``: time from a request to the first frame drawn, 20 sentences.

The bar (issue 43): for a 10 s motion, the median time from the click on Generate to the
first frame of the motion drawn on the page's canvas is at most 1 s on this machine. The
app runs as ``motionlang serve`` runs it (models loaded and warmed once at start); Debian's
headless Chromium (selenium) types each sentence, asks for 10 s, clicks and reads the
page's own measure (``window.mlTimings``: ``performance.now()`` from the click to the end
of the first drawing). Prints each time, the median and the 90th percentile, and the same
request over plain HTTP (no browser) for comparison. Without chromium it prints the HTTP
times only and says so.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_serve.py [--model l2m] [--seconds 10]
"""
from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")   # one core, set before numpy loads its BLAS

import argparse  # noqa: E402
import json  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import urllib.request  # noqa: E402

import numpy as np  # noqa: E402

from motionlang.web.app import running  # noqa: E402
from motionlang.web.options import ServeOptions  # noqa: E402
from motionlang.web.studio import Studio  # noqa: E402

BAR_S = 1.0
SENTENCES = [
    "a person walks forward", "someone waves with the right hand", "a person jumps in place",
    "a man runs forward", "a person walks backwards", "a woman waves with both hands",
    "a person kicks with the right leg", "someone punches with the left hand",
    "a person turns left while walking", "a person bows", "a person raises both hands",
    "a tired person walks slowly", "a happy person walks forward",
    "a person walks in a circle", "someone dances", "a person raises the left hand",
    "an old man walks forward", "a person jogs forward", "someone waves goodbye",
    "a person walks to the right",
]


def http_times(url: str, model: str, seconds: float) -> list[float]:
    times = []
    for text in SENTENCES:
        body = json.dumps({"text": text, "model": model, "seconds": seconds}).encode()
        req = urllib.request.Request(url + "api/generate", data=body,
                                     headers={"Content-Type": "application/json"})
        t0 = time.perf_counter()
        with urllib.request.urlopen(req) as res:
            view = json.loads(res.read())
        times.append(time.perf_counter() - t0)
        assert view["n_frames"] == round(seconds * view["fps"]), view["n_frames"]
    return times


def browser_times(url: str, model: str, seconds: float) -> list[float] | None:
    if shutil.which("chromium") is None or shutil.which("chromedriver") is None:
        return None
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium") or ""
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                "--window-size=1400,900"):
        opts.add_argument(arg)
    browser = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)
    try:
        browser.get(url)
        _wait(lambda: browser.execute_script("return document.body.dataset.ready"))
        browser.execute_script(f"document.getElementById('model').value = {model!r};"
                               f"document.getElementById('seconds').value = '{seconds:g}';")
        box = browser.find_element("id", "text")
        for i, text in enumerate(SENTENCES, 1):
            box.clear()
            box.send_keys(text)
            browser.find_element("id", "generate").click()
            _wait(lambda i=i: browser.execute_script("return window.mlTimings.length") >= i)
        return [t / 1000 for t in browser.execute_script("return window.mlTimings")]
    finally:
        browser.quit()


def _wait(check, timeout: float = 60.0) -> None:
    end = time.monotonic() + timeout
    while not check():
        if time.monotonic() > end:
            raise SystemExit("the page did not answer in time")
        time.sleep(0.01)


def report(what: str, times: list[float]) -> float:
    med = statistics.median(times)
    print(f"{what}: " + " ".join(f"{t:.3f}" for t in times))
    print(f"  median {med:.3f} s, 90th percentile {np.percentile(times, 90):.3f} s, "
          f"max {max(times):.3f} s over {len(times)} sentences")
    return med


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="l2m")
    ap.add_argument("--seconds", type=float, default=10.0)
    args = ap.parse_args()
    t0 = time.perf_counter()
    studio = Studio(ServeOptions(model=[args.model]))
    print(f"start-up (models loaded and warmed): {time.perf_counter() - t0:.2f} s; "
          f"model {args.model}, {args.seconds:g} s motions, "
          f"threads {os.environ['OMP_NUM_THREADS']}, load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    with running(studio) as url:
        report("HTTP request -> JSON decoded (s)", http_times(url, args.model, args.seconds))
        times = browser_times(url, args.model, args.seconds)
    if times is None:
        print("chromium or chromedriver not on PATH: no browser times (apt-get install "
              "chromium chromium-driver)")
        return
    med = report("click -> first frame drawn in Chromium (s)", times)
    print(f"bar: median <= {BAR_S:g} s: {'met' if med <= BAR_S else 'NOT met'}")


if __name__ == "__main__":
    main()
