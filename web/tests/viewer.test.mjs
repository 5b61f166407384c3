// A recording opened without re-simulating it (`situate replay FILE --view --gui`): the robot file
// it was made with is gone, and the page still shows its skills, their outputs at any cycle, and
// plots of the whole recording, built from the wiring the recording holds.

import assert from "node:assert/strict";
import { copyFileSync, mkdtempSync, rmSync } from "node:fs";
import os from "node:os";
import path from "node:path";
import { after, before, describe, test } from "node:test";
import { openPage, repo, runSituate, screenshotPath, startBrowser, startReplayGui, stopBrowser, stopProgram, until } from "./harness.mjs";

const CYCLES = 300;
const text = async (locator) => (await locator.textContent()) ?? "";

describe("a recording viewed without its robot", () => {
  let dir;
  let replay;
  let browser;
  let page;

  before(async () => {
    dir = mkdtempSync(path.join(os.tmpdir(), "situate-viewer-gui-"));
    const robot = path.join(dir, "robot.yaml");
    copyFileSync(path.join(repo, "examples", "toybot.yaml"), robot);
    const file = path.join(dir, "toy.mcap");
    await runSituate("run", robot, "--clock", "simulated", "--cycles", String(CYCLES), "--no-link", "--no-gui", "--record", file);
    rmSync(robot);
    replay = await startReplayGui(file, ["--view"]);
    browser = await startBrowser();
    page = await openPage(browser, replay.url, { panels: false });
  });

  after(async () => {
    if (page) await page.screenshot({ path: screenshotPath("viewer-gui"), fullPage: true }).catch(() => undefined);
    await stopBrowser(browser).catch(() => undefined);
    await stopProgram(replay);
    if (dir) rmSync(dir, { recursive: true, force: true });
  });

  const shown = async () => Number(await page.getByTestId("timeline").getAttribute("data-shown"));

  test("the page says the file is viewed, nothing re-simulated, and holds every cycle", async () => {
    assert.match(replay.out, new RegExp(`viewed ${CYCLES} cycles .*nothing re-simulated`));
    assert.match(replay.out, /identical: every cycle matches the recording/);
    await until(async () => !(await page.getByTestId("replay-banner").isHidden()), "the banner");
    assert.match(await text(page.getByTestId("replay-banner")), /Replay of .*toy\.mcap: viewed from the file alone, nothing re-simulated/);
    await until(async () => new RegExp(`holds cycles 1–${CYCLES}`).test(await text(page.getByTestId("tl-span"))), "every cycle on the timeline");
  });

  test("every recorded skill is there with its parameters, and its outputs at the cycle shown", async () => {
    for (const name of ["sonar", "wheels", "runaway", "wander"]) {
      await until(async () => (await page.getByTestId(`skill-${name}`).count()) === 1, `the skill ${name}`);
    }
    // wander's parameters, as the robot file declared them, read from the recording.
    assert.match(await text(page.getByTestId("skill-wander")), /speed/);
    // The page opens at the first cycle; a step forward shows the second.
    await until(async () => (await shown()) === 1, "cycle 1 shown");
    await page.getByTestId("tl-forward").click();
    await until(async () => (await shown()) === 2, "cycle 2 shown");
    const panel = page.getByTestId("skill-wheels");
    if (!(await panel.evaluate((d) => d.open))) await panel.locator("summary").click();
    await page.getByTestId("show-output-wheels").check();
    await until(async () => /odom/.test(await text(page.getByTestId("outputs-wheels"))) && /-?\d+\.\d+/.test(await text(page.getByTestId("outputs-wheels"))), "wheels' odometry at the cycle shown");
  });

  test("a plot draws the whole recording", async () => {
    await page.getByTestId("plot-signal").fill("odom.x");
    await page.getByTestId("plot-add").click();
    const canvas = page.getByTestId("plot-canvas").first();
    await until(async () => (await canvas.getAttribute("data-state")) === "recording" && Number(await canvas.getAttribute("data-series")) === CYCLES, "the recording's cycles in the plot");
    const drawn = JSON.parse((await canvas.getAttribute("data-drawn")) ?? "{}");
    assert.ok(drawn["odom.x"] >= CYCLES - 2, `odom.x drawn over the recording: ${JSON.stringify(drawn)}`);
  });
});
