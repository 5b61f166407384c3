// Test harness: starts the GUI testbed (the toy robot + GUI + link) on free ports, a headless
// Debian chromium through playwright-core, and runs the `situate` client CLI over the link.
// Everything started here is stopped by `stopAll`, also when a test fails.

import { spawn, execFile } from "node:child_process";
import { mkdtempSync, mkdirSync, rmSync, existsSync, readFileSync } from "node:fs";
import net from "node:net";
import os from "node:os";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "playwright-core";

const here = path.dirname(fileURLToPath(import.meta.url));
export const webDir = path.resolve(here, "..");
export const repo = path.resolve(webDir, "..");
export const results = path.join(webDir, "test-results");
const target = process.env.CARGO_TARGET_DIR || path.join(repo, "target");
export const testbedBin = process.env.TESTBED_BIN || path.join(target, "debug", "examples", "testbed");
export const situateBin = process.env.SITUATE_BIN || path.join(target, "debug", "situate");
export const chromiumPath = process.env.CHROMIUM || "/usr/bin/chromium";

export const CHROMIUM_ARGS = [
  "--headless",
  "--no-sandbox",
  "--disable-gpu",
  "--disable-quic",
  "--no-first-run",
  "--disable-background-networking",
  "--disable-component-update",
  "--disable-sync",
];

/** A free TCP port on 127.0.0.1 (asked of the OS, then released). */
/** Whether `port` (0: any) can be listened on now; resolves with the port, or 0. */
function tryListen(port) {
  return new Promise((resolve) => {
    const srv = net.createServer();
    srv.on("error", () => resolve(0));
    srv.listen(port, "127.0.0.1", () => {
      const addr = srv.address();
      const got = typeof addr === "object" && addr ? addr.port : 0;
      srv.close(() => resolve(got));
    });
  });
}

/**
 * A loopback port nobody listens on now, chosen below the kernel's range for outgoing
 * connections (as situate_link::free_loopback_port does): a port from that range may be given to
 * another program's outgoing connection before the testbed binds it.
 */
export async function freePort() {
  let low = 32768;
  try {
    low = Number(readFileSync("/proc/sys/net/ipv4/ip_local_port_range", "utf8").trim().split(/\s+/)[0]) || low;
  } catch {}
  for (let i = 0; i < 100 && low > 21000; i++) {
    const port = await tryListen(20000 + Math.floor(Math.random() * (low - 20000)));
    if (port) return port;
  }
  return tryListen(0);
}

/** Starts the testbed; resolves when it prints READY. `guiPort`: serve the GUI there (a restart). */
export async function startTestbed(extraArgs = [], { guiPort: wantedGuiPort } = {}) {
  for (const [what, p] of [["testbed", testbedBin], ["situate CLI", situateBin], ["chromium", chromiumPath]]) {
    if (!existsSync(p)) throw new Error(`${what} not found at ${p} (run scripts/gui.sh test, or set its env variable)`);
  }
  const guiPort = wantedGuiPort ?? (await freePort());
  let linkPort = await freePort();
  while (linkPort === guiPort) linkPort = await freePort();
  const args = ["--gui-port", String(guiPort), "--link-port", String(linkPort), "--stdin", ...extraArgs];
  const child = spawn(testbedBin, args, { stdio: ["pipe", "pipe", "pipe"], env: { ...process.env, RUST_LOG: process.env.RUST_LOG || "warn,zenoh=error" } });
  let out = "";
  let err = "";
  child.stdout.on("data", (d) => (out += d));
  child.stderr.on("data", (d) => (err += d));
  await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`testbed not ready after 60 s\nstdout:\n${out}\nstderr:\n${err}`)), 60_000);
    const check = () => {
      if (out.includes("READY")) {
        clearTimeout(timer);
        resolve();
      }
    };
    child.stdout.on("data", check);
    child.on("exit", (code) => {
      clearTimeout(timer);
      reject(new Error(`testbed exited (${code}) before READY\nstdout:\n${out}\nstderr:\n${err}`));
    });
  });
  child.removeAllListeners("exit");
  return { child, guiPort, linkPort, url: `http://127.0.0.1:${guiPort}/`, logs: () => ({ out, err }) };
}

