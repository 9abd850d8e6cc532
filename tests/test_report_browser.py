"""report.html in a real browser: one animation per listed mode, and each one renders and moves.

``mbseig report`` (the fastest options: no time-domain check, studies or sensitivities) writes
report.html for the hand-rehabilitation device (planar, three modes: the case the reports are
for) and a small spatial case (the spherical pendulum, three modes).  Each page is opened in
headless Chromium through chromedriver's WebDriver protocol (W3C WebDriver, plain HTTP: no client
package needed), and

- the page's own script context decodes every gallery animation (``ImageDecoder``, the browser's
  GIF decoder): an embedded ``data:image/gif`` with natural size > 0, more than one frame, a
  frame that is not blank (several colours) and a later frame that differs from the first;
- the rendered <img> elements are photographed (WebDriver element screenshots) a few times
  over one period of the animation: the pixels on screen are not blank and change.

Skipped with the reason when Chromium or chromedriver is absent (Debian: ``apt-get install
chromium chromium-driver``).  Needs Pillow to read the screenshots (installed with matplotlib).
"""

from __future__ import annotations

import base64
import io
import json
import re
import shutil
import socket
import subprocess
import time
import urllib.request

import numpy as np
import pytest
from conftest import CASES

CHROMIUM = next((p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome"))
                 if p), None)
DRIVER = shutil.which("chromedriver")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None or DRIVER is None,
    reason="headless Chromium and chromedriver are not installed (e.g. apt-get install "
           "chromium chromium-driver); the browser test of report.html needs both")

#: (case, number of modes it lists: the device's three degrees of freedom (its base
#: configuration); the spherical pendulum's two swings and the spin of the bob about the rod,
#: closed form of the case's [expected])
CASES_SHOWN = [("hand_device.toml", 3), ("spherical_pendulum.toml", 3)]

PROBE = """
const done = arguments[arguments.length - 1];
(async () => {
  const out = [];
  for (const img of document.querySelectorAll('.gallery img')) {
    const cap = img.closest('figure').querySelector('figcaption').textContent;
    const r = {caption: cap, gif: img.src.startsWith('data:image/gif;base64,'),
               complete: img.complete, natural: [img.naturalWidth, img.naturalHeight]};
    const bytes = await (await fetch(img.src)).arrayBuffer();
    const dec = new ImageDecoder({data: bytes, type: 'image/gif'});
    await dec.tracks.ready;
    r.frames = dec.tracks.selectedTrack.frameCount;
    let first = null;
    r.changed = 0;
    for (let k = 0; k < r.frames; k++) {
      const {image} = await dec.decode({frameIndex: k});
      const c = new OffscreenCanvas(image.displayWidth, image.displayHeight);
      const g = c.getContext('2d');
      g.drawImage(image, 0, 0);
      image.close();
      const d = g.getImageData(0, 0, c.width, c.height).data;
      if (first === null) {
        first = d;
        const colours = new Set();
        for (let i = 0; i < d.length; i += 4) colours.add((d[i] << 16) | (d[i+1] << 8) | d[i+2]);
        r.colours = colours.size;
      } else {
        let diff = 0;
        for (let i = 0; i < d.length; i++) if (d[i] !== first[i]) diff++;
        r.changed = Math.max(r.changed, diff / d.length);
      }
    }
    dec.close();
    out.push(r);
  }
  done(JSON.stringify(out));
})().catch(e => done(JSON.stringify({error: String(e)})));
"""


class WebDriver:
    """The few W3C WebDriver commands this test needs, over HTTP with urllib."""

    def __init__(self, tmp):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            self.port = s.getsockname()[1]
        self.proc = subprocess.Popen([DRIVER, f"--port={self.port}"], stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL)
        self.base = f"http://127.0.0.1:{self.port}"
        try:
            self._start(tmp)
        except BaseException:
            self.proc.terminate()
            self.proc.wait(timeout=10)
            raise

    def _start(self, tmp):
        for _ in range(100):
            try:
                if self.call("GET", "/status")["ready"]:
                    break
            except OSError:
                pass
            time.sleep(0.05)
        args = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                f"--user-data-dir={tmp}", "--window-size=1400,1000"]
        caps = {"browserName": "chrome", "goog:chromeOptions": {"binary": CHROMIUM,
                                                                "args": args}}
        self.sid = self.call("POST", "/session", {"capabilities": {"alwaysMatch": caps}})[
            "sessionId"]
        self.call("POST", f"/session/{self.sid}/timeouts", {"script": 15000})

    def call(self, method, path, body=None):
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(self.base + path, data=data, method=method,
                                     headers={"Content-Type": "application/json"})
        with urllib.request.urlopen(req, timeout=30) as resp:
            return json.loads(resp.read())["value"]

    def session(self, method, path, body=None):
        return self.call(method, f"/session/{self.sid}{path}", body)

    def close(self):
        try:
            self.call("DELETE", f"/session/{self.sid}")
        finally:
            self.proc.terminate()
            self.proc.wait(timeout=10)


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    wd = WebDriver(tmp_path_factory.mktemp("chromium-profile"))
    yield wd
    wd.close()


def _report(case, out):
    from mbseig.cli import main

    assert main(["report", str(CASES / case), "--out", str(out), "--no-check", "--no-studies",
                 "--no-sensitivities"]) == 0
    return out / "report.html"


def _pixels(png_b64):
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(base64.b64decode(png_b64))).convert("RGB"),
                      dtype=np.int16)


@pytest.mark.parametrize(("case", "n_modes"), CASES_SHOWN)
def test_report_animations_render_in_chromium(case, n_modes, browser, tmp_path, capsys):
    page = _report(case, tmp_path / "report")
    capsys.readouterr()
    listed = re.findall(r"\| (\d+) \|", (tmp_path / "report" / "report.md").read_text())
    assert len(set(listed)) >= n_modes  # the mode table lists them (1 … n)
    browser.session("POST", "/url", {"url": page.resolve().as_uri()})

    # the browser's own decoding of every animation
    result = json.loads(browser.session("POST", "/execute/async", {"script": PROBE, "args": []}))
    assert isinstance(result, list), result
    assert [r["caption"] for r in result] == [
        f"mode {k}, animated: one period" for k in range(1, n_modes + 1)]
    for r in result:
        assert r["gif"] and r["complete"] and min(r["natural"]) > 0, r
        assert r["frames"] > 1, r
        assert r["colours"] > 2, r  # drawn: not one flat colour (background + lines + text)
        assert r["changed"] > 0, r  # some frame differs from the first (the bob's spin about
        # the rod moves 0.04 % of the pixels, a swing ~1 %)

    # what the page shows: element screenshots over one period (12 frames at 10 per second)
    elements = browser.session("POST", "/elements", {"using": "css selector",
                                                     "value": ".gallery img"})
    assert len(elements) == n_modes
    for el in elements:
        eid = next(iter(el.values()))
        shots = [_pixels(browser.session("GET", f"/element/{eid}/screenshot"))]
        for _ in range(6):  # until the picture changes (a period is 1.2 s; some frames repeat)
            time.sleep(0.2)
            shots.append(_pixels(browser.session("GET", f"/element/{eid}/screenshot")))
            if not np.array_equal(shots[0], shots[-1]):
                break
        assert all(s.size > 0 and s.std() > 5 for s in shots)  # non-blank
        assert not np.array_equal(shots[0], shots[-1])  # it moves on screen
