// Seeking in a recording in the GUI: records the delivery (`situate demo --headless --record`),
// opens it with `situate replay FILE --gui`, and clicks the timeline's slider at spread positions,
// timing each click until the page shows that cycle (requestAnimationFrame polling). Issue 14's
// target is under 200 ms on a 10-minute recording. Nothing asserts on timing: it is printed.
//   node bench/gui/seek.mjs [--seeks 20] [--seed 1] [--python PATH]

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
const python = opt("python", path.join(repo, ".venv", "bin", "python"));

const dir = mkdtempSync(path.join(os.tmpdir(), "situate-seek-"));
const file = path.join(dir, "delivery.mcap");
const outcome = await new Promise((resolve, reject) =>
  execFile(situateBin, ["demo", "--headless", "--json", "--seed", seed, "--python", python, "--record", file], { cwd: repo, timeout: 600_000 }, (err, stdout, stderr) =>
    err ? reject(new Error(`${err.message}\n${stderr}`)) : resolve(JSON.parse(stdout.trim().split("\n").pop())),
  ),
);
const minutes = outcome.mission_time_s / 60;
console.log(`recorded ${outcome.cycles} cycles (${minutes.toFixed(1)} simulated minutes), ${(outcome.recording.bytes / 1e6).toFixed(1)} MB`);

const port = await freePort();
let err = "";
const child = spawn(situateBin, ["replay", file, "--gui", `127.0.0.1:${port}`], { cwd: repo, stdio: ["ignore", "ignore", "pipe"] });
child.stderr.on("data", (d) => (err += d));
let browser;
try {
  await until(async () => err.includes("GUI on http"), "the replay's GUI");
  browser = await startBrowser();
  const page = await browser.context.newPage();
  await page.goto(`http://127.0.0.1:${port}/`);
  await page.getByTestId("status").filter({ hasText: "connected" }).waitFor({ timeout: 60_000 });
  await until(async () => new RegExp(`holds cycles 1–${outcome.cycles}`).test((await page.getByTestId("tl-span").textContent()) ?? ""), "every cycle on the timeline");
  const bar = page.getByTestId("timeline");
  await page.getByTestId("tl-live").click();
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
  console.log(`${seeks} seeks: min ${q(0)} ms, median ${q(0.5)} ms, max ${times[times.length - 1].toFixed(0)} ms (target: < 200 ms on 10 minutes)`);
} finally {
  await stopBrowser(browser).catch(() => undefined);
  child.kill("SIGINT");
  rmSync(dir, { recursive: true, force: true });
}
