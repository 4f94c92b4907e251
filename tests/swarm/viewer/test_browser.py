"""The replay page in headless Chromium, driven by Playwright: robots drawn where the recording puts them,
the slider moves time, clicking a robot opens its panel, the JavaScript decoder agrees with Python's, lost
messages and communication groups are drawn, the age-of-information panel shows the run's values, trails
fade and can be limited, and a version 1 recording still plays. At swarm size (more than 64 robots):
points, at most one per pixel cell; only the selected robot's map held; panels and layers within budgets;
a recording embedded in pieces.

Needs Debian's chromium (``/usr/bin/chromium``) and the ``playwright`` package; ``.ci/run`` installs both.
Playwright's own browser download does not work here, so we launch the system Chromium.
"""

from __future__ import annotations

import io
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from maps.materials import colour_of
from swarm.record import Recorder, load_recording, record_run
from swarm.record.animation import ROBOT_COLOURS
from swarm.sim.loop import Simulation
from swarm.viewer import write_html

CHROMIUM = os.environ.get("SWARM_CHROMIUM", "/usr/bin/chromium")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def _missing(reason: str) -> None:
    """Skip locally; fail in CI (``.ci/run`` sets SWARM_REQUIRE_BROWSER), where a skip would hide the test."""
    if os.environ.get("SWARM_REQUIRE_BROWSER"):
        pytest.fail(reason, pytrace=False)
    pytest.skip(reason, allow_module_level=True)


if not (os.path.exists(CHROMIUM) or shutil.which(CHROMIUM)):
    _missing(f"no Chromium at {CHROMIUM} (Debian package 'chromium'; .ci/run installs it)")
try:
    from playwright import sync_api
except ImportError:
    _missing("the 'playwright' package is not installed (pip install '.[test]')")

SPEC = {"seed": 2, "map": {"kind": "building", "size": 30}, "robots": {"count": 4}, "stop": {"max_ticks": 900},
        "radio": {"tx_power_dbm": -30.0}, "comm": {"loss": 0.2}}
"""Weak radios and random loss: messages are lost for want of a link and to loss, groups come and go."""
TICK = 400
V1_FILE = Path(__file__).parents[1] / "record" / "data" / "v1-building20.swr"


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    folder = tmp_path_factory.mktemp("browser")
    path = folder / "run.swr"
    result = record_run(Simulation(SPEC), path)
    html = write_html(path, folder / "run.html")
    return load_recording(path), html, result


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        yield b
        b.close()


def open_page(browser, html, width=1400, height=900):
    """A page of ``html`` once its script is ready; after the test: no errors, nothing fetched."""
    context = browser.new_context(viewport={"width": width, "height": height}, device_scale_factor=1)
    pg = context.new_page()
    errors: list[str] = []
    pg.on("pageerror", lambda exc: errors.append(str(exc)))
    pg.on("console", lambda msg: errors.append(msg.text) if msg.type == "error" else None)
    requests: list[str] = []
    pg.on("request", lambda req: requests.append(req.url))
    pg.goto(html.resolve().as_uri())
    pg.wait_for_function("document.body.dataset.ready !== '0'", timeout=60_000)
    assert pg.evaluate("document.body.dataset.ready") == "1", pg.inner_text("#status")
    yield pg
    assert errors == []
    assert all(url.startswith(("file:", "data:", "blob:")) for url in requests), requests  # no network
    context.close()


@pytest.fixture
def page(browser, recording):
    yield from open_page(browser, recording[1])


def canvas_pixel(pg, x: float, y: float) -> tuple[int, int, int]:
    return tuple(pg.evaluate("([x, y]) => Array.from(document.getElementById('map').getContext('2d')"
                             ".getImageData(Math.floor(x), Math.floor(y), 1, 1).data.slice(0, 3))", [x, y]))


def expected_canvas_xy(pg, rec, x: float, y: float) -> tuple[float, float]:
    """Where the world point (x, y) must be drawn, computed here, not by the page: cells are square, north up."""
    width = pg.evaluate("document.getElementById('map').width")
    cell_px = width / rec.shape[1]
    return x / 0.5 * cell_px, (rec.shape[0] - y / 0.5) * cell_px


def set_layers(pg, **on: bool) -> None:
    for name, value in on.items():
        box = pg.locator(f"#show-{name}")
        if box.is_checked() != value:
            box.click()


def test_robots_are_drawn_at_their_recorded_positions(page, recording):
    rec = recording[0]
    page.evaluate(f"swarmViewer.setTick({TICK})")
    assert page.evaluate("swarmViewer.tick()") == TICK
    radius = page.evaluate("swarmViewer.robotScreenPosition(0).radius")
    isolated = 0
    for i in range(rec.n_robots):
        x, y, theta = rec.poses[TICK, i]
        assert page.evaluate(f"swarmViewer.pose({i})") == [x, y, theta]      # the JS decoder is exact
        want = expected_canvas_xy(page, rec, x, y)
        got = page.evaluate(f"swarmViewer.robotScreenPosition({i})")
        assert got["canvasX"] == pytest.approx(want[0], abs=0.01) and got["canvasY"] == pytest.approx(want[1], abs=0.01)
        others = [expected_canvas_xy(page, rec, *rec.poses[TICK, j, :2]) for j in range(rec.n_robots) if j != i]
        if all(np.hypot(ox - want[0], oy - want[1]) > 2.5 * radius for ox, oy in others):
            isolated += 1
            assert canvas_pixel(page, *want) == ROBOT_COLOURS[i % len(ROBOT_COLOURS)]
    assert isolated >= 2


