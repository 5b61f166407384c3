// The GUI tells the truth about time: a robot that is gone is not shown as live, a restarted robot
// is a new run, an inactive skill's outputs are not live values. Each effect is checked against the
// robot itself (the `situate` CLI over the link, or the GUI server's own proxy of the link's verbs).

import assert from "node:assert/strict";
import { spawn } from "node:child_process";
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from "node:fs";
import os from "node:os";
import path from "node:path";
import { after, afterEach, before, describe, test } from "node:test";
import { cli, cliDo, closeGui, killTestbed, openGui, repo, screenshotPath, situateBin, startTestbed, until } from "./harness.mjs";

const text = async (locator) => (await locator.textContent()) ?? "";

describe("a robot that goes away and comes back", () => {
  let tb;
  let browser;
  let page;
  let oldRun;

  before(async () => {
    ({ tb, browser, page } = await openGui());
  });

  after(() => closeGui({ tb, browser }));

  afterEach(async (t) => {
    if (page) await page.screenshot({ path: screenshotPath(t.name.replace(/[^a-z0-9]+/gi, "-")), fullPage: true }).catch(() => undefined);
  });

  test("without the robot every live value says when it was last seen, and controls are disabled", async () => {
    // Something of this run in every place a new run must clear: a plot, the trail, a monitor and its events.
    await page.getByTestId("plot-signal").fill("odom.x");
    await page.getByTestId("plot-add").click();
    const plot = page.getByTestId("plot-canvas").first();
    await until(async () => Number(await plot.getAttribute("data-points")) >= 5, "the plot has points");
    await page.getByTestId("monitor-condition").fill("odom.x < 1000");
    await page.getByTestId("monitor-mode").selectOption("edge");
    await page.getByTestId("monitor-add").click();
    await until(async () => (await page.locator('[data-testid="event-log"] [data-kind="monitor_fired"]').count()) > 0, "the monitor's event");
    await until(async () => (await text(page.getByTestId("stat-state"))) === "running", "the state shown while connected");
    assert.match(await text(page.getByTestId("stat-rate")), /Hz/);
    oldRun = await page.evaluate(() => document.body.dataset.run);
    assert.ok(oldRun, "the hello named the run");
    assert.equal(await page.getByTestId("timeline").getAttribute("data-link"), "up");
    assert.equal(await text(page.getByTestId("tl-live")), "● Live");

    await killTestbed(tb);
    await until(async () => (await text(page.getByTestId("status"))).includes("disconnected"), "the page sees the robot gone");
    const state = await text(page.getByTestId("stat-state"));
    assert.ok(!state.includes("running"), `the state no longer claims running: ${state}`);
    assert.match(state, /disconnected/);
    assert.ok(!(await text(page.getByTestId("stat-rate"))).includes("Hz"), "no rate is claimed");
    // Every live panel says when its values were last seen; the time keeps counting.
    const livePanels = await page.locator(".panel.live").count();
    assert.ok(livePanels >= 5, `the live panels: ${livePanels}`);
    const notes = page.locator(".panel.live h2 [data-testid=stale-note]");
    assert.equal(await notes.count(), livePanels, "one note per live panel");
    await until(async () => {
      for (let i = 0; i < livePanels; i++) {
        if (!(await notes.nth(i).isVisible())) return false;
        if (!/^last seen at cycle \d+, [2-9]\d* s ago$|^last seen at cycle \d+, \d{2,} s ago$/.test(await text(notes.nth(i)))) return false;
      }
      return true;
    }, "every live panel: last seen at cycle N, t ≥ 2 s ago");
    assert.match(await text(page.getByTestId("stale-banner")), /not live/);
    // Where the run's cycles are now, if the robot died: its recording, opened from the file.
    assert.match(await text(page.getByTestId("stale-banner")), /situate replay FILE --view --recover --gui/);
    // Controls that need the robot are disabled, not failing on click.
    for (const id of ["run", "stop", "step", "switch-wander", "monitor-add", "plot-add"]) {
      assert.equal(await page.getByTestId(id).isDisabled(), true, `${id} is disabled`);
    }
    // Local controls still work.
    assert.equal(await page.getByTestId("world-reset").isDisabled(), false);
    // The timeline's bar does not say "Live" either.
    const bar = page.getByTestId("timeline");
    assert.equal(await bar.getAttribute("data-link"), "down");
    assert.equal(await text(page.getByTestId("tl-live")), "○ Disconnected");
    assert.ok(await page.getByTestId("tl-live").evaluate((b) => b.classList.contains("disconnected")), "drawn as disconnected (not live's colour)");
  });

  test("a restart on the same port is a new run: plots, trail and monitors start afresh, old events are set apart", async () => {
    assert.ok(oldRun, "the previous test ran");
    tb = await startTestbed([], { guiPort: tb.guiPort });
    await until(async () => {
      const run = await page.evaluate(() => document.body.dataset.run);
      return run && run !== oldRun;
    }, "the page sees the new run");
    await until(async () => (await text(page.getByTestId("status"))) === "connected", "connected again");
    await until(async () => (await page.getByTestId("timeline").getAttribute("data-link")) === "up", "the bar connected again");
    assert.equal(await text(page.getByTestId("tl-live")), "● Live");
    const newRun = await page.evaluate(() => document.body.dataset.run);
    assert.match(await text(page.getByTestId("run-info")), new RegExp(`run ${newRun}`));
    // The new run's start, as its hello says (the same clock as the telemetry's wall time).
    const started = await page.evaluate(async () => {
      const ws = new WebSocket(`ws://${location.host}/ws`);
      const hello = await new Promise((resolve, reject) => {
        ws.onmessage = (m) => resolve(JSON.parse(m.data));
        ws.onerror = () => reject(new Error("the WebSocket failed"));
      });
      ws.close();
      return hello.run.started_unix_s;
    });
    assert.ok(started > 1.6e9, `the hello's start time: ${started}`);
    const separator = page.getByTestId("run-separator");
    await separator.waitFor({ timeout: 60_000 });
    assert.match(await text(separator), new RegExp(`new run ${newRun}.*previous run \\(${oldRun}\\)`));
    const oldEvents = page.locator('[data-testid="event-log"] [data-kind="monitor_fired"]');
    assert.ok((await oldEvents.count()) > 0);
    assert.equal(await page.locator('[data-testid="event-log"] [data-kind="monitor_fired"]:not(.old-run)').count(), 0, "the old run's events are marked as old");
    // The plot starts again: no point older than the new run.
    const plot = page.getByTestId("plot-canvas").first();
    await until(async () => Number(await plot.getAttribute("data-points")) >= 3, "the plot has points of the new run");
    const since = Number(await plot.getAttribute("data-since"));
    assert.ok(since >= started, `the plot's first point (${since}) is not older than the run (${started})`);
    const world = page.getByTestId("world-canvas");
    await until(async () => Number(await world.getAttribute("data-trail-since")) > 0, "a trail in the new run");
    assert.ok(Number(await world.getAttribute("data-trail-since")) >= started, "the trail is of the new run only");
    // The old run's monitor is not listed (the new robot has none).
    await until(async () => !(await text(page.getByTestId("monitors"))).includes("odom.x < 1000"), "the old monitor gone");
    // Live again: no stale note, controls enabled, the state and rate shown.
    await until(async () => (await page.locator("[data-testid=stale-note]:visible").count()) === 0, "no stale note");
    await until(async () => (await text(page.getByTestId("stat-state"))) === "running", "running");
    await until(async () => /Hz/.test(await text(page.getByTestId("stat-rate"))), "a rate");
    assert.equal(await page.getByTestId("run").isDisabled(), false);
  });
});

