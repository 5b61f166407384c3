// The timeline in a real browser against the testbed: pause, step back one cycle, seek with the
// slider, play, jump to an event's mark, and go live again. The robot's own effects (a skill
// deactivated) are made and checked over the link with the `situate` CLI.

import assert from "node:assert/strict";
import { after, afterEach, before, describe, test } from "node:test";
import { cli, closeGui, openGui, screenshotPath, startTestbed, stopTestbed, until } from "./harness.mjs";

const text = async (locator) => (await locator.textContent()) ?? "";

describe("the timeline", () => {
  let tb;
  let browser;
  let page;

  before(async () => {
    const ready = async (page) => {
      // The circle's outputs (its pose, which changes every cycle) in its panel.
      await page.getByTestId("skill-circle").locator("summary").click();
      await page.getByTestId("show-output-circle").check();
      await page.getByTestId("output-table-circle").waitFor({ timeout: 60_000 });
      // Some history to look back on.
      await until(async () => {
        const m = /holds cycles (\d+)–(\d+)/.exec(await text(page.getByTestId("tl-span")));
        return m && Number(m[2]) - Number(m[1]) >= 60;
      }, "sixty cycles on the timeline");
    };
    ({ tb, browser, page } = await openGui([], { ready }));
  });

  after(() => closeGui({ tb, browser }));

  afterEach(async (t) => {
    if (page) await page.screenshot({ path: screenshotPath(`timeline-${t.name.replace(/[^a-z0-9]+/gi, "-")}`), fullPage: true }).catch(() => undefined);
  });

  const bar = () => page.getByTestId("timeline");
  const mode = async () => bar().getAttribute("data-mode");
  const shown = async () => {
    const s = await bar().getAttribute("data-shown");
    return s === null ? null : Number(s);
  };
  /** The circle's `pose` output as the skills panel shows it. */
  const pose = async () => {
    const cell = page.getByTestId("output-table-circle").locator('tr[data-signal="truth.pose"] td.value');
    return JSON.parse((await cell.getAttribute("data-value")) ?? "null");
  };
  const samples = async () => Number(await page.evaluate(() => document.body.dataset.samples ?? "0"));
  const span = async () => {
    const m = /holds cycles (\d+)–(\d+)/.exec(await text(page.getByTestId("tl-span")));
    assert.ok(m, "the span is shown");
    return { first: Number(m[1]), last: Number(m[2]) };
  };
  const pause = async () => {
    if ((await mode()) !== "paused") await page.getByTestId("tl-live").click();
    await until(async () => (await mode()) === "paused" && (await shown()) !== null, "paused at a cycle");
  };
  const goLive = async () => {
    if ((await mode()) !== "live") await page.getByTestId("tl-live").click();
    await until(async () => (await mode()) === "live", "live again");
  };

  test("paused, the panels hold a past cycle; one step back shows the cycle before and its output", async () => {
    await pause();
    const at = await shown();
    await until(async () => (await text(page.getByTestId("tl-cycle"))).startsWith(`cycle ${at}`), "the cycle shown in the bar");
    assert.match(await text(page.getByTestId("skills-past")), new RegExp(`at cycle ${at} \\(paused`));
    assert.match(await text(page.getByTestId("world-past")), new RegExp(`at cycle ${at} \\(paused`));
    const then = await pose();
    assert.ok(then && typeof then.x === "number", `a pose at cycle ${at}: ${JSON.stringify(then)}`);
    assert.ok(Math.abs(Math.hypot(then.x, then.y) - 2) < 1e-6, `on the circle of radius 2: ${JSON.stringify(then)}`);
    // Live samples keep coming; the paused panel does not follow them.
    const seen = await samples();
    await until(async () => (await samples()) >= seen + 3, "three more live samples");
    assert.deepEqual(await pose(), then, "the paused panel followed the live robot");
    assert.equal(await shown(), at);

    // One cycle back at a time until the pose differs (the circle is a device on a thread of its
    // own: on a loaded machine a cycle may get no new reading, and the pose stays).
    let back = at;
    let before = then;
    while (JSON.stringify(before) === JSON.stringify(then)) {
      assert.ok(at - back < 40, `the pose stayed the same over 40 cycles before ${at}`);
      await page.getByTestId("tl-back").click();
      back -= 1;
      await until(async () => (await shown()) === back, `cycle ${back} shown`);
      await until(async () => (await text(page.getByTestId("tl-cycle"))).startsWith(`cycle ${back}`), "its number in the bar");
      assert.match(await text(page.getByTestId("skills-past")), new RegExp(`at cycle ${back} \\(`));
      before = await pose();
    }
    assert.ok(Math.abs(Math.hypot(before.x, before.y) - 2) < 1e-6, `on the circle: ${JSON.stringify(before)}`);
    // One forward: the cycle after shows the later pose again.
    await page.getByTestId("tl-forward").click();
    await until(async () => (await shown()) === back + 1, `cycle ${back + 1} shown`);
    assert.deepEqual(await pose(), then, "the cycle after the change shows the later pose");
  });

  test("dragging the slider seeks to the cycle under the pointer", async () => {
    await pause();
    const { first, last } = await span();
    assert.ok(last - first > 40, `enough history to seek in: ${first}–${last}`);
    const box = await page.getByTestId("tl-slider").boundingBox();
    assert.ok(box, "the slider is on the page");
    const y = box.y + box.height / 2;
    await page.mouse.move(box.x + box.width * 0.8, y);
    await page.mouse.down();
    await page.mouse.move(box.x + box.width * 0.5, y, { steps: 5 });
    await page.mouse.move(box.x + box.width * 0.25, y, { steps: 5 });
    await page.mouse.up();
    const value = Number(await page.getByTestId("tl-slider").inputValue());
    // The history goes on growing while the page is paused (the robot runs): on a slow machine
    // the slider's range at the release is wider than the span read before the drag, so the
    // quarter of the slider is measured against the range it has now.
    const range = await page.getByTestId("tl-slider").evaluate((el) => ({ min: Number(el.min), max: Number(el.max) }));
    assert.ok(range.max >= last, `the slider spans the history: ${JSON.stringify(range)} vs ${first}–${last}`);
    assert.ok(
      value < range.min + (range.max - range.min) * 0.5,
      `the slider moved back (${value} in ${range.min}–${range.max}; ${first}–${last} before the drag)`,
    );
    await until(async () => (await shown()) === value, `cycle ${value} shown`);
    assert.equal(await text(page.getByTestId("tl-cycle")), `cycle ${value}`);
    const p = await pose();
    assert.ok(p && Math.abs(Math.hypot(p.x, p.y) - 2) < 1e-6, `the pose then: ${JSON.stringify(p)}`);
  });

  test("playing at 4× moves through the cycles", async () => {
    await pause();
    const { first } = await span();
    const box = await page.getByTestId("tl-slider").boundingBox();
    await page.mouse.click(box.x + 2, box.y + box.height / 2);
    await until(async () => (await shown()) !== null && (await shown()) < first + 20, "near the start of the window");
    const from = await shown();
    await page.getByTestId("tl-speed").selectOption("4");
    await page.getByTestId("tl-play").click();
    await until(async () => (await shown()) >= from + 20, "twenty cycles played");
    await page.getByTestId("tl-play").click();
    assert.equal(await mode(), "paused", "playing the past is not live");
  });

  test("an event's mark jumps to its cycle: the skill as it was then, and the cycle before", async () => {
    await goLive();
    const before = Object.fromEntries((await cli(tb.linkPort, "skills")).map((s) => [s.name, s]));
    assert.equal(before.wander.active, true, "wander starts active");
    await cli(tb.linkPort, "deactivate", "wander");
    await until(async () => Object.fromEntries((await cli(tb.linkPort, "skills")).map((s) => [s.name, s])).wander.active === false, "wander inactive over the link");
    const mark = page.locator('[data-testid="tl-mark"][data-kind="activation"][data-text^="deactivated wander"]');
    await until(async () => (await mark.count()) === 1, "the deactivation's mark on the bar");
    // Go on a little: the mark is in the past when clicked.
    const seen = await samples();
    await until(async () => (await samples()) >= seen + 3, "three more live samples");
    const cycle = Number(await mark.getAttribute("data-cycle"));
    await mark.click();
    await until(async () => (await mode()) === "paused" && (await shown()) === cycle, `paused at the mark's cycle ${cycle}`);
    await until(async () => (await text(page.getByTestId("state-wander"))) === "inactive", "wander inactive at its deactivation's cycle");
    assert.match(await text(page.getByTestId("since-wander")), new RegExp(`since cycle ${cycle}\\b`));
    // The graph follows the timeline too.
    const graphWander = page.locator('[data-testid="graph"] g.node.skill[data-node="wander"]');
    await until(async () => (await graphWander.getAttribute("data-active")) === "false", "wander inactive in the graph at the mark");
    await page.getByTestId("tl-back").click();
    await until(async () => (await shown()) === cycle - 1, "the cycle before");
    await until(async () => (await text(page.getByTestId("state-wander"))) === "active", "wander still active the cycle before");
    await until(async () => (await graphWander.getAttribute("data-active")) === "true", "wander active in the graph the cycle before");
    // The robot itself was not touched by looking back.
    assert.equal(Object.fromEntries((await cli(tb.linkPort, "skills")).map((s) => [s.name, s])).wander.active, false);
    // The panel shows wander active then, but its button acts on the robot now, where wander is
    // inactive: it offers to activate it, and says "now".
    if (!(await page.getByTestId("skill-wander").evaluate((d) => d.open))) await page.getByTestId("skill-wander").locator("summary").click();
    const button = page.getByTestId("activate-wander");
    await until(async () => (await text(button)) === "Activate now", "the button offers what the robot now allows");
    assert.match((await button.getAttribute("title")) ?? "", /acts on the robot now \(inactive now\)/);
    await button.click();
    await until(async () => Object.fromEntries((await cli(tb.linkPort, "skills")).map((s) => [s.name, s])).wander.active === true, "wander activated on the robot by the paused page");
    await until(async () => (await text(button)) === "Deactivate now", "the button follows the robot now");
    assert.equal(await shown(), cycle - 1, "the page stayed on the cycle shown");
  });

  test("the mission lane: the sequencer's phases as spans, the phase shown with the cycle, a click on one shows its start", async () => {
    await goLive();
    const phase = async (text) => {
      await cli(tb.linkPort, "phase", text, "--client", "seq");
      await until(async () => (await page.locator(`[data-testid="tl-phase-seg"][data-text="seq: ${text}"]`).count()) === 1, `"${text}" on the lane`);
    };
    await phase("leaving the lab");
    const seen = await samples();
    await until(async () => (await samples()) >= seen + 5, "five more live samples");
    await phase("riding the car");
    await until(async () => (await text(page.getByTestId("tl-phase"))) === "mission: seq: riding the car", "the live phase on the bar");
    const segs = page.getByTestId("tl-phase-seg");
    const first = Number(await segs.nth(0).getAttribute("data-cycle"));
    const second = Number(await segs.nth(1).getAttribute("data-cycle"));
    assert.ok(second > first, `the phases in order: ${first} < ${second}`);
    // Not marks: the lane holds them.
    assert.equal(await page.locator('[data-testid="tl-mark"][data-kind="phase"]').count(), 0);
    // The first phase's span ends where the second begins: both measured in one go (the live
    // lane is laid out again as samples come; two separate measures once straddled a redraw).
    const [a, b] = await page.evaluate(() =>
      [...document.querySelectorAll('[data-testid="tl-phase-seg"]')].slice(0, 2).map((e) => {
        const r = e.getBoundingClientRect();
        return { x: r.x, width: r.width };
      }),
    );
    assert.ok(a && b && Math.abs(a.x + a.width - b.x) < 3, `adjacent spans: ${JSON.stringify([a, b])}`);
    await segs.nth(0).click();
    await until(async () => (await mode()) === "paused" && (await shown()) === first, `paused at the first phase's cycle ${first}`);
    assert.equal(await text(page.getByTestId("tl-phase")), "mission: seq: leaving the lab");
    await page.getByTestId("tl-back").click();
    await until(async () => (await shown()) === first - 1, "the cycle before the first phase");
    assert.equal(await text(page.getByTestId("tl-phase")), "", "no phase before the first");
    // The event log has them too, as the link sends them.
    assert.ok((await page.getByTestId("event-log").locator('[data-kind="phase"]').count()) >= 2);
  });

  test("keys: P pauses and goes live, the arrows step one cycle", async () => {
    await goLive();
    await page.locator("body").click({ position: { x: 5, y: 5 } });
    await page.keyboard.press("p");
    await until(async () => (await mode()) === "paused" && (await shown()) !== null, "paused by the key P");
    const at = await shown();
    await page.keyboard.press("ArrowLeft");
    await until(async () => (await shown()) === at - 1, "one cycle back by ←");
    await page.keyboard.press("ArrowRight");
    await until(async () => (await shown()) === at, "one cycle forward by →");
    // In a form field the keys are the field's.
    await page.getByTestId("step-count").focus();
    await page.keyboard.press("p");
    await page.keyboard.press("ArrowLeft");
    // (The handlers change the mode and the slider at once, before any reply.)
    assert.equal(await mode(), "paused", "P typed in a field went live");
    assert.equal(await page.getByTestId("tl-slider").inputValue(), String(at), "← typed in a field moved the timeline");
    await page.locator("body").click({ position: { x: 5, y: 5 } });
    await page.keyboard.press("p");
    await until(async () => (await mode()) === "live", "live again by the key P");
  });

  test("going live shows the live robot again", async () => {
    await pause();
    const paused = await pose();
    await goLive();
    await until(async () => (await text(page.getByTestId("skills-past"))) === "", "the skills panel no longer says it shows the past");
    assert.equal(await text(page.getByTestId("world-past")), "");
    assert.equal(await bar().getAttribute("data-shown"), null);
    await until(async () => JSON.stringify(await pose()) !== JSON.stringify(paused), "the pose moves on");
    const a = Number(await text(page.getByTestId("stat-cycle")));
    await until(async () => Number(/cycle (\d+)/.exec(await text(page.getByTestId("tl-cycle")))?.[1] ?? 0) > a, "the bar's cycle follows the live robot");
    await until(async () => Object.fromEntries((await cli(tb.linkPort, "skills")).map((s) => [s.name, s])).wander.active === true, "wander active over the link");
    await until(async () => (await text(page.getByTestId("state-wander"))) === "active", "the live state in the panel");
  });
});

