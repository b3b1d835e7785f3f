"""The report of a real run opened in headless Chromium (selenium + chromedriver): the page is not
blank, logs no console error, and its WebGL view draws the pressure and turns with the mouse.

Needs Chromium and its driver (Debian: ``apt-get install chromium chromium-driver``; ``make
test-slow`` installs them when run as root) and the ``selenium`` package (the dev extra); skips
with the reason otherwise. WebGL runs on SwiftShader, Chromium's CPU renderer: no GPU needed.
"""

import io
import os
import re
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fenics_garment._stack import MPI
from fenics_garment.report import REPORT_FILE
from fenics_garment.scene import config
from fenics_garment.scene.run import run

pytestmark = [pytest.mark.slow]

SCENE = Path(__file__).parent.parent / "demos" / "tube_on_cylinder.toml"
BROWSERS = ("chromium", "chromium-browser", "google-chrome")
#: Pixels darker than this in any channel are not the page's white background.
WHITE = 245

# the canvas of the 3D view, copied into a 2D canvas and read back: (pixels not white, pixels
# coloured (not grey: the pressure's colour map), all pixels, a checksum of the image)
READ_CANVAS = """
const c = document.querySelector("canvas.view");
const t = document.createElement("canvas");
t.width = c.width; t.height = c.height;
const g = t.getContext("2d");
g.drawImage(c, 0, 0);
const d = g.getImageData(0, 0, t.width, t.height).data;
let drawn = 0, coloured = 0, sum = 0;
for (let i = 0; i < d.length; i += 4) {
  const lo = Math.min(d[i], d[i + 1], d[i + 2]), hi = Math.max(d[i], d[i + 1], d[i + 2]);
  if (lo < arguments[0]) drawn++;
  if (hi - lo > 60) coloured++;
  sum = (sum * 31 + d[i] + 7 * d[i + 1] + 13 * d[i + 2]) % 1000000007;
}
return [drawn, coloured, t.width * t.height, sum];
"""


def _browser() -> tuple[str, str]:
    """(Chromium, chromedriver) paths, or skip with the reason."""
    pytest.importorskip("selenium", reason="selenium is not installed (pip install -e .[dev])")
    browser = os.environ.get("FENICS_GARMENT_CHROMIUM") or next(
        (p for b in BROWSERS if (p := shutil.which(b))), None
    )
    driver = shutil.which("chromedriver")
    if browser is None or driver is None:
        pytest.skip("Chromium or chromedriver not found (apt-get install chromium chromium-driver)")
    return browser, driver


@pytest.fixture(scope="module")
def browser() -> tuple[str, str]:
    """(Chromium, chromedriver): checked before the scene is run, to skip at once."""
    return _browser()


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> Path:
    """report.html of the tube scene, run on a coarser body (about 10 s)."""
    if MPI.COMM_WORLD.size > 1:
        pytest.skip("one browser, one rank")
    s = config.load(SCENE)
    s = replace(s, body=replace(s.body, mesh_size=0.01), output=replace(s.output, vtx=False))
    result = run(s, tmp_path_factory.mktemp("report"), quiet=True, checkpoints=False)
    assert result.completed
    path = result.folder / REPORT_FILE
    assert path.is_file() and (result.folder / "report_surfaces.npz").is_file()
    return path


@pytest.fixture(scope="module")
def page(browser: tuple[str, str], report: Path):
    binary, driver_path = browser
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = binary
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                "--window-size=1200,1000", "--force-device-scale-factor=1"):  # fmt: skip
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(driver_path), options=options)
    try:
        driver.get(report.as_uri())
        yield driver
    finally:
        driver.quit()


def _wait_drawn(driver) -> None:
    from selenium.common.exceptions import TimeoutException
    from selenium.webdriver.support.ui import WebDriverWait

    script = 'return Number(document.querySelector("canvas.view").dataset.triangles || 0)'
    try:
        WebDriverWait(driver, 30).until(lambda d: d.execute_script(script) > 0)
    except TimeoutException:
        status = driver.find_element("css selector", ".viewer3d .status").text
        pytest.fail(f"the 3D view was not drawn in 30 s: {status!r}; console: "
                    f"{driver.get_log('browser')}")  # fmt: skip


def test_page_is_not_blank_and_logs_no_error(page):
    from PIL import Image

    _wait_drawn(page)
    shot = np.asarray(Image.open(io.BytesIO(page.get_screenshot_as_png())).convert("L"), float)
    assert shot.std() > 20, f"the screenshot is nearly uniform (std {shot.std():.1f})"
    assert (shot < 128).mean() > 0.01  # text, tables and the view: dark pixels somewhere
    errors = [e for e in page.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == [], errors
    assert page.find_element("css selector", "#checks + table").is_displayed()
    assert page.find_element("css selector", ".viewer3d .status").text == ""


def test_canvas_draws_the_pressure_and_turns(page):
    from selenium.webdriver.common.action_chains import ActionChains

    _wait_drawn(page)
    drawn, coloured, total, before = page.execute_script(READ_CANVAS, WHITE)
    assert drawn > 0.05 * total, f"only {drawn} of {total} canvas pixels drawn"
    assert coloured > 0.01 * total, f"only {coloured} pixels in the pressure's colours"
    canvas = page.find_element("css selector", "canvas.view")
    # hovering the middle of the view, the middle of the tube, reads its pressure (Laplace:
    # about 0.45 kPa); the canvas in view first (selenium aims at the middle of what is seen)
    page.execute_script("arguments[0].scrollIntoView()", canvas)
    ActionChains(page).move_to_element(canvas).perform()
    page.execute_script("return new Promise((done) => requestAnimationFrame(() => done()))")
    text = page.find_element("css selector", ".viewer3d .readout").text
    assert re.fullmatch(r"garment: \d+\.\d{3} kPa", text), text
    assert 0.3 < float(text.split()[1]) < 0.6, text
    ActionChains(page).move_to_element(canvas).click_and_hold().move_by_offset(150, 40).release(
    ).perform()  # fmt: skip
    page.execute_script("return new Promise((done) => requestAnimationFrame(() => done()))")
    drawn2, _, _, after = page.execute_script(READ_CANVAS, WHITE)
    assert after != before and drawn2 > 0.05 * total  # turned, still drawn
    # the body alone, coloured by its pressure
    page.execute_script('const s = document.querySelector("select.show"); s.value = "body"; '
                        's.dispatchEvent(new Event("change"));')  # fmt: skip
    page.execute_script("return new Promise((done) => requestAnimationFrame(() => done()))")
    _, coloured3, _, _ = page.execute_script(READ_CANVAS, WHITE)
    assert coloured3 > 0.01 * total
    errors = [e for e in page.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == [], errors
