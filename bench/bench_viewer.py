#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""The browser viewer's size and frame time (docs/viewer.md; a benchmark, not a test).

usage: PYTHONPATH=build/python /usr/bin/python3 bench/bench_viewer.py [--frames 300]

For a 10 s run of a planar chain of 10 bars (and of a few gallery examples): the page's size,
and the mean time to draw one frame in headless Chromium with software rendering (SwiftShader):
setFrame + render + a one-pixel read-back (which waits for the frame), over successive frames,
after a warm-up; and the frames per second drawn while the page plays for 3 s
(requestAnimationFrame). Prints a Markdown table for bench/RESULTS.md.
"""
import argparse
import os
import sys
import tempfile
import time

import ukdyn

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python",
                                "tests"))
from test_viewer import _chain  # noqa: E402  (the same 10-bar chain the size test uses)


def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--use-gl=swiftshader",
              "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--window-size=1280,800",
              "--force-device-scale-factor=1"):
        options.add_argument(a)
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)


def measure(driver, path, frames):
    driver.get("file://" + path)
    for _ in range(200):
        if driver.execute_script("return !!(window.ukdyn && window.ukdyn.ready)"):
            break
        time.sleep(0.05)
    driver.execute_script("ukdyn.frameTime(30)")  # warm-up
    size = driver.execute_script("const c = ukdyn.camera(); return [c.width, c.height]")
    ms = driver.execute_script("return ukdyn.frameTime(arguments[0])", frames)
    driver.set_script_timeout(30)
    fps = driver.execute_async_script(
        "const done = arguments[arguments.length - 1]; ukdyn.playbackRate(3000).then(done)")
    return ms, fps, size


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=300)
    args = parser.parse_args()
    cases = [("chain of 10 bars, 10 s", lambda: ukdyn.parse(_chain(10), "chain.yaml").simulate()),
             ("heavy_top, 10 s", lambda: ukdyn.load("heavy_top").simulate(t_end=10)),
             ("bricard, 10 s", lambda: ukdyn.load("bricard").simulate(t_end=10)),
             ("double_pendulum, 10 s", lambda: ukdyn.load("double_pendulum").simulate(t_end=10))]
    driver = browser()
    rows = []
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for name, run in cases:
                result = run()
                path = os.path.join(tmp, "page.html")
                start = time.perf_counter()
                result.save_animation(path)
                written = time.perf_counter() - start
                ms, fps, size = measure(driver, path, args.frames)
                rows.append((name, os.path.getsize(path), len(result), written, ms, fps, size))
    finally:
        driver.quit()
    print("| run | samples | page | written in | frame time (%dx%d) | playback |" % tuple(rows[0][6]))
    print("|---|---|---|---|---|---|")
    for name, nbytes, samples, written, ms, fps, _ in rows:
        print("| %s | %d | %.2f MB | %.2f s | %.2f ms | %.0f frames/s |"
              % (name, samples, nbytes / 1e6, written, ms, fps))


if __name__ == "__main__":
    main()