describe("a paused page when the robot restarts", () => {
  let tb;
  let browser;
  let page;

  before(async () => {
    ({ tb, browser, page } = await openGui());
  });

  after(() => closeGui({ tb, browser }));

  test("goes live on the new run: the old run's past is not shown as the new one's", async () => {
    const bar = page.getByTestId("timeline");
    await until(async () => /holds cycles \d+–\d+/.test(await text(page.getByTestId("tl-span"))), "the timeline's span");
    await page.getByTestId("tl-live").click();
    await until(async () => (await bar.getAttribute("data-mode")) === "paused" && (await bar.getAttribute("data-shown")) !== null, "paused");
    const oldRun = await page.evaluate(() => document.body.dataset.run);
    await stopTestbed(tb);
    tb = await startTestbed([], { guiPort: tb.guiPort });
    await until(async () => {
      const run = await page.evaluate(() => document.body.dataset.run);
      return run && run !== oldRun;
    }, "the page sees the new run");
    await until(async () => (await bar.getAttribute("data-mode")) === "live", "live on the new run");
    assert.equal(await bar.getAttribute("data-shown"), null);
    await until(async () => (await text(page.getByTestId("skills-past"))) === "", "the skills panel shows the live robot");
    assert.equal(await text(page.getByTestId("world-past")), "");
  });
});

describe("a GUI without a timeline", () => {
  let tb;
  let browser;
  let page;

  before(async () => {
    ({ tb, browser, page } = await openGui(["--no-history"], { panels: false }));
  });

  after(() => closeGui({ tb, browser }));

  test("says there is none, and offers no pause", async () => {
    await until(async () => /keeps no history/.test(await text(page.getByTestId("tl-note"))), "the bar says why there is no timeline");
    assert.equal(await page.getByTestId("tl-live").isVisible(), false, "no pause button");
    assert.equal(await page.getByTestId("tl-slider").isVisible(), false, "no slider");
    assert.equal(await page.getByTestId("timeline").getAttribute("data-mode"), "live");
  });
});