/** Stops the testbed: closes its stdin (it then shuts down), then kills it if it lingers. */
export async function stopTestbed(tb) {
  if (!tb || tb.child.exitCode !== null || tb.child.signalCode !== null) return;
  const exited = new Promise((resolve) => tb.child.once("exit", resolve));
  tb.child.stdin.end();
  const timer = setTimeout(() => tb.child.kill("SIGKILL"), 10_000);
  await exited;
  clearTimeout(timer);
}

/** Kills the testbed at once (SIGKILL: the robot dies, it does not shut down). */
export async function killTestbed(tb) {
  if (!tb || tb.child.exitCode !== null || tb.child.signalCode !== null) return;
  const exited = new Promise((resolve) => tb.child.once("exit", resolve));
  tb.child.kill("SIGKILL");
  await exited;
}

/** A fresh headless chromium (its own profile directory). */
export async function startBrowser() {
  const profile = mkdtempSync(path.join(os.tmpdir(), "situate-gui-chromium-"));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: chromiumPath,
    headless: true,
    args: CHROMIUM_ARGS,
    viewport: { width: 1400, height: 1000 },
  });
  return { context, profile };
}

export async function stopBrowser(b) {
  if (!b) return;
  try {
    await b.context.close();
  } finally {
    rmSync(b.profile, { recursive: true, force: true });
  }
}

/**
 * A new tab at `url` that shows "connected" (page errors are logged). `viewport`: its size, when
 * not the browser's. `panels` (default true): also wait for the first telemetry sample to have
 * built the skills' panels (wander's switch).
 */
export async function openPage(browser, url, { viewport, panels = true } = {}) {
  const page = await browser.context.newPage();
  page.on("pageerror", (e) => console.error(`page error: ${e.message}`));
  if (viewport) await page.setViewportSize(viewport);
  await page.goto(url);
  await page.getByTestId("status").filter({ hasText: "connected" }).waitFor({ timeout: 60_000 });
  if (panels) await page.getByTestId("switch-wander").waitFor({ timeout: 60_000 });
  return page;
}

/**
 * The set-up of a browser test: a testbed (with `extraArgs`), a browser, and a tab on its GUI
 * (`openPage`, with `panels`), then `ready(page, tb)` for the file's own preparations, if given.
 * When any step fails, what was started is stopped before the error is thrown. Resolves to
 * `{ tb, browser, page }`; pass `{ tb, browser }` to `closeGui` in an `after` hook.
 */
export async function openGui(extraArgs = [], { panels = true, ready } = {}) {
  let tb;
  let browser;
  try {
    tb = await startTestbed(extraArgs);
    browser = await startBrowser();
    const page = await openPage(browser, tb.url, { panels });
    if (ready) await ready(page, tb);
    return { tb, browser, page };
  } catch (e) {
    await stopBrowser(browser).catch(() => undefined);
    await stopTestbed(tb).catch(() => undefined);
    throw e;
  }
}

/** Closes what `openGui` opened (either may be missing: a set-up that failed stopped its own). */
export async function closeGui({ tb, browser } = {}) {
  await stopBrowser(browser).catch((e) => console.error(`closing the browser: ${e.message}`));
  await stopTestbed(tb);
}

/** Runs `situate ARGS --connect tcp/127.0.0.1:PORT --json`; returns its stdout parsed as JSON. */
export function cli(linkPort, ...args) {
  return new Promise((resolve, reject) => {
    execFile(
      situateBin,
      [...args, "--connect", `tcp/127.0.0.1:${linkPort}`, "--json", "--timeout", "10"],
      { timeout: 30_000, env: { ...process.env, RUST_LOG: "error" } },
      (error, stdout, stderr) => {
        if (error) return reject(new Error(`situate ${args.join(" ")} failed: ${error.message}\n${stderr}`));
        try {
          resolve(JSON.parse(stdout));
        } catch {
          reject(new Error(`situate ${args.join(" ")} printed no JSON: ${stdout}\n${stderr}`));
        }
      },
    );
  });
}

