// GUI overhead: the mean cycle time of one robot with two GUI tabs and a Foxglove client (subscribed
// to every channel) attached vs none, in one run.
// Phases alternate (none, tabs, tabs, none, …) so drift hits both sides alike; each phase's mean
// cycle time comes from the manager's own stats (cycle counter and mean) read over the link at its
// start and end. Nothing asserts on timing: the verdict is printed.

import { writeFileSync, mkdirSync } from "node:fs";
import { createRequire } from "node:module";
import os from "node:os";
import path from "node:path";
import { cli, startBrowser, startTestbed, stopBrowser, stopTestbed } from "../../web/tests/harness.mjs";

const opt = (name, dflt) => {
  const i = process.argv.indexOf(`--${name}`);
  return i >= 0 && process.argv[i + 1] !== undefined ? process.argv[i + 1] : dflt;
};
const phaseS = Number(opt("phase-s", "15"));
const rounds = Number(opt("rounds", "3"));
const robot = opt("robot", "");
const out = opt("json", "");

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// The Foxglove client the tests use, from the web app's packages.
const webRequire = createRequire(new URL("../../web/tests/harness.mjs", import.meta.url));
const { FoxgloveClient } = webRequire("@foxglove/ws-protocol");
const WS = typeof globalThis.WebSocket === "function" ? globalThis.WebSocket : webRequire("playwright-core/lib/utilsBundle").ws;

/** A Foxglove client on the GUI's /foxglove, subscribed to every channel it advertises; counts
 *  the messages it gets. */
function foxgloveClient(tb) {
  const ws = new WS(`ws://127.0.0.1:${tb.guiPort}/foxglove`, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  const client = new FoxgloveClient({ ws });
  const state = { messages: 0, channels: 0, close: () => client.close() };
  client.on("advertise", (channels) => {
    for (const c of channels) client.subscribe(c.id);
    state.channels += channels.length;
  });
  client.on("message", () => state.messages++);
  client.on("error", (e) => console.error(`foxglove client error: ${e?.message ?? e}`));
  return state;
}

async function phase(tb, label) {
  const a = await cli(tb.linkPort, "stats");
  await sleep(phaseS * 1000);
  const b = await cli(tb.linkPort, "stats");
  const cycles = b.cycle - a.cycle;
  const meanNs = cycles > 0 ? (b.mean_cycle_ns * b.cycle - a.mean_cycle_ns * a.cycle) / cycles : NaN;
  const overruns = b.overruns - a.overruns;
  console.log(`${label.padEnd(6)} ${String(cycles).padStart(6)} cycles, mean cycle time ${(meanNs / 1000).toFixed(2)} µs, overruns ${overruns}`);
  return { label, cycles, mean_ns: meanNs, overruns };
}

const load0 = os.loadavg()[0];
const tb = await startTestbed(["--no-circle", ...(robot ? ["--robot", robot] : [])]);
let browser;
const results = [];
try {
  browser = await startBrowser();
  // Let the robot settle before measuring.
  await sleep(2000);
  for (let r = 0; r < rounds; r++) {
    const order = r % 2 === 0 ? ["none", "tabs"] : ["tabs", "none"];
    for (const what of order) {
      if (what === "none") {
        results.push(await phase(tb, "none"));
      } else {
        const pages = [];
        for (let i = 0; i < 2; i++) {
          const p = await browser.context.newPage();
          await p.goto(tb.url);
          await p.getByTestId("switch-wander").waitFor({ timeout: 20_000 });
          for (const s of ["odom.x", "sonar.range[0]"]) {
            await p.getByTestId("plot-signal").fill(s);
            await p.getByTestId("plot-add").click();
          }
          for (const name of ["runaway", "wheels"]) {
            await p.getByTestId(`skill-${name}`).locator("summary").click();
            await p.getByTestId(`show-input-${name}`).check();
            await p.getByTestId(`show-output-${name}`).check();
          }
          pages.push(p);
        }
        const fox = foxgloveClient(tb);
        try {
          const r = await phase(tb, "tabs");
          r.foxglove_messages = fox.messages;
          r.foxglove_channels = fox.channels;
          console.log(`       foxglove: ${fox.messages} messages on ${fox.channels} channels`);
          results.push(r);
        } finally {
          fox.close();
          for (const p of pages) await p.close();
        }
      }
    }
  }
} finally {
  await stopBrowser(browser).catch(() => undefined);
  await stopTestbed(tb);
}

const mean = (label) => {
  const rs = results.filter((r) => r.label === label);
  const cycles = rs.reduce((s, r) => s + r.cycles, 0);
  return rs.reduce((s, r) => s + r.mean_ns * r.cycles, 0) / cycles;
};
const none = mean("none");
const tabs = mean("tabs");
const ratio = tabs / none;
console.log(`\nmean cycle time: none ${(none / 1000).toFixed(2)} µs, two tabs and a Foxglove client ${(tabs / 1000).toFixed(2)} µs`);
console.log(`ratio (two tabs and Foxglove / none): ${ratio.toFixed(3)}×`);
const load1 = os.loadavg()[0];
const cpus = os.cpus().length;
// Other work on the machine swamps a 5 % effect: then the verdict is not a verdict.
const busy = Math.max(load0, load1) > cpus;
console.log(`load average ${load0.toFixed(2)} → ${load1.toFixed(2)} on ${cpus} CPUs${busy ? " (busy machine)" : ""}`);
console.log(`TARGET two tabs and a Foxglove client ≤ 1.05× none: ${busy ? "INCONCLUSIVE (load above the CPU count), " : ""}${ratio <= 1.05 ? "met" : "NOT met"}`);
if (out) {
  mkdirSync(path.dirname(out), { recursive: true });
  writeFileSync(out, JSON.stringify({ phase_s: phaseS, rounds, none_mean_ns: none, tabs_mean_ns: tabs, ratio, load_avg: [load0, load1], cpus, inconclusive: busy, phases: results }, null, 2));
  console.log(`figures: ${out}`);
}
