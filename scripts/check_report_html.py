#!/usr/bin/env python3
"""Open a report.html in headless Chromium: screenshot it and check that no image is broken.

    python scripts/check_report_html.py reports/hand_device/report.html [--screenshot out.png]

Checks (exit 1 on failure): every <img> is an embedded PNG data URI that decodes, or an
embedded GIF (a mode animation) that decodes to at least two frames and loops (no browser
needed), and in Chromium every image has naturalWidth > 0 after load (the DOM is dumped after a
small inline script writes the counts of images, broken images and animations into the page
title).
"""

from __future__ import annotations

import argparse
import base64
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
GIF_PREFIX = "data:image/gif;base64,"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--no-first-run", "--hide-scrollbars"]


def find_chromium():
    """A headless-capable Chromium: $CHROMIUM, else the first of the usual names on PATH
    (Debian's ``chromium`` or ``chromium-headless-shell``, Chrome).  None when there is none:
    browsers from pip (playwright, pyppeteer) download their binary from a CDN at install time,
    which this project's machines cannot reach, so only a system package provides one."""
    env = os.environ.get("CHROMIUM")
    if env and shutil.which(env):
        return shutil.which(env)
    for name in ("chromium", "chromium-headless-shell", "chromium-browser", "google-chrome",
                 "chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def check_embedded(html: str) -> list[str]:
    """(problems, number of still figures): problems with the <img> tags (not an embedded PNG
    or GIF, or not decodable); the count is of the PNG figures (the animations are counted by
    :func:`check_animations`)."""
    import io

    import matplotlib.image as mpimg

    problems = []
    srcs = re.findall(r'<img[^>]*\bsrc="([^"]*)"', html)
    if not srcs:
        problems.append("no <img> in the page")
    n = 0
    for k, src in enumerate(srcs):
        if src.startswith(GIF_PREFIX):
            problems += [f"image {k}: {p}" for p in _gif_problems(src)]
            continue
        if not src.startswith("data:image/png;base64,"):
            problems.append(f"image {k}: not an embedded PNG or GIF ({src[:40]!r})")
            continue
        n += 1
        data = base64.b64decode(src.split(",", 1)[1], validate=True)
        if not data.startswith(PNG_SIGNATURE):
            problems.append(f"image {k}: bad PNG signature")
            continue
        img = mpimg.imread(io.BytesIO(data), format="png")
        if img.shape[0] < 10 or img.shape[1] < 10:
            problems.append(f"image {k}: decoded to {img.shape}")
    return problems, n


def _gif_problems(src):
    """What is wrong with an embedded GIF animation (decoded by Pillow, which matplotlib
    depends on): not a GIF, fewer than two frames, not looping, tiny."""
    import io

    from PIL import Image

    data = base64.b64decode(src[len(GIF_PREFIX):], validate=True)
    if not data.startswith((b"GIF87a", b"GIF89a")):
        return ["bad GIF signature"]
    with Image.open(io.BytesIO(data)) as im:
        out = []
        if getattr(im, "n_frames", 1) < 2:
            out.append("a GIF of one frame (not an animation)")
        if im.info.get("loop") != 0:
            out.append("a GIF that does not loop")
        if im.size[0] < 10 or im.size[1] < 10:
            out.append(f"GIF of size {im.size}")
        return out


def check_animations(html: str):
    """(problems, number of embedded GIF animations, frames of each)."""
    import io

    from PIL import Image

    srcs = [s for s in re.findall(r'<img[^>]*\bsrc="([^"]*)"', html) if s.startswith(GIF_PREFIX)]
    problems, frames = [], []
    for k, src in enumerate(srcs):
        problems += [f"animation {k}: {p}" for p in _gif_problems(src)]
        with Image.open(io.BytesIO(base64.b64decode(src[len(GIF_PREFIX):]))) as im:
            frames.append(getattr(im, "n_frames", 1))
    return problems, len(srcs), frames


def check_in_browser(page: Path, screenshot: Path, chromium: str, width=1200, height=3000, *,
                     animations=False):
    """(number of images, number broken) as seen by Chromium, and with ``animations`` the
    number of loaded GIF animations as a third value; writes the screenshot."""
    html = page.read_text()
    probe = ("<script>window.addEventListener('load',()=>{const im=[...document.images];"
             "const ok=i=>i.complete&&i.naturalWidth>0;"
             "document.title='IMAGES '+im.length+' BROKEN '+im.filter(i=>!ok(i)).length"
             "+' GIFS '+im.filter(i=>i.src.startsWith('data:image/gif')&&ok(i)).length;});"
             "</script>")
    with tempfile.TemporaryDirectory() as tmp:
        probed = Path(tmp) / "probe.html"
        probed.write_text(html.replace("</body>", probe + "</body>"))
        profile = Path(tmp) / "profile"
        dom = subprocess.run([chromium, *FLAGS, f"--user-data-dir={profile}",
                              "--virtual-time-budget=5000", "--dump-dom", probed.as_uri()],
                             capture_output=True, text=True, timeout=120)
        m = re.search(r"<title>IMAGES (\d+) BROKEN (\d+) GIFS (\d+)</title>", dom.stdout)
        subprocess.run([chromium, *FLAGS, f"--user-data-dir={profile}2",
                        f"--screenshot={screenshot}", f"--window-size={width},{height}",
                        page.resolve().as_uri()], capture_output=True, timeout=120)
    if not m:
        raise RuntimeError("chromium did not run the probe script:\n" + dom.stderr[-2000:])
    counts = int(m.group(1)), int(m.group(2))
    return (*counts, int(m.group(3))) if animations else counts


def print_to_pdf(page: Path, pdf: Path, chromium: str):
    """The page printed by Chromium (its @media print styles applied) to ``pdf``."""
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([chromium, *FLAGS, f"--user-data-dir={Path(tmp) / 'profile'}",
                        "--no-pdf-header-footer", f"--print-to-pdf={pdf}",
                        page.resolve().as_uri()], capture_output=True, timeout=120)
    return pdf


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("html", type=Path)
    ap.add_argument("--screenshot", type=Path, default=None)
    args = ap.parse_args(argv)
    html = args.html.read_text()
    problems, n = check_embedded(html)
    _, n_anim, frames = check_animations(html)
    print(f"{n} embedded figures and {n_anim} animations ({sum(frames)} frames); "
          f"{len(problems)} problems")
    for p in problems:
        print("  " + p)
    chromium = find_chromium()
    if chromium is None:
        print("chromium not found: browser check skipped")
        return 1 if problems else 0
    shot = args.screenshot or args.html.with_name("screenshot.png")
    total, broken, gifs = check_in_browser(args.html, shot, chromium, animations=True)
    print(f"chromium: {total} images ({gifs} animations), {broken} broken; screenshot {shot}")
    return 1 if problems or broken or total != n + n_anim or gifs != n_anim else 0


if __name__ == "__main__":
    sys.exit(main())
