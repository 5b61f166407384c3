// Takes a screenshot of a running GUI: node web/tests/screenshot.mjs URL OUT.png [SECONDS]
// (used for the README's picture of the delivery demo: scripts/demo-screenshot.sh).
import { mkdtempSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { chromium } from "playwright-core";

const [url, out, seconds = "20"] = process.argv.slice(2);
if (!url || !out) {
  console.error("usage: node web/tests/screenshot.mjs URL OUT.png [SECONDS]");
  process.exit(2);
}
const context = await chromium.launchPersistentContext(mkdtempSync(join(tmpdir(), "situate-shot-")), {
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  viewport: { width: 1600, height: 1000 },
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
try {
  const page = await context.newPage();
  await page.goto(url);
  await page.waitForTimeout(Number(seconds) * 1000);
  await page.screenshot({ path: out });
  console.log(`screenshot: ${out}`);
} finally {
  await context.close();
}
