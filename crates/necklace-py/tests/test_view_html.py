"""view.html in a real browser: headless Chromium (Debian's chromium and chromium-driver,
which `scripts/test` installs when it can) loads the kitten's page, driven by Selenium.

Checks that the WebGL canvas is not blank, that the panel lists as many loops as
loops.json, and that clicking a row (a real WebDriver click) changes the highlighted
loop, in the page's state and in the picture. Screenshots go to
$NECKLACE_SCREENSHOTS (default: the test's temporary folder), to be looked at.

Skipped, with the reason printed, where no browser or driver is installed.
"""

import json
import os
import pathlib
import shutil

import pytest

from conftest import run

BROWSERS = ["chromium", "chromium-browser", "google-chrome"]

# Counts pixels of the WebGL canvas: not white, and of the highlight colour (green,
# 26, 217, 77 shaded; the kinds are red and blue, the saddles gold, the surface grey).
COUNT_PIXELS = """
const canvas = document.getElementById('canvas');
const copy = document.createElement('canvas');
copy.width = canvas.width; copy.height = canvas.height;
const ctx = copy.getContext('2d');
ctx.drawImage(canvas, 0, 0);
const d = ctx.getImageData(0, 0, copy.width, copy.height).data;
let drawn = 0, highlight = 0;
const colours = new Set();
for (let i = 0; i < d.length; i += 4) {
  const r = d[i], g = d[i + 1], b = d[i + 2];
  if (r < 250 || g < 250 || b < 250) drawn++;
  if (g > 120 && g - r > 80 && g - b > 50) highlight++;
  colours.add((r >> 3) * 1024 + (g >> 3) * 32 + (b >> 3));
}
return [drawn, highlight, colours.size, copy.width * copy.height];
"""


def browser_or_skip():
    """The Chromium and chromedriver executables, or skip the test saying why."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        pytest.skip("selenium is not installed (pip install selenium): no browser test")
    browser = next((shutil.which(b) for b in BROWSERS if shutil.which(b)), None)
    driver = shutil.which("chromedriver")
    if browser is None or driver is None:
        reason = (
            "no headless browser here (scripts/test installs Debian's chromium and "
            "chromium-driver with apt-get when it runs as root): "
            f"browser={browser}, chromedriver={driver}"
        )
        print(reason)
        pytest.skip(reason)
    return browser, driver


@pytest.fixture(scope="module")
def page(cli, kitten, tmp_path_factory):
    out = tmp_path_factory.mktemp("kitten-html")
    run(cli, "loops", kitten, "-q", "-o", out, "--html")
    return out


@pytest.fixture(scope="module")
def chrome(page):
    browser, driver_path = browser_or_skip()
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = browser
    for flag in [
        "--headless=new",
        "--no-sandbox",
        "--disable-dev-shm-usage",
        # WebGL without a GPU: SwiftShader, Chromium's software renderer.
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--window-size=1400,900",
    ]:
        options.add_argument(flag)
    try:
        driver = webdriver.Chrome(service=Service(driver_path), options=options)
    except Exception as e:  # a browser that does not start: say why, do not fail
        reason = f"headless Chromium did not start: {str(e).splitlines()[0]}"
        print(reason)
        pytest.skip(reason)
    yield driver
    driver.quit()


def screenshot(driver, name, tmp_path):
    folder = pathlib.Path(os.environ.get("NECKLACE_SCREENSHOTS", tmp_path))
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    driver.save_screenshot(str(path))
    print(f"screenshot: {path}")
    return path


def test_the_kitten_page_draws_lists_and_highlights_its_loops(chrome, page, tmp_path):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    loops = json.loads((page / "loops.json").read_text())["loops"]
    assert len(loops) >= 2, "the kitten has at least two loops to tell apart"
    chrome.get((page / "view.html").as_uri())
    WebDriverWait(chrome, 30).until(lambda d: d.execute_script("return document.body.dataset.ready") == "1")
    assert chrome.execute_script("return document.getElementById('canvas').getContext('webgl') !== null")

    # The canvas is not blank: a good part of it is drawn, in many shades.
    chrome.execute_script("window.necklace.state.hovered = null;")
    drawn, highlight, colours, total = chrome.execute_script(COUNT_PIXELS)
    screenshot(chrome, "kitten-page.png", tmp_path)
    assert drawn > 0.03 * total, (drawn, total)
    assert colours > 50, colours
    assert highlight == 0, "nothing is highlighted before a click"

    # The panel lists every loop of loops.json, in order, with its kind.
    rows = chrome.find_elements(By.CSS_SELECTOR, "#loops tbody tr")
    assert len(rows) == len(loops)
    for row, loop in zip(rows, loops):
        assert loop["kind"] in row.text

    # Clicking a row highlights its loop; clicking another moves the highlight.
    assert chrome.execute_script("return document.body.dataset.highlighted") == ""
    rows[1].click()
    WebDriverWait(chrome, 10).until(lambda d: d.execute_script("return document.body.dataset.highlighted") == "1")
    assert "highlighted" in rows[1].get_attribute("class")
    chrome.execute_script("window.necklace.state.hovered = null;")
    chrome.execute_script("return new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
    _, highlight_1, _, _ = chrome.execute_script(COUNT_PIXELS)
    screenshot(chrome, "kitten-row-1.png", tmp_path)
    assert highlight_1 > 50, "the highlighted loop is drawn in the highlight colour"

    rows[0].click()
    WebDriverWait(chrome, 10).until(lambda d: d.execute_script("return document.body.dataset.highlighted") == "0")
    assert "highlighted" in rows[0].get_attribute("class")
    assert "highlighted" not in rows[1].get_attribute("class")
    screenshot(chrome, "kitten-row-0.png", tmp_path)

    # The slider hides necks gone below a scale: at its right end only those alive at
    # the largest scale stay listed.
    chrome.execute_script(
        "const s = document.getElementById('scale'); s.value = 1000; s.dispatchEvent(new Event('input'));"
    )
    shown = [r for r in rows if "hidden" not in r.get_attribute("class")]
    alive = [l for l in loops if l["death_scale"] is None]
    assert len(shown) == len(alive)