/** Runs a `situate` client verb that answers nothing (`cycle stop`, `param set`); resolves on success. */
export function cliDo(linkPort, ...args) {
  return new Promise((resolve, reject) => {
    execFile(
      situateBin,
      [...args, "--connect", `tcp/127.0.0.1:${linkPort}`, "--timeout", "10"],
      { timeout: 30_000, env: { ...process.env, RUST_LOG: "error" } },
      (error, stdout, stderr) => (error ? reject(new Error(`situate ${args.join(" ")} failed: ${error.message}\n${stderr}`)) : resolve(stdout)),
    );
  });
}

/**
 * Starts `program ARGS` in the repository (zenoh quiet); collects its output. The result has
 * `child`, `out`, `err`, `exit` (null while it runs, then `{ code, signal }`) and `exited`.
 */
export function startProgram(program, args) {
  const child = spawn(program, args, {
    cwd: repo,
    stdio: ["ignore", "pipe", "pipe"],
    env: { ...process.env, RUST_LOG: "warn,zenoh=error" },
  });
  const p = { child, out: "", err: "", exit: null };
  child.stdout.on("data", (d) => (p.out += d));
  child.stderr.on("data", (d) => (p.err += d));
  p.exited = new Promise((resolve) =>
    child.on("exit", (code, signal) => {
      p.exit = { code, signal };
      resolve(p.exit);
    }),
  );
  return p;
}

/** Runs `situate ARGS` in the repository to its end (two minutes at most); resolves with its output. */
export function runSituate(...args) {
  return new Promise((resolve, reject) => {
    execFile(situateBin, args, { cwd: repo, timeout: 120_000 }, (err, stdout, stderr) => {
      if (err) reject(new Error(`situate ${args.join(" ")}: ${err.message}\n${stderr}`));
      else resolve(stdout);
    });
  });
}

/** Starts `situate replay FILE ARGS --gui` on a free port and waits until it serves; the result is
 *  `startProgram`'s, with the GUI's `url`. */
export async function startReplayGui(file, args = []) {
  const port = await freePort();
  const p = startProgram(situateBin, ["replay", file, ...args, "--gui", `127.0.0.1:${port}`]);
  await until(async () => p.err.includes("GUI on http") || p.exit !== null, `situate replay ${args.join(" ")} to serve its GUI`);
  if (p.exit !== null) throw new Error(`situate replay exited: ${p.out}\n${p.err}`);
  p.url = `http://127.0.0.1:${port}/`;
  return p;
}

/** Stops a program `startProgram` started: SIGINT, and SIGKILL if it is still there 10 s later. */
export async function stopProgram(p) {
  if (!p || p.exit !== null) return;
  p.child.kill("SIGINT");
  const timer = setTimeout(() => p.child.kill("SIGKILL"), 10_000);
  await p.exited;
  clearTimeout(timer);
}

/**
 * Polls `f` until it returns a truthy value (or throws the last error after `timeoutMs`). The
 * bound only turns a hang into a failure: it is generous so that a loaded machine never trips it.
 */
export async function until(f, what, timeoutMs = 60_000) {
  const end = Date.now() + timeoutMs;
  let last;
  while (Date.now() < end) {
    try {
      const v = await f();
      if (v) return v;
      last = undefined;
    } catch (e) {
      last = e;
    }
    await new Promise((r) => setTimeout(r, 200));
  }
  throw new Error(`timed out waiting for ${what}${last ? `: ${last.message}` : ""}`);
}

export function screenshotPath(name) {
  mkdirSync(results, { recursive: true });
  return path.join(results, `${name}.png`);
}
