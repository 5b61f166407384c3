// `situate demo` with the GUI keeps serving after the mission, with the outcome on the page, until
// Ctrl-C; `--exit-when-done` and `--headless` end with the mission. A stand-in sequencer (a Python
// script that gives up at once) makes the mission end quickly; the robot is the demo's own.

import assert from "node:assert/strict";
import { mkdtempSync, rmSync, writeFileSync } from "node:fs";
import os from "node:os";
import path from "node:path";
import { after, before, describe, test } from "node:test";
import { freePort, screenshotPath, situateBin, startBrowser, startProgram, stopBrowser, until } from "./harness.mjs";

const python = process.env.SITUATE_PYTHON || "python3";

/** Starts `situate demo ARGS` with the stand-in sequencer; collects its output. */
function startDemo(sequencer, ...args) {
  return startProgram(situateBin, ["demo", "--sequencer", sequencer, "--python", python, ...args]);
}

/** Waits for the demo to exit by itself (a generous bound turns a hang into a failure). */
async function exitsByItself(demo, what) {
  await until(() => demo.exit !== null, `${what} exits by itself\nstdout:\n${demo.out}\nstderr:\n${demo.err}`, 180_000);
  return demo.exit;
}

describe("the demo's end", () => {
  let dir;
  let sequencer;
  let browser;
  const started = [];

  before(async () => {
    dir = mkdtempSync(path.join(os.tmpdir(), "situate-demo-test-"));
    sequencer = path.join(dir, "give_up.py");
    writeFileSync(
      sequencer,
      [
        "# A stand-in for demo/deliver.py: announces a phase, then gives up (the demo's narrative lines).",
        "print('[    0.0 s] phase 1: standing still', flush=True)",
        "print('[    0.0 s] mission failed: the test sequencer gives up', flush=True)",
        "raise SystemExit(1)",
        "",
      ].join("\n"),
    );
    browser = await startBrowser();
  });

  after(async () => {
    for (const d of started) if (d.exit === null) d.child.kill("SIGKILL");
    await stopBrowser(browser).catch(() => undefined);
    rmSync(dir, { recursive: true, force: true });
  });

  test("with the GUI, the page shows the outcome after the mission, until Ctrl-C", async () => {
    const port = await freePort();
    const demo = startDemo(sequencer, "--gui", `127.0.0.1:${port}`, "--speed", "4");
    started.push(demo);
    await until(() => demo.err.includes("the GUI stays on") || demo.exit !== null, `the mission over\nstderr:\n${demo.err}`, 180_000);
    assert.equal(demo.exit, null, `the demo is still serving after the mission\nstdout:\n${demo.out}\nstderr:\n${demo.err}`);
    assert.match(demo.out, /demo: NOT delivered/);
    const page = await browser.context.newPage();
    try {
      await page.goto(`http://127.0.0.1:${port}/`);
      const outcome = page.getByTestId("outcome");
      await until(async () => await outcome.isVisible(), "the outcome on the page");
      const text = (await outcome.textContent()) ?? "";
      assert.match(text, /failed/);
      assert.match(text, /the test sequencer gives up/, "the reason, as the sequencer said it");
      assert.match(text, /phase 1/);
      assert.equal(await outcome.getAttribute("data-ok"), "false");
      // The robot is still there to inspect: live telemetry, the cycle stopped where the mission ended.
      await until(async () => (await page.getByTestId("stat-state").textContent()) === "stopped", "the robot's state, live");
      assert.equal(demo.exit, null, "still serving while the page is open");
      await page.screenshot({ path: screenshotPath("demo-outcome"), fullPage: true });
    } finally {
      await page.close();
    }
    demo.child.kill("SIGINT");
    const exit = await exitsByItself(demo, "the demo after Ctrl-C");
    assert.equal(exit.code, 1, `the mission's status (not delivered), not the signal's: ${JSON.stringify(exit)}\n${demo.err}`);
  });

  test("--exit-when-done ends with the mission, GUI or not", async () => {
    const port = await freePort();
    const demo = startDemo(sequencer, "--gui", `127.0.0.1:${port}`, "--exit-when-done");
    started.push(demo);
    const exit = await exitsByItself(demo, "the demo with --exit-when-done");
    assert.equal(exit.code, 1, demo.out + demo.err);
    assert.match(demo.out, /demo: NOT delivered/);
    assert.ok(!demo.err.includes("the GUI stays on"), demo.err);
  });

  test("--headless ends with the mission", async () => {
    const demo = startDemo(sequencer, "--headless", "--json");
    started.push(demo);
    const exit = await exitsByItself(demo, "the headless demo");
    assert.equal(exit.code, 1, demo.out + demo.err);
    const outcome = JSON.parse(demo.out.split("\n").filter((l) => l.startsWith("{")).pop());
    assert.equal(outcome.delivered, false);
    assert.equal(outcome.sequencer_exit, 1);
  });
});