describe("skills, monitors, the world view and the layout", () => {
  let tb;
  let browser;
  let page;

  before(async () => {
    ({ tb, browser, page } = await openGui());
  });

  after(() => closeGui({ tb, browser }));

  afterEach(async (t) => {
    if (page) await page.screenshot({ path: screenshotPath(t.name.replace(/[^a-z0-9]+/gi, "-")), fullPage: true }).catch(() => undefined);
  });

  /** Asks the GUI server's proxy of the link (the manager's own answer), from the page. */
  const ask = (verb, args = {}) =>
    page.evaluate(
      async ([verb, args]) => {
        const ws = new WebSocket(`ws://${location.host}/ws`);
        try {
          return await new Promise((resolve, reject) => {
            ws.onopen = () => ws.send(JSON.stringify({ id: 1, verb, args }));
            ws.onmessage = (m) => {
              const msg = JSON.parse(m.data);
              if (msg.type === "reply" && msg.id === 1) (msg.error ? reject(new Error(msg.error.message)) : resolve(msg.ok));
            };
            ws.onerror = () => reject(new Error("the WebSocket failed"));
          });
        } finally {
          ws.close();
        }
      },
      [verb, args],
    );

  test("an inactive skill's outputs say since which cycle; who wins each resource is in the skills panel", async () => {
    const reply = await cli(tb.linkPort, "deactivate", "wander");
    const at = reply.at_cycle;
    assert.ok(Number.isInteger(at), `deactivate's reply: ${JSON.stringify(reply)}`);
    const panel = page.getByTestId("skill-wander");
    if (!(await panel.evaluate((d) => d.open))) await panel.locator("summary").click();
    await page.getByTestId("show-output-wander").check();
    const cell = page.getByTestId("output-table-wander").locator("td.value").first();
    await until(async () => (await cell.getAttribute("data-inactive")) !== null, "wander's output shown as inactive");
    assert.match(await text(cell), new RegExp(`^inactive since cycle ${at} `), "the cycle it was deactivated at");
    assert.equal(await text(page.getByTestId("since-wander")), `since cycle ${at}`);
    // An active skill's outputs are live values.
    const runaway = page.getByTestId("skill-runaway");
    if (!(await runaway.evaluate((d) => d.open))) await runaway.locator("summary").click();
    await page.getByTestId("show-output-runaway").check();
    await until(async () => (await page.getByTestId("output-table-runaway").locator("td.value[data-inactive]").count()) === 0 && (await page.getByTestId("output-table-runaway").locator("td.value").count()) > 0, "runaway's outputs live");

    // Resources: stopped, so the page and the manager can be compared exactly.
    await cli(tb.linkPort, "activate", "wander");
    await cliDo(tb.linkPort, "cycle", "stop");
    await cliDo(tb.linkPort, "cycle", "step", "2");
    try {
      const winners = await ask("winners");
      assert.ok(winners.length > 0, "the toy robot has resources (drive)");
      const table = page.getByTestId("resources");
      for (const w of winners) {
        const row = table.locator(`tr[data-resource="${w.signal}"]`);
        await until(async () => (await row.count()) === 1 && (await row.locator("td.winner").getAttribute("data-winner")) === (w.winner ?? ""), `${w.signal}: winner ${w.winner} in the skills panel`);
        assert.match(await text(row), new RegExp(w.writers.join(", ")));
      }
    } finally {
      await cliDo(tb.linkPort, "cycle", "run");
    }
  });

  test("a monitor can pause the cycle from the page, and the page resumes it", async () => {
    await until(async () => (await cli(tb.linkPort, "stats")).running === true, "running");
    await page.getByTestId("monitor-condition").fill("odom.x < 1000");
    await page.getByTestId("monitor-mode").selectOption("once");
    await page.getByTestId("monitor-pause").check();
    await page.getByTestId("monitor-add").click();
    await until(async () => (await cli(tb.linkPort, "stats")).running === false, "the monitor paused the cycle (over the link)");
    const paused = page.getByTestId("monitor-paused");
    await until(async () => (await paused.isVisible()) && /paused by monitor \d+/.test(await text(paused)), "the page says which monitor paused the cycle");
    await page.getByTestId("monitor-resume").click();
    await until(async () => (await cli(tb.linkPort, "stats")).running === true, "resumed (over the link)");
    await until(async () => !(await paused.isVisible()), "the pause note gone");
    await page.getByTestId("monitor-pause").uncheck();
  });

  test("a sequencer's pause is said as its own, and only once it lasts", async () => {
    await until(async () => (await cli(tb.linkPort, "stats")).running === true, "running");
    // A sequencer (the CLI's `monitor`, its own session) pauses the cycle and does not resume it.
    const seq = spawn(situateBin, ["monitor", "odom.x < 1000", "--mode", "level", "--pause", "--connect", `tcp/127.0.0.1:${tb.linkPort}`], {
      stdio: ["ignore", "pipe", "pipe"],
      env: { ...process.env, RUST_LOG: "error" },
    });
    try {
      await until(async () => (await cli(tb.linkPort, "stats")).running === false, "the sequencer's monitor paused the cycle");
      const paused = page.getByTestId("monitor-paused");
      await until(async () => (await paused.isVisible()) && /paused by .+'s monitor \d+/.test(await text(paused)), "the page says whose monitor paused the cycle");
      assert.match(await text(paused), /runs it again when done/);
      assert.notEqual(await paused.getAttribute("data-owner"), "this tab");
      assert.equal(await text(page.getByTestId("monitor-resume")), "Resume anyway");
    } finally {
      // The sequencer goes, and its monitor with its session; then the cycle runs again.
      const exited = new Promise((resolve) => (seq.exitCode !== null ? resolve() : seq.once("exit", resolve)));
      seq.kill("SIGINT");
      await exited;
      await until(async () => !(await cli(tb.linkPort, "monitors")).some((m) => m.condition === "odom.x < 1000"), "the sequencer's monitor gone with it");
      await cliDo(tb.linkPort, "cycle", "run");
    }
    await until(async () => (await cli(tb.linkPort, "stats")).running === true, "running again");
    await until(async () => !(await page.getByTestId("monitor-paused").isVisible()), "the pause note gone once the cycle runs");
  });

  test("the world view zooms, pans, resets, keeps a trail per floor and follows the robot's floor", async () => {
    const canvas = page.getByTestId("world-canvas");
    const data = async () => canvas.evaluate((c) => ({ ...c.dataset, width: c.width, cssWidth: c.clientWidth, dpr: window.devicePixelRatio }));
    await until(async () => Number((await data()).draws) >= 3, "drawn");
    let d = await data();
    assert.equal(await page.getByTestId("world-floor").inputValue(), "auto", "the robot's floor by default");
    assert.equal(await page.getByTestId("world-follow").isChecked(), true, "following by default");
    assert.equal(Number(d.zoom), 1);
    // Labels at their size on the page: the canvas is not scaled down, the car's label is ≥ 12 px.
    assert.ok(Math.abs(d.cssWidth * d.dpr - d.width) <= 2, `drawn at the page's pixel size: ${d.width} for ${d.cssWidth} css px`);
    const labels = JSON.parse(d.labels);
    const car = labels.find((l) => l.text.startsWith("car 1"));
    assert.ok(car && car.px >= 12, `the car's label: ${JSON.stringify(labels)}`);
    // Wheel: zoom in, centred on the robot while following.
    await canvas.scrollIntoViewIfNeeded();
    const box = await canvas.boundingBox();
    await page.mouse.move(box.x + box.width / 4, box.y + box.height / 4);
    await page.mouse.wheel(0, -600);
    await until(async () => Number((await data()).zoom) > 1.5, "zoomed in");
    // Centred on the robot as the same draw shows it. (Against a pose queried through the CLI
    // the robot, driving in circles, had moved on: 2 m apart once on a loaded machine.)
    d = await data();
    assert.ok(d.robotX !== "", `the robot is drawn: ${JSON.stringify(d)}`);
    assert.ok(Math.hypot(Number(d.centerX) - Number(d.robotX), Number(d.centerY) - Number(d.robotY)) < 0.01, `centred on the robot: ${d.centerX}, ${d.centerY} vs ${d.robotX}, ${d.robotY}`);
    // And the robot drawn is the robot: its truth pose moves on, so within a generous bound of
    // one queried while it is drawn, in some draw.
    await until(async () => {
      const pose = await cli(tb.linkPort, "query", "truth.pose");
      const now = await data();
      return Math.hypot(Number(now.robotX) - pose.value.x, Number(now.robotY) - pose.value.y) < 1.0;
    }, "the robot drawn where it is");
    // Drag: pan, which stops following.
    const before = await data();
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
    await page.mouse.down();
    await page.mouse.move(box.x + box.width / 2 + 120, box.y + box.height / 2 + 40, { steps: 4 });
    await page.mouse.up();
    await until(async () => (await page.getByTestId("world-follow").isChecked()) === false, "panning stops following");
    d = await data();
    assert.ok(Number(d.centerX) < Number(before.centerX) - 0.2, `dragging right moves the view left: ${before.centerX} → ${d.centerX}`);
    // Reset.
    await page.getByTestId("world-reset").click();
    await until(async () => Number((await data()).zoom) === 1 && (await page.getByTestId("world-follow").isChecked()), "reset: fitted and following");
    // Another floor: the view follows it, and each floor keeps its own trail.
    await until(async () => (JSON.parse((await data()).trail)["0"] ?? 0) >= 5, "a trail on floor 0");
    await cliDo(tb.linkPort, "param", "set", "circle", "floor", "1");
    try {
      await until(async () => (await data()).floor === "1" && (await text(page.getByTestId("world-info"))).includes("floor 1; showing floor 1"), "the view follows the robot to floor 1");
      await until(async () => (JSON.parse((await data()).trail)["1"] ?? 0) >= 3, "a trail on floor 1");
      const trails = JSON.parse((await data()).trail);
      assert.ok(trails["0"] >= 5, `floor 0 keeps its trail: ${JSON.stringify(trails)}`);
      await page.getByTestId("world-floor").selectOption("0");
      await until(async () => (await data()).floor === "0", "floor 0 shown when chosen");
      await page.getByTestId("world-floor").selectOption("auto");
    } finally {
      await cliDo(tb.linkPort, "param", "set", "circle", "floor", "0");
    }
  });

  test("usable at 390 px wide, and dark when the system is", async () => {
    const narrow = await browser.context.newPage();
    try {
      await narrow.setViewportSize({ width: 390, height: 844 });
      await narrow.goto(tb.url);
      await narrow.getByTestId("switch-wander").waitFor({ timeout: 60_000 });
      const panel = narrow.getByTestId("skill-wheels");
      await panel.locator("summary").click();
      await narrow.getByTestId("show-output-wheels").check();
      await narrow.getByTestId("show-input-wheels").check();
      await until(async () => (await narrow.getByTestId("output-table-wheels").count()) === 1, "the wheels' outputs shown");
      await until(async () => (await narrow.locator("[data-testid=graph] svg").count()) === 1, "the graph drawn");
      const width = await narrow.evaluate(() => document.scrollingElement.scrollWidth);
      assert.ok(width <= 390, `no horizontal page scroll at 390 px: the page is ${width} px wide`);
      await narrow.screenshot({ path: screenshotPath("narrow-390"), fullPage: true });

      await narrow.emulateMedia({ colorScheme: "dark" });
      const luminance = (rgb) => {
        const [r, g, b] = rgb.match(/\d+/g).map(Number);
        return (0.2126 * r + 0.7152 * g + 0.0722 * b) / 255;
      };
      const bg = await narrow.evaluate(() => getComputedStyle(document.body).backgroundColor);
      assert.ok(luminance(bg) < 0.2, `a dark background: ${bg}`);
      const panelBg = await narrow.evaluate(() => getComputedStyle(document.querySelector(".panel")).backgroundColor);
      assert.ok(luminance(panelBg) < 0.2, `dark panels: ${panelBg}`);
      const fg = await narrow.evaluate(() => getComputedStyle(document.body).color);
      assert.ok(luminance(fg) > 0.6, `light text: ${fg}`);
      // The world view draws in the dark scheme too (its next frame).
      const canvas = narrow.getByTestId("world-canvas");
      const draws = Number(await canvas.getAttribute("data-draws"));
      await until(async () => Number(await canvas.getAttribute("data-draws")) > draws + 1, "redrawn");
      const corner = await canvas.evaluate((c) => [...c.getContext("2d").getImageData(1, 1, 1, 1).data]);
      assert.ok(luminance(`rgb(${corner[0]}, ${corner[1]}, ${corner[2]})`) < 0.2, `the world's background is dark: ${corner}`);
      await narrow.screenshot({ path: screenshotPath("narrow-390-dark"), fullPage: true });
    } finally {
      await narrow.close();
    }
  });
});

describe("a skill inactive from the start", () => {
  let tb;
  let browser;
  let page;
  let dir;

  before(async () => {
    // The toy robot with wander inactive from its first cycle (`active: false`).
    dir = mkdtempSync(path.join(os.tmpdir(), "situate-gui-inactive-"));
    const robot = path.join(dir, "toybot.yaml");
    const yaml = readFileSync(path.join(repo, "examples", "toybot.yaml"), "utf8");
    const edited = yaml.replace("params: {speed: 0.2, seed: 7}", "params: {speed: 0.2, seed: 7}\n    active: false");
    assert.notEqual(edited, yaml, "wander's entry in examples/toybot.yaml");
    writeFileSync(robot, edited);
    ({ tb, browser, page } = await openGui(["--robot", robot]));
  });

  after(async () => {
    await closeGui({ tb, browser });
    if (dir) rmSync(dir, { recursive: true, force: true });
  });

  afterEach(async (t) => {
    if (page) await page.screenshot({ path: screenshotPath(t.name.replace(/[^a-z0-9]+/gi, "-")), fullPage: true }).catch(() => undefined);
  });

  test("a skill never switched reads 'inactive since cycle 0', as docs/gui.md says, live and paused", async () => {
    const skills = await cli(tb.linkPort, "skills");
    assert.equal(skills.find((s) => s.name === "wander")?.active, false, "wander inactive (over the link)");
    // The robot ran cycles before the GUI served it: still, the GUI saw it from its first cycle.
    const since = page.getByTestId("since-wander");
    await until(async () => (await text(since)) !== "", "wander's since");
    assert.equal(await text(since), "since cycle 0");
    const panel = page.getByTestId("skill-wander");
    if (!(await panel.evaluate((d) => d.open))) await panel.locator("summary").click();
    await page.getByTestId("show-output-wander").check();
    const cell = page.getByTestId("output-table-wander").locator("td.value").first();
    await until(async () => (await cell.getAttribute("data-inactive")) !== null, "wander's output shown as inactive");
    assert.match(await text(cell), /^inactive since cycle 0 /);
    // Paused on the timeline: the same.
    await page.getByTestId("tl-live").click();
    await until(async () => (await page.getByTestId("timeline").getAttribute("data-shown")) !== null, "a past cycle shown");
    assert.equal(await text(since), "since cycle 0");
    await page.getByTestId("tl-live").click();
    await until(async () => (await page.getByTestId("timeline").getAttribute("data-mode")) === "live", "live again");
  });
});
