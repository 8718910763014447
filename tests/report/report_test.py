"""The HTML report in a real browser (Debian's headless Chromium): no console error, the canvas
shows the body, two screenshots at different times differ where the body moved, the slider moves
the scene, the plots and the equations are drawn. Usage: report_test.py NHDYN SOURCE_DIR WORK_DIR.
Exits 77 (ctest's skip code) with the reason printed when Chromium cannot start; nowhere else."""
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from browser import Browser, find_chromium, png_pixels  # noqa: E402

NHDYN, SOURCE, WORK = sys.argv[1:4]
os.makedirs(WORK, exist_ok=True)
failures = []


def check(condition, message):
    print(("ok   " if condition else "FAIL ") + message, flush=True)
    if not condition:
        failures.append(message)


def run(*args):
    result = subprocess.run([NHDYN, *args], capture_output=True, text=True)
    if result.returncode != 0:
        raise SystemExit(f"nhdyn {' '.join(args)} failed ({result.returncode}): {result.stderr}")
    return result


def canvas_pixels(browser):
    rect = browser.evaluate("(() => { const r = document.getElementById('canvas').getBoundingClientRect();"
                            " return [r.left, r.top, r.width, r.height]; })()")
    png = browser.screenshot({"x": rect[0], "y": rect[1], "width": rect[2], "height": rect[3]})
    width, height, rows = png_pixels(png)
    return rect, rows, png


def coloured_near(rows, rect, point, radius):
    """Pixels within `radius` of `point` (page coordinates) that are clearly coloured: the bodies are
    drawn in saturated colours, the background white and the grid grey."""
    x0, y0 = int(point[0] - rect[0]), int(point[1] - rect[1])
    count = 0
    for y in range(max(0, y0 - radius), min(len(rows), y0 + radius + 1)):
        for x in range(max(0, x0 - radius), min(len(rows[0]), x0 + radius + 1)):
            r, g, b = rows[y][x]
            if max(r, g, b) - min(r, g, b) > 60:
                count += 1
    return count


def changed_near(a, b, rect, point, radius):
    x0, y0 = int(point[0] - rect[0]), int(point[1] - rect[1])
    count = 0
    for y in range(max(0, y0 - radius), min(len(a), y0 + radius + 1)):
        for x in range(max(0, x0 - radius), min(len(a[0]), x0 + radius + 1)):
            if sum(abs(p - q) for p, q in zip(a[y][x], b[y][x])) > 60:
                count += 1
    return count


def slider_point(browser, fraction):
    r = browser.evaluate("(() => { const r = document.getElementById('slider').getBoundingClientRect();"
                         " return [r.left, r.top, r.width, r.height]; })()")
    # The thumb's centre travels over the width less the thumb (about 16 px wide).
    return r[0] + 8 + fraction * (r[2] - 16), r[1] + r[3] / 2


def choose_view(browser, value):
    browser.evaluate(f"(() => {{ const s = document.getElementById('follow'); s.value = '{value}';"
                     " s.dispatchEvent(new Event('change')); return s.value; })()")


def check_follow(browser, label, screenshots):
    """A system travelling far beyond its size is followed by default: the view is centred on it
    and the system is drawn there at both times; the grid moves under it."""
    check(browser.evaluate("document.getElementById('follow').value") == "-2",
          f"{label}: the view follows the bodies by default (the motion is far larger than the system)")
    for fraction, name in ((0.15, "follow-early"), (0.8, "follow-late")):
        browser.click(*slider_point(browser, fraction))
        rect, rows, png = canvas_pixels(browser)
        middle = (rect[0] + rect[2] / 2, rect[1] + rect[3] / 2)
        check(coloured_near(rows, rect, middle, 40) > 40,
              f"{label}: the followed system is drawn at the middle of the view ({name})")
        path = os.path.join(WORK, f"{label}-{name}.png")
        with open(path, "wb") as f:
            f.write(png)
        screenshots.append(path)