def test_walls_are_coloured_by_material(page, recording):
    rec = recording[0]
    set_layers(page, links=False, messages=False, trails=False, lost=False, groups=False, goals=False, grid=False)
    page.evaluate(f"swarmViewer.setTick({rec.last_tick})")
    seen, truth = rec.seen_at(rec.last_tick), rec.truth
    rows, cols = np.nonzero(truth.solid & seen)
    checked = 0
    for row, col in list(zip(rows.tolist(), cols.tolist()))[:: max(1, len(rows) // 25)]:
        x, y = (col + 0.5) * 0.5, (row + 0.5) * 0.5
        if min(np.hypot(*(rec.poses[rec.last_tick, :, :2] - (x, y)).T)) < 1.5:
            continue  # a robot is drawn over it
        assert canvas_pixel(page, *expected_canvas_xy(page, rec, x, y)) == colour_of(truth.materials[truth.material[row, col]])
        checked += 1
    assert checked >= 10


def test_the_slider_moves_time(page, recording):
    rec = recording[0]
    slider = page.locator("#timeline")
    assert slider.get_attribute("max") == str(rec.last_tick)
    box = slider.bounding_box()
    page.mouse.click(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    middle = page.evaluate("swarmViewer.tick()")
    assert abs(middle - rec.last_tick / 2) < 0.05 * rec.last_tick
    assert int(slider.input_value()) == middle
    assert f"tick {middle} /" in page.inner_text("#readout")
    before = page.evaluate("swarmViewer.robotScreenPosition(0)")
    slider.focus()
    page.keyboard.press("End")
    assert page.evaluate("swarmViewer.tick()") == rec.last_tick
    after = page.evaluate("swarmViewer.robotScreenPosition(0)")
    assert (before["canvasX"], before["canvasY"]) != (after["canvasX"], after["canvasY"])
    assert f"explored {100 * rec.explored[rec.last_tick]:.1f} %" in page.inner_text("#readout")


def test_clicking_a_robot_shows_its_panel_and_its_own_map(page, recording):
    rec = recording[0]
    page.evaluate(f"swarmViewer.setTick({TICK})")
    assert page.locator("#robot-panel").is_hidden()
    robot = 2
    pos = page.evaluate(f"swarmViewer.robotScreenPosition({robot})")
    page.mouse.click(pos["x"], pos["y"])
    panel = page.locator("#robot-panel")
    assert panel.is_visible() and panel.get_attribute("data-robot") == str(robot)
    text = panel.inner_text()
    x, y, _ = rec.poses[TICK, robot]
    assert f"Robot {robot}" in text and f"{x:.2f}, {y:.2f} m" in text
    known = rec.known_at(TICK)[robot]
    assert f"{int((known == 1).sum())} free + {int((known == 2).sum())} wall cells" in text
    so_far = [m for m in rec.messages() if m.tick <= TICK]
    sent = [m for m in so_far if m.sender == robot]
    received = sum(robot in m.receivers for m in so_far)
    assert f"{len(sent)} sent ({sum(m.size for m in sent)} B), {received} received" in text
    # the map now shows this robot's knowledge: a free cell others saw but it did not is drawn differently
    # from one it knows
    set_layers(page, links=False, messages=False, trails=False, debug=False, lost=False, groups=False, goals=False,
               grid=False)
    others_only = np.argwhere(rec.seen_at(TICK) & (known == 0) & ~rec.truth.solid)
    mine = np.argwhere((known == 1) & ~rec.truth.solid)
    far = lambda rc: min(np.hypot(*(rec.poses[TICK, :, :2] - ((rc[1] + 0.5) * 0.5, (rc[0] + 0.5) * 0.5)).T)) > 1.5
    a = next(rc for rc in others_only if far(rc))
    b = next(rc for rc in mine if far(rc))
    pa = canvas_pixel(page, *expected_canvas_xy(page, rec, (a[1] + 0.5) * 0.5, (a[0] + 0.5) * 0.5))
    pb = canvas_pixel(page, *expected_canvas_xy(page, rec, (b[1] + 0.5) * 0.5, (b[0] + 0.5) * 0.5))
    assert pa != pb
    page.locator("#robot-close").click()
    assert panel.is_hidden()


def test_javascript_reconstruction_equals_python_at_several_ticks(page, recording):
    """Forward, backward and long jumps (keyframes) all give the reader's state."""
    rec = recording[0]
    h, w = rec.shape
    for tick in (rec.last_tick, 3, TICK, 0, TICK + 1, rec.last_tick // 2):
        page.evaluate(f"swarmViewer.setTick({tick})")
        known = page.evaluate(f"""() => {{ const v = swarmViewer, out = [];
            for (let i = 0; i < {rec.n_robots}; i++) for (let r = 0; r < {h}; r++) for (let c = 0; c < {w}; c++)
              out.push(v.knownCell(i, r, c)); return out; }}""")
        seen = page.evaluate(f"""() => {{ const out = [];
            for (let r = 0; r < {h}; r++) for (let c = 0; c < {w}; c++) out.push(swarmViewer.seenCell(r, c));
            return out; }}""")
        assert np.array_equal(np.array(known, dtype=np.uint8).reshape(rec.n_robots, h, w), rec.known_at(tick))
        assert np.array_equal(np.array(seen, dtype=bool).reshape(h, w), rec.seen_at(tick))
        assert page.evaluate("swarmViewer.linkCount()") == int(rec.links_at(tick)[0].sum())
        assert page.evaluate("swarmViewer.explored()") == rec.explored[tick]


def test_play_advances_and_pause_stops(page):
    page.evaluate("swarmViewer.setTick(0)")
    page.locator("#play").click()
    page.wait_for_function("swarmViewer.tick() > 5", timeout=30_000)
    page.locator("#play").click()
    assert page.evaluate("swarmViewer.isPlaying()") is False
    assert page.locator("#play").get_attribute("data-playing") == "0"


def test_screenshot_is_not_blank(page, tmp_path):
    from PIL import Image

    page.evaluate(f"swarmViewer.setTick({TICK})")
    png = page.screenshot(full_page=True)
    (tmp_path / "viewer.png").write_bytes(png)
    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    assert image.std() > 20
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 50
    canvas = np.asarray(Image.open(io.BytesIO(page.locator("#map").screenshot())).convert("RGB"))
    assert canvas.shape[0] > 200 and canvas.std() > 20


# ------------------------------------------------------------------------------ communication ----
ONLY = dict(links=False, messages=False, trails=False, debug=False, lost=False, groups=False, goals=False, grid=False,
            ids=False)


def map_image(pg) -> np.ndarray:
    """The map canvas as the screen shows it (device scale 1: one canvas pixel per screen pixel)."""
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(pg.locator("#map").screenshot())).convert("RGB")).astype(int)


def near_segment(shape: tuple[int, ...], a, b, lo: float, hi: float, width: float) -> np.ndarray:
    """Pixels whose centre is within ``width`` of the part [lo, hi] of the segment a -> b."""
    ys, xs = np.mgrid[0:shape[0], 0:shape[1]] + 0.5
    d = np.subtract(b, a)
    f = np.clip(((xs - a[0]) * d[0] + (ys - a[1]) * d[1]) / (d @ d), lo, hi)
    return np.hypot(xs - a[0] - f * d[0], ys - a[1] - f * d[1]) <= width


def test_a_lost_message_is_drawn_from_whom_to_whom_with_its_cause(page, recording):
    rec = recording[0]
    lost = [(m, robot, cause) for m in rec.messages() for robot, cause in m.lost]
    assert {"link", "loss"} <= {cause for _, _, cause in lost}, "the run loses messages for both reasons"
    radius = page.evaluate("swarmViewer.robotScreenPosition(0).radius")

    def apart(m, robot):  # a line long enough to see, no third robot near it
        a, b = (np.array(expected_canvas_xy(page, rec, *rec.poses[m.tick, k, :2])) for k in (m.transmitter, robot))
        points = a + np.linspace(0, 1, 30)[:, None] * (b - a)
        others = [np.array(expected_canvas_xy(page, rec, *rec.poses[m.tick, j, :2])) for j in range(rec.n_robots)
                  if j not in (m.transmitter, robot)]
        return np.hypot(*(b - a)) > 10 * radius and all(np.hypot(*(points - o).T).min() > 3 * radius for o in others)

    m, robot, cause = next((m, r, c) for m, r, c in lost if c == "loss" and apart(m, r))
    tick = m.tick
    set_layers(page, **{**ONLY, "lost": True})
    page.evaluate(f"swarmViewer.setTick({tick})")
    drawn = page.evaluate("swarmViewer.drawnLosses()")
    want = sorted((x.tick, x.transmitter, r, c) for x, r, c in lost if tick - 6 < x.tick <= tick)
    assert sorted((d["tick"], d["from"], d["to"], d["cause"]) for d in drawn) == want

    # on the canvas: a dashed line in the cause's colour from the transmitter toward the robot it missed
    a = expected_canvas_xy(page, rec, *rec.poses[tick, m.transmitter, :2])
    b = expected_canvas_xy(page, rec, *rec.poses[tick, robot, :2])
    colour = page.evaluate(f"swarmViewer.causeColour('{cause}')")
    assert colour != page.evaluate("swarmViewer.causeColour('link')")
    image = map_image(page)
    line = near_segment(image.shape, a, b, 0.15, 0.7, 1.5)
    match = (image == colour).all(axis=2)
    assert match[line].sum() >= 10
    assert match[~near_segment(image.shape, a, b, 0.0, 0.9, 8.0)].sum() < match[line].sum()  # not everywhere
    x, y = np.add(a, 0.4 * np.subtract(b, a))
    tip = page.evaluate(f"swarmViewer.tooltipAt({x}, {y})")
    assert f"robot {m.sender} → robot {robot}" in tip and f"tick {tick}" in tip and "comm.loss" in tip, tip
    set_layers(page, lost=False)
    assert not (map_image(page) == colour).all(axis=2)[line].any()


def test_communication_groups_are_drawn_as_hulls(page, recording):
    rec = recording[0]
    radius = page.evaluate("swarmViewer.robotScreenPosition(0).radius")

    def candidate(tick):
        groups = rec.comm_at(tick).groups
        if len(groups) < 2:
            return None
        for g in groups:
            if len(g) == 2:
                i, j = sorted(g)
                mid = np.mean([expected_canvas_xy(page, rec, *rec.poses[tick, k, :2]) for k in (i, j)], axis=0)
                if all(np.hypot(*(np.array(expected_canvas_xy(page, rec, *rec.poses[tick, k, :2])) - mid)) > 3 * radius
                       for k in range(rec.n_robots)):
                    return groups, sorted(g), mid
        return None

    tick, (groups, pair, mid) = next((t, c) for t in range(0, rec.ticks, 5) if (c := candidate(t)))
    assert groups == rec.link_state(tick).groups()  # the radio's, recomputed from the exact poses
    set_layers(page, **{**ONLY, "groups": True})
    page.evaluate(f"swarmViewer.setTick({tick})")
    assert page.evaluate("swarmViewer.groups()") == [sorted(g) for g in groups]
    drawn = page.evaluate("swarmViewer.drawnGroups()")
    assert [d["members"] for d in drawn] == [sorted(g) for g in groups if len(g) > 1]
    colour = np.array(next(d["colour"] for d in drawn if d["members"] == pair))
    on = map_image(page)
    set_layers(page, groups=False)
    off = map_image(page)
    x, y = int(mid[0]), int(mid[1])
    assert not np.array_equal(on[y, x], off[y, x])
    assert np.abs(on[y, x] - colour).sum() < np.abs(off[y, x] - colour).sum()  # tinted toward the group's colour
    ys, xs = np.mgrid[0:on.shape[0], 0:on.shape[1]]
    far = np.ones(on.shape[:2], dtype=bool)
    for k in range(rec.n_robots):
        cx, cy = expected_canvas_xy(page, rec, *rec.poses[tick, k, :2])
        far &= np.hypot(xs - cx, ys - cy) > 30 * radius
    assert far.any() and np.array_equal(on[far], off[far])  # nothing drawn away from the robots
    set_layers(page, groups=True)
    assert f"robots {pair[0]}, {pair[1]}" in page.evaluate(f"swarmViewer.tooltipAt({mid[0]}, {mid[1]})")


def test_the_age_of_information_panel_shows_the_runs_values(page, recording):
    rec, _, result = recording
    rows, robots = result.comm["series"]["tick"], result.comm["robots"]
    assert page.locator("#aoi-panel").is_visible()
    shown = []
    for k in (len(rows) // 3, 2 * len(rows) // 3, len(rows) - 1):
        page.evaluate(f"swarmViewer.setTick({rows[k]})")
        cells = page.evaluate("Array.from(document.querySelectorAll('#aoi-rows tr'))"
                              ".map((tr) => ({ ...tr.dataset, text: tr.innerText }))")
        assert [int(c["robot"]) for c in cells] == list(range(rec.n_robots))
        for i, c in enumerate(cells):
            age, since, missing = robots["aoi_age"][k][i], robots["since_contact"][k][i], robots["missing_free"][k][i]
            assert (float(c["age"]), float(c["since"]), float(c["missing"])) == (age, since, missing)
            numbers = [float(v) for v in c["text"].replace("%", " ").replace("s", " ").split()
                       if v.replace(".", "").isdigit()]
            assert numbers[-3:-1] == pytest.approx([since / 10, age / 10], abs=0.051)  # seconds, 1 decimal
            assert numbers[-1] == pytest.approx(100 * missing, abs=0.501)             # whole per cent
            members = next(g for g in rec.comm_at(rows[k]).groups if i in g)
            assert int(c["group"]) == min(members)
            assert (f"with {len(members) - 1}" if len(members) > 1 else "alone") in c["text"]
        shown.append([c["age"] for c in cells])
    assert len({tuple(x) for x in shown}) == 3  # it follows the playback
    assert max(max(a) for a in robots["aoi_age"]) > 50  # ... of a run where robots lose touch


def test_trails_fade_and_can_be_limited_to_the_last_seconds(page, recording):
    rec = recording[0]
    t, old = rec.last_tick, rec.last_tick - 400
    set_layers(page, **{**ONLY, "trails": True})
    page.evaluate(f"swarmViewer.setTick({t})")
    cell = page.evaluate("document.getElementById('map').width") / rec.shape[1]
    xy = rec.poses[: t + 1, :, :2] / 0.5 * cell

    def lonely(i):  # robot i's position at `old`, far from every other part of every trail
        p = xy[old, i]
        d = np.hypot(*(xy - p).transpose(2, 0, 1))
        d[max(0, old - 40): old + 40, i] = np.inf
        return d.min() > 8

    robot = next(i for i in range(rec.n_robots) if lonely(i))
    x, y = expected_canvas_xy(page, rec, *rec.poses[old, robot, :2])
    page.locator("#trail-fade").uncheck()
    page.fill("#trail-seconds", "0")
    assert page.evaluate("swarmViewer.trailRange()") == [0, t]
    whole = map_image(page)[int(y), int(x)]
    page.fill("#trail-seconds", "5")
    assert page.evaluate("swarmViewer.trailRange()") == [t - 50, t]
    limited = map_image(page)[int(y), int(x)]
    set_layers(page, trails=False)
    base = map_image(page)[int(y), int(x)]
    assert not np.array_equal(whole, base) and np.array_equal(limited, base)
    set_layers(page, trails=True)
    page.fill("#trail-seconds", "0")
    page.locator("#trail-fade").check()
    faded = map_image(page)[int(y), int(x)]
    assert np.abs(faded - base).sum() < np.abs(whole - base).sum()  # 40 s old: faded toward the map


def test_a_version_1_recording_plays_without_the_communication_layers(browser, tmp_path):
    html = write_html(V1_FILE, tmp_path / "v1.html")
    for pg in open_page(browser, html):
        assert pg.evaluate("swarmViewer.hasComm") is False
        pg.evaluate("swarmViewer.setTick(30)")
        assert "tick 30 / 40" in pg.inner_text("#readout")
        assert pg.evaluate("swarmViewer.drawnLosses()") == [] and pg.evaluate("swarmViewer.drawnGroups()") == []
        assert pg.locator("#aoi-panel").is_hidden()
        assert "format version 1" in pg.inner_text("#lost-legend")


def test_a_version_2_recording_plays_as_version_3_of_the_same_run(browser, tmp_path):
    """Version 3 stores link toggles, RSSI updates and merges as per-tick gaps: the page shows the run
    recorded before that change exactly as the same run recorded now."""
    from tests.swarm.record.test_record_comm import V2_FILE, V2_SPEC
    record_run(Simulation(V2_SPEC), tmp_path / "v3.swr")
    shown = []
    for path in (V2_FILE, tmp_path / "v3.swr"):
        html = write_html(path, tmp_path / (path.stem + ".html"))
        for pg in open_page(browser, html):
            seen = []
            for tick in (0, 30, 60, 90, 120):
                pg.evaluate(f"swarmViewer.setTick({tick})")
                seen.append((pg.evaluate("swarmViewer.linkCount()"), pg.evaluate("swarmViewer.groups()"),
                             pg.evaluate("swarmViewer.aoi()"), pg.evaluate("swarmViewer.knownCell(1, 10, 10)")))
            shown.append(seen)
    assert shown[0] == shown[1]
    assert len({str(s[0]) for s in shown[0]}) > 1  # the links changed over the run


# ------------------------------------------------------------------------------ swarm size ----
SWARM_SPEC = {"seed": 3, "map": {"kind": "building", "size": 50}, "robots": {"count": 120},
              "stop": {"max_ticks": 40}, "radio": {"tx_power_dbm": -30.0}, "comm": {"loss": 0.2}}
"""More robots than the viewer draws as discs (64), crowded at the start, more links, message deliveries
and losses than a frame draws."""
SWARM_TICK = 20


@pytest.fixture(scope="module")
def swarm_recording(tmp_path_factory):
    folder = tmp_path_factory.mktemp("swarm")
    path = folder / "swarm.swr"
    result = record_run(Simulation(SWARM_SPEC), path)
    return load_recording(path), write_html(path, folder / "swarm.html"), result


@pytest.fixture
def swarm_page(browser, swarm_recording):
    yield from open_page(browser, swarm_recording[1])


@pytest.mark.parametrize("width", [1280, 600])
def test_a_swarm_is_drawn_as_points_at_most_one_per_pixel_cell(browser, swarm_recording, width):
    """In a small window (2 pixels a cell) robots that start side by side share pixel cells."""
    rec = swarm_recording[0]
    for pg in open_page(browser, swarm_recording[1], width=width, height=400 if width < 1000 else 800):
        assert pg.evaluate("swarmViewer.pointMode()") is True
        set_layers(pg, **ONLY)
        cell = pg.evaluate("swarmViewer.budgets.pointCell")
        for tick in (0, SWARM_TICK):
            pg.evaluate(f"swarmViewer.setTick({tick})")
            check_points(pg, rec, tick, cell, crowded=width < 1000 and tick == 0)


def check_points(pg, rec, tick, cell, crowded):
    """One point per occupied pixel cell (fewer than robots when crowded), every robot under or next to a
    point in a robot's colour."""
    xy = np.array([expected_canvas_xy(pg, rec, *rec.poses[tick, i, :2]) for i in range(rec.n_robots)])
    cells = {(int(x // cell), int(y // cell)) for x, y in xy}
    assert pg.evaluate("swarmViewer.drawnCounts().robots") == len(cells)
    if crowded:
        assert len(cells) < rec.n_robots
    image, palette = map_image(pg), np.array(ROBOT_COLOURS)
    for x, y in xy:
        window = image[max(0, int(y) - cell): int(y) + cell + 1, max(0, int(x) - cell): int(x) + cell + 1]
        assert (window.reshape(-1, 1, 3) == palette).all(axis=2).any()


def test_a_swarm_robots_own_map_is_rebuilt_when_selected(swarm_page, swarm_recording):
    """Only the selected robot's map is held, rebuilt from its stream entries, exact forward and back."""
    rec, pg = swarm_recording[0], swarm_page
    h, w = rec.shape
    held = pg.evaluate("swarmViewer.stateBytes()")
    assert held["robotMapCount"] == 0 and held["state"] < rec.n_robots * h * w   # not every robot's map
    for robot, tick in ((77, SWARM_TICK), (77, rec.last_tick), (77, 3), (5, SWARM_TICK), (77, 0)):
        pg.evaluate(f"swarmViewer.setTick({tick}); swarmViewer.select({robot})")
        known = pg.evaluate(f"""() => {{ const out = [];
            for (let r = 0; r < {h}; r++) for (let c = 0; c < {w}; c++) out.push(swarmViewer.knownCell({robot}, r, c));
            return out; }}""")
        want = rec.known_at(tick)[robot]
        assert np.array_equal(np.array(known, dtype=np.uint8).reshape(h, w), want)
        text = pg.locator("#robot-panel").inner_text()   # counts kept without the map
        assert f"{int((want == 1).sum())} free + {int((want == 2).sum())} wall cells" in text
        held = pg.evaluate("swarmViewer.stateBytes()")
        assert 1 <= held["robotMapCount"] <= 2 and held["robotMaps"] < 2 * 8 * h * w


def test_a_swarms_panels_list_the_oldest_information_only(swarm_page, swarm_recording):
    rec, pg = swarm_recording[0], swarm_page
    rows = pg.evaluate("swarmViewer.budgets.aoiRows")
    pg.evaluate(f"swarmViewer.setTick({SWARM_TICK})")
    comm = rec.comm_at(SWARM_TICK)
    oldest = sorted(range(rec.n_robots), key=lambda i: (-comm.aoi_age[i], i))[:rows]
    cells = pg.evaluate("Array.from(document.querySelectorAll('#aoi-rows tr')).map((tr) => ({ ...tr.dataset }))")
    assert [int(c["robot"]) for c in cells] == oldest
    assert [float(c["age"]) for c in cells] == [comm.aoi_age[i] for i in oldest]
    assert f"the {rows} of {rec.n_robots} robots" in pg.inner_text("#aoi-note")
    other = next(i for i in range(rec.n_robots) if i not in oldest)
    pg.evaluate(f"swarmViewer.select({other})")
    assert int(pg.evaluate("document.querySelector('#aoi-rows tr:last-child').dataset.robot")) == other
    heard = rec.links_at(SWARM_TICK)[0][other].sum()
    items = pg.evaluate("swarmViewer.budgets.listItems")
    assert heard > items
    links = pg.inner_text("#robot-links")
    assert links.count("dB margin") == items and f"the strongest {items} of {heard}" in links


def test_a_swarms_links_messages_and_losses_are_drawn_within_budgets(swarm_page, swarm_recording):
    rec, pg = swarm_recording[0], swarm_page
    budgets = pg.evaluate("swarmViewer.budgets")
    pg.evaluate(f"swarmViewer.setTick({SWARM_TICK})")
    link = rec.links_at(SWARM_TICK)[0]
    pairs = int((link | link.T).sum()) // 2
    window = [m for m in rec.messages() if SWARM_TICK - 6 < m.tick <= SWARM_TICK]
    deliveries, lost = sum(len(m.receivers) for m in window), [(m, r) for m in window for r, _ in m.lost]
    assert pairs > budgets["links"] and deliveries > budgets["messages"] and len(lost) > budgets["losses"]
    drawn = pg.evaluate("swarmViewer.drawnCounts()")
    assert budgets["links"] / 2 <= drawn["links"] <= budgets["links"]            # an even sample, not none
    assert budgets["messages"] / 2 <= drawn["messages"] <= budgets["messages"]
    assert budgets["losses"] / 2 <= drawn["losses"] <= budgets["losses"]
    want = {(m.tick, m.transmitter, r) for m, r in lost}
    assert {(d["tick"], d["from"], d["to"]) for d in pg.evaluate("swarmViewer.drawnLosses()")} <= want


def test_a_recording_embedded_in_pieces_plays(browser, recording, tmp_path, monkeypatch):
    from swarm.viewer import build

    rec = recording[0]
    monkeypatch.setattr(build, "PIECE_BYTES", 3 * 4000)
    source = tmp_path / "run.swr"
    source.write_bytes(Path(recording[1]).with_suffix(".swr").read_bytes())
    html = write_html(source, tmp_path / "pieces.html")
    assert html.read_text().count('class="swr-data"') > 2
    for pg in open_page(browser, html):
        assert pg.evaluate("document.querySelectorAll('script.swr-data').length") == 0   # dropped once decoded
        pg.evaluate(f"swarmViewer.setTick({TICK})")
        assert pg.evaluate("swarmViewer.pose(1)") == rec.poses[TICK, 1].tolist()


def test_zooming_in_on_a_swarm_draws_the_robots_in_view_as_discs(swarm_page, swarm_recording):
    rec, pg = swarm_recording[0], swarm_page
    set_layers(pg, **ONLY)
    pg.evaluate(f"swarmViewer.setTick({SWARM_TICK})")
    robot = 7
    before = pg.evaluate(f"swarmViewer.robotScreenPosition({robot})")
    mouse = np.round([before["x"], before["y"]])
    pg.mouse.move(*mouse)
    for _ in range(3):
        pg.mouse.wheel(0, -400)
    pg.wait_for_function("swarmViewer.view().zoom > 8")
    view = pg.evaluate("swarmViewer.view()")
    after = pg.evaluate(f"swarmViewer.robotScreenPosition({robot})")
    # the wheel zooms about the mouse: the point under it stays, the robot (a fraction of a pixel away) with it
    moved = np.subtract([after["x"], after["y"]], mouse)
    assert moved == pytest.approx(np.subtract([before["x"], before["y"]], mouse) * view["zoom"], abs=0.01)
    x, y = expected_canvas_xy(pg, rec, *rec.poses[SWARM_TICK, robot, :2])
    want = (x * view["zoom"] - view["offX"], y * view["zoom"] - view["offY"])
    assert (after["canvasX"], after["canvasY"]) == pytest.approx(want, abs=0.01)
    assert pg.evaluate("swarmViewer.pointMode()") is False   # few robots in view: discs, as at team size
    assert after["radius"] > 10
    assert canvas_pixel(pg, after["canvasX"], after["canvasY"]) == ROBOT_COLOURS[robot % len(ROBOT_COLOURS)]
    pg.mouse.down()   # a drag pans (and is not a click: nothing gets selected)
    pg.mouse.move(mouse[0] - 100, mouse[1] - 50, steps=5)
    pg.mouse.up()
    panned = pg.evaluate("swarmViewer.view()")
    assert (panned["offX"], panned["offY"]) == pytest.approx((view["offX"] + 100, view["offY"] + 50))
    assert pg.evaluate("swarmViewer.selected()") is None
    pg.keyboard.press("0")
    assert pg.evaluate("swarmViewer.view()") == {"zoom": 1, "offX": 0, "offY": 0}
    assert pg.evaluate("swarmViewer.pointMode()") is True


def test_the_robot_panel_gives_the_age_of_what_it_knows_of_each_other_robot(page, recording):
    rec, pg = recording[0], page
    tick, robot = rec.last_tick - 100, 1
    pg.evaluate(f"swarmViewer.setTick({tick}); swarmViewer.select({robot})")
    comm = rec.comm_at(tick)
    text = pg.locator("#robot-facts").inner_text()
    ages = "; ".join([f"{comm.aoi_age[robot] / 10:.1f} s on average",
                      ", ".join(f"{s}: {(tick - comm.merged_at[robot, s]) / 10:.1f} s"
                                for s in range(rec.n_robots) if s != robot)])
    assert f"info age\t{ages}" in text


def test_a_swarm_robots_panel_gives_its_mean_age_of_information(swarm_page, swarm_recording):
    """Above 64 robots the map-merge pairs are not kept (two thirds of a decoded swarm recording)."""
    rec, pg = swarm_recording[0], swarm_page
    pg.evaluate(f"swarmViewer.setTick({SWARM_TICK}); swarmViewer.select(3)")
    age = rec.comm_at(SWARM_TICK).aoi_age[3]
    assert f"info age\t{age / 10:.1f} s on average\n" in pg.locator("#robot-facts").inner_text() + "\n"


def check_links_drawn_once(pg, rec, ticks) -> list[int]:
    """Every pair with a link either way is drawn, one line each (below the budget); the pair counts."""
    set_layers(pg, **{**ONLY, "links": True})
    counts = []
    for tick in ticks:
        link = rec.links_at(tick)[0]
        pg.evaluate(f"swarmViewer.setTick({tick})")
        counts.append(int(np.triu(link | link.T, 1).sum()))
        assert pg.evaluate("swarmViewer.drawnCounts().links") == counts[-1]
    return counts


def test_each_linked_pair_is_drawn_once(page, recording):
    counts = check_links_drawn_once(page, recording[0], range(0, recording[0].ticks, 97))
    assert 0 < max(counts) and min(counts) < max(counts)


def test_each_linked_pair_of_a_spread_swarm_is_drawn_once(browser, tmp_path):
    """Robots spread at random: few links (the viewer then visits set bits, not all pairs)."""
    sim = Simulation({**SWARM_SPEC, "robots": {"count": 100, "spawn": "random"}, "stop": {"max_ticks": 10}})
    recorder = Recorder.attach(sim)
    recorder.finish(sim, sim.run())
    path = recorder.save(tmp_path / "spread.swr")
    rec = load_recording(path)
    for pg in open_page(browser, write_html(path, tmp_path / "spread.html")):
        counts = check_links_drawn_once(pg, rec, range(rec.ticks))
        assert 0 < max(counts) and 2 * max(counts) < rec.n_robots ** 2 / 8   # sparse indeed


# ------------------------------------------------------------------------------ readability (issue 53) ----
def dark(image: np.ndarray) -> np.ndarray:
    return image.sum(axis=-1) < 120


def test_the_lost_readout_counts_the_window_the_layer_draws(page, recording):
    rec = recording[0]
    window = page.evaluate("swarmViewer.lostTicks")
    assert f"(last {window} ticks, {window / 10:.1f} s)" in page.inner_text("#layers")
    lost = [(m.tick, m.transmitter, r) for m in rec.messages() for r, _ in m.lost]
    per_tick = np.bincount([t for t, _, _ in lost], minlength=rec.ticks + 1)
    in_window = np.convolve(per_tick, np.ones(window, dtype=int))[: len(per_tick)]
    # a tick whose window holds losses from more than one tick (the one-tick count would differ)
    tick = next(t for t in range(window, rec.ticks) if 0 < per_tick[t] < in_window[t] < 200)
    set_layers(page, **{**ONLY, "lost": True})
    page.evaluate(f"swarmViewer.setTick({tick})")
    readout = page.inner_text("#readout")
    assert f"lost in the last {window} ticks: {in_window[tick]}" in readout, readout
    assert len(page.evaluate("swarmViewer.drawnLosses()")) == in_window[tick] == page.evaluate("swarmViewer.lostCount()")


def test_a_scale_bar_and_metre_grid_are_drawn_and_toggle(page, recording):
    rec = recording[0]
    set_layers(page, **ONLY)
    page.evaluate(f"swarmViewer.setTick({TICK})")
    assert page.evaluate("swarmViewer.scaleBar()") is None
    bare = map_image(page)
    set_layers(page, grid=True)
    bar = page.evaluate("swarmViewer.scaleBar()")
    cell = page.evaluate("swarmViewer.cellPx()")
    assert bar["metres"] in (1, 2, 5, 10, 20) and bar["px"] == pytest.approx(bar["metres"] / 0.5 * cell)
    assert 80 <= bar["px"] < 250
    image = map_image(page)
    y = int(bar["y"])
    assert dark(image[y, int(bar["x"]) + 2: int(bar["x"] + bar["px"]) - 2]).all()  # the bar, its full length
    assert not dark(bare[y, int(bar["x"]) + 2: int(bar["x"] + bar["px"]) - 2]).all()
    # grid lines: at every whole step of metres from the map's west edge, and nowhere else along a row
    step = page.evaluate("swarmViewer.gridMetres()")
    assert step * 2 * cell >= 70
    first = (rec.shape[0] - step / 0.5) * cell          # the horizontal line at `step` m from the south edge
    y = int(first - 0.6 * step / 0.5 * cell)             # between two horizontal lines and below its labels
    row = np.any(image != bare, axis=2)[y]
    lines = np.nonzero(row)[0]
    lines = lines[lines > 45]                            # right of the labels along the west edge
    want = np.arange(step, rec.shape[1] * 0.5, step) / 0.5 * cell
    want = want[want > 45]
    assert len(want) >= 3 and all(np.abs(lines - w).min() <= 1 for w in want)
    assert all(np.abs(want - c).min() <= 1.5 for c in lines)


def test_robot_ids_are_big_and_can_be_hidden(page, recording):
    rec = recording[0]
    set_layers(page, **{**ONLY, "ids": True})
    page.evaluate(f"swarmViewer.setTick({TICK})")
    radius = page.evaluate("swarmViewer.robotScreenPosition(0).radius")
    clustered = {i for c in page.evaluate("swarmViewer.drawnClusters()") for i in c}
    robot = next(i for i in range(rec.n_robots) if i not in clustered)
    p = page.evaluate(f"swarmViewer.robotScreenPosition({robot})")
    x0, y1 = int(p["canvasX"] + radius + 2), int(p["canvasY"] - radius - 1)
    box = (slice(max(0, y1 - 14), y1 + 1), slice(x0, x0 + 10 * len(str(robot)) + 2))
    on = dark(map_image(page)[box]).sum()
    set_layers(page, ids=False)
    off = dark(map_image(page)[box]).sum()
    assert on >= 15 and off < on / 3, (on, off)  # bold 13 px digits, gone when hidden


def test_the_robot_panel_is_beside_the_map_at_1400_by_900(page, recording):
    page.evaluate(f"swarmViewer.setTick({TICK}); swarmViewer.select(1)")
    panel = page.locator("#robot-panel").bounding_box()
    stage = page.locator("#map").bounding_box()
    assert page.evaluate("[window.innerWidth, window.innerHeight]") == [1400, 900]
    assert panel["x"] >= stage["x"] + stage["width"] and panel["x"] + panel["width"] <= 1400
    assert panel["y"] < 120 and panel["y"] + panel["height"] <= 900  # seen without scrolling
    assert stage["width"] >= 600 and stage["y"] + stage["height"] <= 900


def goal_at(rec, robot: int, tick: int):
    """The goal the robot drives to at ``tick``, as the viewer's currentGoal finds it: its latest action that
    sets or clears one (an action without a goal keeps the previous)."""
    for t in range(tick, -1, -1):
        changed = rec.actions_changed(t)
        if robot in changed:
            act = changed[robot]
            if act is None:
                return None
            if isinstance(act["goal"], (list, tuple)) and len(act["goal"]) == 2:
                return list(act["goal"])
            if act["clear_goal"]:
                return None
    return None


def test_every_robots_goal_is_drawn_and_can_be_hidden(page, recording):
    rec = recording[0]
    set_layers(page, **{**ONLY, "goals": True})
    page.evaluate(f"swarmViewer.setTick({TICK})")
    want = {i: goal_at(rec, i, TICK) for i in range(rec.n_robots)}
    drawn = {g["robot"]: g for g in page.evaluate("swarmViewer.drawnGoals()")}
    assert {i: g["goal"] for i, g in drawn.items()} == {i: g for i, g in want.items() if g is not None}
    assert len(drawn) >= 2
    image = map_image(page)
    hits = 0
    for i, g in drawn.items():
        x, y = expected_canvas_xy(page, rec, *g["goal"])
        assert (g["x"], g["y"]) == (pytest.approx(x, abs=0.01), pytest.approx(y, abs=0.01))
        patch = image[int(y) - 3: int(y) + 4, int(x) - 3: int(x) + 4]
        hits += bool((patch == page.evaluate(f"swarmViewer.robotColour({i})")).all(axis=2).any())
    assert hits >= len(drawn) - 1  # a cross in the robot's colour (one may hide under a robot)
    set_layers(page, goals=False)
    assert page.evaluate("swarmViewer.drawnGoals()") == []


def test_robots_drawn_on_top_of_each_other_are_one_labelled_cluster(page, recording):
    rec = recording[0]
    set_layers(page, **{**ONLY, "ids": True})
    radius = page.evaluate("swarmViewer.robotScreenPosition(0).radius")
    for tick in (0, TICK):
        page.evaluate(f"swarmViewer.setTick({tick})")
        xy = np.array([expected_canvas_xy(page, rec, *rec.poses[tick, i, :2]) for i in range(rec.n_robots)])
        near = np.hypot(*(xy[:, None] - xy[None]).transpose(2, 0, 1)) < 2 * radius + 13
        # connected components of "drawn too close", computed here
        parent = list(range(rec.n_robots))
        for i, j in zip(*np.nonzero(near)):
            a, b = parent[i], parent[j]
            parent = [min(a, b) if p in (a, b) else p for p in parent]
        groups = {}
        for i, p in enumerate(parent):
            groups.setdefault(p, []).append(i)
        want = sorted(g for g in groups.values() if len(g) > 1)
        assert sorted(page.evaluate("swarmViewer.drawnClusters()")) == want
        if tick == 0:
            assert want == [list(range(rec.n_robots))]  # spawned together: one cluster of all
            image = map_image(page)
            cx, cy = xy.min(axis=0) / 2 + xy.max(axis=0) / 2
            reach = np.hypot(*(xy - (cx, cy)).T).max() + radius + 3
            ys, xs = np.mgrid[0:image.shape[0], 0:image.shape[1]] + 0.5
            ring = np.abs(np.hypot(xs - cx, ys - cy) - reach) <= 1.5
            outside = np.abs(np.hypot(xs - cx, ys - cy) - reach - 6) <= 1.5
            assert dark(image)[ring].mean() > 0.08 > dark(image)[outside].mean()  # a dashed ring around them
            label = image[int(cy - reach - 30): int(cy), int(cx + 0.5 * reach): int(cx + reach + 140)]
            assert dark(label).sum() > 60  # the count badge and "robots 0-3"
