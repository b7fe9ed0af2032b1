"""Pictures of the documentation site (issue 45): its front page, a how-to guide and the gallery, as a reader's
browser shows them, into docs/site_front.png, docs/site_howto_sweep.png and docs/site_gallery.png.

Builds the site (Sphinx, as `make docs`) into a scratch folder, then opens each page in Debian's chromium driven by
Playwright (the test extra's browser), 1100 x 850 pixels.

    python bench/site_screenshots.py
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGES = {"site_front.png": "index.html", "site_howto_sweep.png": "howto/sweep.html",
         "site_gallery.png": "generated/gallery.html"}


def main() -> None:
    from playwright.sync_api import sync_playwright

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        sys.exit("site_screenshots: chromium is not installed (apt-get install chromium)")
    site = Path(tempfile.mkdtemp(prefix="andyc-site-"))
    subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(ROOT / "docs"),
                    str(site)], check=True)
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=["--headless", "--no-sandbox", "--disable-gpu"])
        page = browser.new_page(viewport={"width": 1100, "height": 850})
        for picture, name in PAGES.items():
            page.goto((site / name).as_uri())
            page.screenshot(path=str(ROOT / "docs" / picture))
            print(f"docs/{picture}: {name}")
        browser.close()
    shutil.rmtree(site)


if __name__ == "__main__":
    main()