def check_report(browser, html, shape, label, screenshots, follows=False):
    browser.events.clear()
    browser.open("file://" + os.path.abspath(html) + "#paused")
    check(browser.errors() == [], f"{label}: no console error on opening ({browser.errors()[:3]})")
    check(browser.evaluate("document.getElementById('canvas') !== null"), f"{label}: the page has a WebGL canvas")
    frames = browser.evaluate("nhdyn.frames")
    check(browser.evaluate("nhdyn.frame") == 0, f"{label}: paused at the first frame")
    if follows:
        check_follow(browser, label, screenshots)
    else:
        check(browser.evaluate("document.getElementById('follow').value") == "-1",
              f"{label}: the whole motion is shown by default")
    choose_view(browser, "-1")  # the whole motion: the body moves across a still view
    if isinstance(shape, str):  # the first shape of this kind
        shape = browser.evaluate(f"NHDYN.scene.shapes.findIndex(s => s.kind === '{shape}')")

    # The slider moves the scene: a click at 15 % and at 80 % of its track.
    browser.click(*slider_point(browser, 0.15))
    first = browser.evaluate("nhdyn.frame")
    check(abs(first - 0.15 * (frames - 1)) <= 0.03 * frames,
          f"{label}: a click at 15 % of the slider shows frame {first} of {frames}")
    where_first = browser.evaluate(f"nhdyn.screen({shape})")
    rect, rows_first, png_first = canvas_pixels(browser)
    browser.click(*slider_point(browser, 0.8))
    second = browser.evaluate("nhdyn.frame")
    check(abs(second - 0.8 * (frames - 1)) <= 0.03 * frames,
          f"{label}: a click at 80 % of the slider shows frame {second} of {frames}")
    where_second = browser.evaluate(f"nhdyn.screen({shape})")
    _, rows_second, png_second = canvas_pixels(browser)
    for name, png in (("early", png_first), ("late", png_second)):
        path = os.path.join(WORK, f"{label}-{name}.png")
        with open(path, "wb") as f:
            f.write(png)
        screenshots.append(path)

    # Not blank: the body is drawn where the camera projects it, at both times.
    check(coloured_near(rows_first, rect, where_first, 6) > 10,
          f"{label}: the body is drawn at {where_first[0]:.0f}, {where_first[1]:.0f} (early)")
    check(coloured_near(rows_second, rect, where_second, 6) > 10,
          f"{label}: the body is drawn at {where_second[0]:.0f}, {where_second[1]:.0f} (late)")
    moved = ((where_first[0] - where_second[0]) ** 2 + (where_first[1] - where_second[1]) ** 2) ** 0.5
    check(moved > 15, f"{label}: the body moved {moved:.0f} px on the screen between the two times")
    # The two screenshots differ where the body was and where it went.
    check(changed_near(rows_first, rows_second, rect, where_first, 6) > 10,
          f"{label}: the screenshots differ where the body was")
    check(changed_near(rows_first, rows_second, rect, where_second, 6) > 10,
          f"{label}: the screenshots differ where the body went")
    far = (rect[0] + 3, rect[1] + 3)
    check(changed_near(rows_first, rows_second, rect, far, 2) == 0,
          f"{label}: the screenshots agree far from the body (the corner)")
    plots = browser.evaluate("document.querySelectorAll('canvas.plot').length")
    check(plots >= 3, f"{label}: {plots} plot panels")
    check(browser.errors() == [], f"{label}: no console error after moving the slider ({browser.errors()[:3]})")


def screens_at(browser, shape, fractions):
    """The canvas's pixels at each fraction of the run, with its rectangle and where shape `shape` is
    drawn on the page."""
    out = []
    for fraction in fractions:
        browser.evaluate(f"nhdyn.setFrame(Math.round({fraction} * (nhdyn.frames - 1)))")
        where = browser.evaluate(f"nhdyn.screen({shape})")
        rect, rows, _ = canvas_pixels(browser)
        out.append((rows, rect, where))
    return out


def check_contacts(browser, html, label, kinds):
    """A page of [[contacts]]: no console error, the shapes and grounds of `kinds` in its scene, and the
    first contact shape drawn where the camera projects it at two times, turning between them."""
    browser.events.clear()
    browser.open("file://" + os.path.abspath(html) + "#paused")
    check(browser.errors() == [], f"{label}: no console error on opening ({browser.errors()[:3]})")
    present = browser.evaluate("NHDYN.scene.shapes.map(s => s.kind)")
    check(all(k in present for k in kinds), f"{label}: the scene has {kinds} ({present})")
    shape = browser.evaluate("NHDYN.scene.shapes.findIndex(s => s.body)")
    fractions = (0.2, 0.7)
    screens = screens_at(browser, shape, fractions)
    for (rows, rect, where), fraction in zip(screens, fractions):
        check(coloured_near(rows, rect, where, 20) > 100,
              f"{label}: the shape is drawn at {where[0]:.0f}, {where[1]:.0f} ({fraction:.0%} of the run)")
    (a, rect, where), (b, _, _) = screens
    check(changed_near(a, b, rect, where, 20) > 20, f"{label}: the drawing changed where the shape was")
    check(browser.errors() == [], f"{label}: no console error after moving ({browser.errors()[:3]})")


