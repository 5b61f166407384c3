// Seeking in a recording in the GUI, and plotting a whole recording: records the delivery
// (`situate demo --headless --record`) and a long toy run (`situate run examples/toybot.yaml`,
// simulated clock, `--cycles`, default 100,000), opens each with `situate replay FILE --gui`, clicks
// the timeline's slider at spread positions, timing each click until the page shows that cycle
// (requestAnimationFrame polling), then adds a plot and times it until it holds the whole
// recording (`history_series`). Issue 38's targets, on 100,000 cycles: a seek under 100 ms, a
// whole-recording plot under 300 ms. Nothing asserts on timing: it is printed.
//   node bench/gui/seek.mjs [--seeks 20] [--seed 1] [--cycles 100000] [--python PATH]

import { spawn, execFile } from "node:child_process";
import { mkdtempSync, rmSync } from "node:fs";
import os from "node:os";
import path from "node:path";
import { freePort, repo, situateBin, startBrowser, stopBrowser, until } from "../../web/tests/harness.mjs";

const opt = (name, dflt) => {
  const i = process.argv.indexOf(`--${name}`);
  return i >= 0 && process.argv[i + 1] !== undefined ? process.argv[i + 1] : dflt;
};
const seeks = Number(opt("seeks", "20"));
const seed = opt("seed", "1");
const longCycles = Number(opt("cycles", "100000"));
const python = opt("python", path.join(repo, ".venv", "bin", "python"));

const situate = (args) =>
  new Promise((resolve, reject) =>
    execFile(situateBin, args, { cwd: repo, timeout: 900_000, maxBuffer: 1 << 26 }, (err, stdout, stderr) => (err ? reject(new Error(`${err.message}\n${stderr}`)) : resolve(stdout))),
  );

/** Seeks and a whole-recording plot in the replay GUI of `file` (`cycles` long), printed as `name`. */
async function measure(name, file, cycles, signal) {
  const port = await freePort();
  let err = "";
  const child = spawn(situateBin, ["replay", file, "--gui", `127.0.0.1:${port}`], { cwd: repo, stdio: ["ignore", "ignore", "pipe"] });
  child.stderr.on("data", (d) => (err += d));
  let browser;
  try {
    await until(async () => err.includes("GUI on http") || child.exitCode !== null, "the replay's GUI", 900_000);
    browser = await startBrowser();
    const page = await browser.context.newPage();
    await page.goto(`http://127.0.0.1:${port}/`);
    await page.getByTestId("status").filter({ hasText: "connected" }).waitFor({ timeout: 60_000 });
    await until(async () => new RegExp(`holds cycles 1–${cycles}\\b`).test((await page.getByTestId("tl-span").textContent()) ?? ""), "every cycle on the timeline", 300_000);
    const bar = page.getByTestId("timeline");
    // A replay opens paused at its first cycle.
    await until(async () => (await bar.getAttribute("data-mode")) === "paused", "paused");
    const box = await page.getByTestId("tl-slider").boundingBox();
    const times = [];
    for (let k = 0; k < seeks; k++) {
      // Spread over the whole recording, jumping back and forth.
      const f = ((k * 0.618034) % 1) * 0.96 + 0.02;
      const t0 = performance.now();
      await page.mouse.click(box.x + box.width * f, box.y + box.height / 2);
      const v = await page.getByTestId("tl-slider").inputValue();
      await page.waitForFunction((v) => document.querySelector('[data-testid="timeline"]')?.getAttribute("data-shown") === v, v, { polling: "raf", timeout: 60_000 });
      times.push(performance.now() - t0);
    }
    times.sort((a, b) => a - b);
    const q = (p) => times[Math.min(times.length - 1, Math.floor(p * times.length))].toFixed(0);
    console.log(`${name}: ${seeks} seeks: min ${q(0)} ms, median ${q(0.5)} ms, max ${times[times.length - 1].toFixed(0)} ms (target: < 100 ms on 100,000 cycles)`);
    const plots = [];
    for (let k = 0; k < 3; k++) {
      await page.getByTestId("plot-signal").fill(signal);
      const t0 = performance.now();
      await page.getByTestId("plot-add").click();
      const canvas = page.getByTestId("plot-canvas").nth(k);
      await canvas.waitFor({ timeout: 60_000 });
      await page.waitForFunction((k) => {
        const c = document.querySelectorAll('[data-testid="plot-canvas"]')[k];
        return c?.getAttribute("data-state") === "recording" && Number(c.getAttribute("data-series")) > 0 && Number(c.getAttribute("data-draws")) > 0;
      }, k, { polling: "raf", timeout: 60_000 });
      plots.push(performance.now() - t0);
    }
    const points = await page.getByTestId("plot-canvas").first().getAttribute("data-series");
    console.log(`${name}: a plot of ${signal} over the whole recording (${points} points of ${cycles} cycles): ${plots.map((t) => t.toFixed(0)).join(", ")} ms (target: < 300 ms on 100,000 cycles)`);
  } finally {
    await stopBrowser(browser).catch(() => undefined);
    child.kill("SIGINT");
  }
}

const dir = mkdtempSync(path.join(os.tmpdir(), "situate-seek-"));
try {
  const delivery = path.join(dir, "delivery.mcap");
  const outcome = JSON.parse((await situate(["demo", "--headless", "--json", "--seed", seed, "--python", python, "--record", delivery])).trim().split("\n").pop());
  console.log(`delivery: recorded ${outcome.cycles} cycles (${(outcome.mission_time_s / 60).toFixed(1)} simulated minutes), ${(outcome.recording.bytes / 1e6).toFixed(1)} MB`);
  await measure("delivery", delivery, outcome.cycles, "odom.x");
  const long = path.join(dir, "toy.mcap");
  await situate(["run", "examples/toybot.yaml", "--clock", "simulated", "--cycles", String(longCycles), "--no-link", "--record", long]);
  console.log(`toy robot: recorded ${longCycles} cycles`);
  await measure(`toy robot, ${longCycles} cycles`, long, longCycles, "odom.x");
} finally {
  rmSync(dir, { recursive: true, force: true });
}
