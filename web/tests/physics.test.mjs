// The world view of a ROS 2 robot: the physics robot (`python -m situate.physics`, MuJoCo, over
// rmw_zenoh on situate's link) publishes its true pose on `ground_truth/odom`, its people on
// `ground_truth/people` and its cars on `ground_truth/cars`, and the delivery robot of
// demo/physics.yaml, run by `situate run --map`, maps them onto `truth.pose`, `truth.people`
// and `truth.cars`, and the altimeter's `/floor` onto `floor`. The GUI draws the building from
// the map, the robot where the physics puts it, on its floor (the pose itself has none), the
// people walking there and the cars' floors and doors, and follows the robot as it drives.

import assert from "node:assert/strict";
import { existsSync } from "node:fs";
import path from "node:path";
import { after, afterEach, before, describe, test } from "node:test";
import { cli, cliDo, freePort, openPage, repo, screenshotPath, situateBin, startBrowser, startProgram, stopBrowser, until } from "./harness.mjs";

// The physics robot needs the Python package and MuJoCo: the checkout's .venv (scripts/python.sh).
const venvPython = path.join(repo, ".venv", "bin", "python");
const python = process.env.SITUATE_PYTHON || (existsSync(venvPython) ? venvPython : "python3");

/** Stops a program with `signal`, killing it if it lingers. */
async function stop(p, signal) {
  if (!p || p.exit !== null) return;
  p.child.kill(signal);
  const timer = setTimeout(() => p.child.kill("SIGKILL"), 20_000);
  await p.exited;
  clearTimeout(timer);
}

/** The world view's robot as its info line says it: x, y, floor, and the floor shown. */
async function shown(page) {
  const text = (await page.getByTestId("world-info").textContent()) ?? "";
  const m = text.match(/robot at \((-?[\d.]+), (-?[\d.]+)\) m, θ \d+°, floor (-?\d+); showing floor (-?\d+)/);
  return m ? { x: Number(m[1]), y: Number(m[2]), floor: Number(m[3]), showing: Number(m[4]), text } : { text };
}