def check_turntable(browser, html, label):
    """A turntable's page: its plane turns, so that between two times the drawing changes far from
    the ball too (the table's grid, spokes and coloured sector), not only where the ball was."""
    browser.events.clear()
    browser.open("file://" + os.path.abspath(html) + "#paused")
    check(browser.evaluate("NHDYN.scene.shapes.filter(s => s.kind === 'plane' && s.turns).length") == 1,
          f"{label}: one turning plane in the scene")
    ball = browser.evaluate("NHDYN.scene.shapes.findIndex(s => s.body)")
    (a, rect, p), (b, _, q) = screens_at(browser, ball, (0.2, 0.5))
    far = 0
    for y in range(len(a)):
        for x in range(len(a[0])):
            near_ball = any((x + rect[0] - w[0]) ** 2 + (y + rect[1] - w[1]) ** 2 < 60 ** 2 for w in (p, q))
            if not near_ball and sum(abs(u - v) for u, v in zip(a[y][x], b[y][x])) > 60:
                far += 1
    check(far > 2000, f"{label}: the drawing changed at {far} pixels away from the ball (the table turned)")
    check(browser.errors() == [], f"{label}: no console error ({browser.errors()[:3]})")


def main():
    chromium = find_chromium()
    if chromium is None:
        print("SKIP: no Chromium on PATH (apt-get install chromium); the report's browser tests did not run")
        return 77
    reports = []
    sled = os.path.join(WORK, "sled.html")
    run("simulate", os.path.join(SOURCE, "examples/sled.toml"), "--t-end", "4", "-q",
        "-o", os.path.join(WORK, "sled.csv"), "--html", sled)
    reports.append((sled, "sphere", "sled"))  # the centre of mass
    disk = os.path.join(WORK, "rolling_disk_bodies.html")
    run("simulate", os.path.join(SOURCE, "examples/rolling_disk_bodies.toml"), "--t-end", "3", "-q",
        "-o", os.path.join(WORK, "disk.csv"), "--html", disk)
    bicycle = os.path.join(WORK, "whipple_bicycle.html")
    run("simulate", os.path.join(SOURCE, "examples/whipple_bicycle.toml"), "--t-end", "10", "--output-step", "0.01",
        "-q", "-o", os.path.join(WORK, "bicycle.csv"), "--html", bicycle)
    # (one page of [[contacts]]: KaTeX lays out a terrain's long equations for seconds; the
    # terrain's mesh is checked in report_test.cpp)
    bowl = os.path.join(WORK, "ball_in_bowl.html")
    run("simulate", os.path.join(SOURCE, "examples/ball_in_bowl.toml"), "--t-end", "1.6", "--set", "x0=0.15", "-q",
        "-o", os.path.join(WORK, "bowl.csv"), "--html", bowl)
    turntable = os.path.join(WORK, "ball_on_turntable.html")
    run("simulate", os.path.join(SOURCE, "examples/ball_on_turntable.toml"), "--t-end", "2", "-q",
        "-o", os.path.join(WORK, "turntable.csv"), "--html", turntable)
    size = os.path.getsize(bicycle)
    check(size < 5e6, f"whipple_bicycle: a 10 s run at 100 frames/s gives a page of {size / 1e6:.2f} MB (< 5 MB)")
    try:
        browser = Browser(chromium)
    except Exception as error:  # noqa: BLE001 - any failure to start is a reason to skip
        print(f"SKIP: Chromium ({chromium}) cannot start here: {error}")
        return 77
    screenshots = []
    try:
        for html, shape, label in reports[:1]:
            check_report(browser, html, shape, label, screenshots, follows=True)
        check_report(browser, disk, "wheel", "rolling_disk_bodies", screenshots)
        check(browser.evaluate("document.querySelectorAll('.katex').length") > 0,
              "rolling_disk_bodies: the equations are rendered by KaTeX")
        check(browser.evaluate("document.querySelectorAll('.katex-error').length") == 0,
              "rolling_disk_bodies: KaTeX reports no error in the equations")
        text = browser.evaluate("[...document.querySelectorAll('#equations p')].map(p => p.textContent).join(' ')")
        # (the rendered formulas in the paragraphs keep their TeX source in KaTeX's annotation)
        check("Constraint disk_slip1, given at velocity level" in text and "disk\\_slip" not in text,
              f"rolling_disk_bodies: a constraint's name reads as written, without TeX escapes ({text[:120]!r})")
        check_contacts(browser, bowl, "ball_in_bowl", ["ellipsoid", "surface", "track"])
        check_turntable(browser, turntable, "ball_on_turntable")
        browser.events.clear()
        browser.open("file://" + os.path.abspath(bicycle) + "#paused")
        check(browser.evaluate("nhdyn.frames") == 1001, "whipple_bicycle: all 1001 rows shown")
        check(browser.evaluate("NHDYN.scene.shapes.filter(s => s.kind === 'wheel').length") == 2,
              "whipple_bicycle: two wheels drawn")
        check_follow(browser, "whipple_bicycle", screenshots)
        check(browser.errors() == [], f"whipple_bicycle: no console error ({browser.errors()[:3]})")
    finally:
        browser.close()
    print("screenshots: " + " ".join(screenshots))
    if failures:
        print(f"{len(failures)} check(s) failed")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