describe("the world view of the physics robot", () => {
  let robot;
  let physics;
  let browser;
  let page;
  let linkPort;

  before(async () => {
    const guiPort = await freePort();
    linkPort = await freePort();
    while (linkPort === guiPort) linkPort = await freePort();
    const listen = `tcp/127.0.0.1:${linkPort}`;
    robot = startProgram(situateBin, ["run", "demo/physics.yaml", "--map", "maps/default.yaml", "--gui", `127.0.0.1:${guiPort}`, "--listen", listen]);
    await until(() => robot.err.includes("GUI on http") || robot.exit !== null, `the robot's GUI\nstderr:\n${robot.err}`, 120_000);
    assert.equal(robot.exit, null, `situate run exited\nstderr:\n${robot.err}`);
    physics = startProgram(python, ["-m", "situate.physics", "maps/default.yaml", "--connect", listen, "--lockstep", "/deliverybot/cycle", "--time-scale", "2", "--people", "2"]);
    await until(() => physics.out.includes("physics robot in") || physics.exit !== null, `the physics robot\nstdout:\n${physics.out}\nstderr:\n${physics.err}`, 120_000);
    assert.equal(physics.exit, null, `python -m situate.physics exited\nstderr:\n${physics.err}`);
    browser = await startBrowser();
    page = await openPage(browser, `http://127.0.0.1:${guiPort}/`);
  });

  after(async () => {
    await stopBrowser(browser).catch(() => undefined);
    await stop(physics, "SIGTERM");
    await stop(robot, "SIGINT");
  });

  afterEach(async (t) => {
    if (page) await page.screenshot({ path: screenshotPath(`physics-${t.name.replace(/[^a-z0-9]+/gi, "-")}`), fullPage: true }).catch(() => undefined);
  });

  test("the robot is drawn where the physics puts it, on its floor, in the building", async () => {
    // The map's floors are offered: the building came with --map.
    const floors = await page.getByTestId("world-floor").locator("option").evaluateAll((os) => os.map((o) => o.value));
    assert.deepEqual(floors, ["auto", "-1", "0", "1", "2", "3", "4"]);
    // The robot stands (no skill drives) at the mission's start, in the lab on floor -1.
    const first = await until(async () => {
      const s = await shown(page);
      return s.floor !== undefined && s;
    }, "the world view's robot", 120_000).catch(async (e) => {
      throw new Error(`${e.message}: the world view says ${JSON.stringify((await shown(page)).text)}`);
    });
    assert.equal(first.floor, -1, first.text);
    assert.equal(first.showing, -1, first.text);
    assert.ok(Math.hypot(first.x - 1.5, first.y - 1.5) < 0.1, `at the start pose (1.5, 1.5): ${first.text}`);
    // ... which is the robot's truth.pose over the link (the ROS 2 ground truth).
    const truth = await cli(linkPort, "query", "truth.pose");
    assert.ok(Math.hypot(truth.value.x - first.x, truth.value.y - first.y) < 0.01, `${JSON.stringify(truth)} vs ${first.text}`);
    assert.equal((await cli(linkPort, "query", "floor")).value, -1);
    // Drawn: a red disc at its place on the canvas showing floor -1.
    const canvas = page.getByTestId("world-canvas");
    assert.equal(await canvas.getAttribute("data-floor"), "-1");
    await until(async () => Number(await canvas.getAttribute("data-draws")) >= 2, "the robot drawn");
    const ring = await canvas.evaluate((c) => {
      const [x, y, r] = [Number(c.dataset.robotPx), Number(c.dataset.robotPy), Number(c.dataset.robotPr)];
      const ctx = c.getContext("2d");
      return [...Array(8).keys()].map((k) => {
        const a = (k * Math.PI) / 4 + 0.2;
        return [...ctx.getImageData(Math.round(x + 0.6 * r * Math.cos(a)), Math.round(y + 0.6 * r * Math.sin(a)), 1, 1).data];
      });
    });
    assert.ok(ring.filter(([r, g, b]) => r > 150 && g < 90 && b < 90).length >= 5, `the robot's disc is red: ${JSON.stringify(ring)}`);
  });

  test("the people walking on the robot's floor and the cars' floors and doors are drawn", async () => {
    const canvas = page.getByTestId("world-canvas");
    // The people on the floor shown (the robot's, -1) are those truth.people has there.
    const walking = await until(async () => {
      const q = await cli(linkPort, "query", "truth.people");
      return Array.isArray(q.value?.floor) && q.value.floor.length > 0 && q.value;
    }, "truth.people from ground_truth/people", 120_000);
    const here = walking.floor.filter((f) => f === -1).length;
    assert.ok(here > 0, `people on floor -1: ${JSON.stringify(walking)}`);
    await until(async () => Number(await canvas.getAttribute("data-people")) === here, `${here} people drawn on floor -1`);
    // Each car of the map is labelled with its floor and its door's state, from truth.cars.
    const cars = (await cli(linkPort, "query", "truth.cars")).value;
    assert.ok(Array.isArray(cars.floor) && cars.floor.length === cars.door.length && cars.floor.length > 1, JSON.stringify(cars));
    const labels = await until(async () => {
      const ls = JSON.parse((await canvas.getAttribute("data-labels")) ?? "[]").map((l) => l.text);
      return ls.filter((t) => t.startsWith("fl ")).length === cars.floor.length && ls;
    }, "a floor label for every car");
    for (let i = 1; i <= cars.floor.length; i++) assert.ok(labels.includes(`car ${i}`), `car ${i}: ${JSON.stringify(labels)}`);
    assert.ok(labels.some((t) => t === "open" || t === "closed" || t.endsWith(" %")), `the doors' states: ${JSON.stringify(labels)}`);
  });

  test("the view follows the robot as the skills drive it, and its trail grows on its floor", async () => {
    const from = await shown(page);
    assert.equal(from.floor, -1, from.text);
    await cliDo(linkPort, "activate", "runaway", "avoid", "wander");
    const moved = await until(async () => {
      const s = await shown(page);
      return s.floor !== undefined && Math.hypot(s.x - from.x, s.y - from.y) > 0.5 && s;
    }, "the robot driven half a metre in the world view", 180_000);
    assert.equal(moved.floor, -1, moved.text);
    // Inside the lab (x 0..8, y 0..6): its walls hold the physics robot.
    assert.ok(moved.x > 0 && moved.x < 8 && moved.y > 0 && moved.y < 6, moved.text);
    const trail = JSON.parse((await page.getByTestId("world-canvas").getAttribute("data-trail")) ?? "{}");
    assert.ok(trail["-1"] >= 5, `a trail on floor -1: ${JSON.stringify(trail)}`);
    assert.deepEqual(Object.keys(trail), ["-1"], "no trail on any other floor");
  });

  test("paused, the world view shows the robot of a past cycle, on its floor then", async () => {
    const bar = page.getByTestId("timeline");
    await page.getByTestId("tl-live").click();
    await until(async () => (await bar.getAttribute("data-mode")) === "paused" && (await bar.getAttribute("data-shown")) !== null, "paused at a cycle");
    const at = Number(await bar.getAttribute("data-shown"));
    await until(async () => ((await page.getByTestId("world-past").textContent()) ?? "").startsWith(`at cycle ${at} (paused`), "the world view at the cycle shown");
    const then = await shown(page);
    assert.equal(then.floor, -1, then.text);
    assert.equal(then.showing, -1, then.text);
    assert.equal(await page.getByTestId("world-canvas").getAttribute("data-floor"), "-1");
    await page.getByTestId("tl-live").click();
    await until(async () => (await bar.getAttribute("data-mode")) === "live", "live again");
  });
});
