// The page's layout (plots, open skill panels, the cycle shown) in its address: it survives a
// reload, and the address opened in a fresh browser (no storage) shows the same page.

import assert from "node:assert/strict";
import { after, afterEach, before, describe, test } from "node:test";
import { closeGui, openGui, openPage, screenshotPath, startBrowser, stopBrowser, until } from "./harness.mjs";

const text = async (locator) => (await locator.textContent()) ?? "";

describe("the page's layout", () => {
  let tb;
  let browser;
  let page;

  before(async () => {
    ({ tb, browser, page } = await openGui());
  });

  after(() => closeGui({ tb, browser }));

  afterEach(async (t) => {
    if (page) await page.screenshot({ path: screenshotPath(`layout-${t.name.replace(/[^a-z0-9]+/gi, "-")}`), fullPage: true }).catch(() => undefined);
  });

  const plotsShown = async (p) => p.getByTestId("plot").evaluateAll((els) => els.map((e) => e.dataset.expr));
  const hash = async (p) => new URLSearchParams((await p.evaluate(() => location.hash)).slice(1));

  test("plots, an open panel and a paused cycle are in the address, and a reload shows them again", async () => {
    await page.getByTestId("plot-signal").fill("odom.x");
    await page.getByTestId("plot-add").click();
    await until(async () => (await page.getByTestId("plot").count()) === 1, "a plot");
    await page.getByTestId("plot-add-signal").fill("odom.y");
    await page.getByTestId("plot-add-signal-button").click();
    await page.getByTestId("plot-signal").fill("sonar.range[3]");
    await page.getByTestId("plot-add").click();
    await until(async () => JSON.stringify(await plotsShown(page)) === JSON.stringify(["odom.x,odom.y", "sonar.range[3]"]), "two plots, the first of two signals");
    await page.getByTestId("skill-wander").locator("summary").click();
    await page.getByTestId("tl-live").click();
    const bar = page.getByTestId("timeline");
    await until(async () => (await bar.getAttribute("data-shown")) !== null, "paused at a cycle");
    const cycle = Number(await bar.getAttribute("data-shown")) - 1;
    await page.getByTestId("tl-back").click();
    await until(async () => Number(await bar.getAttribute("data-shown")) === cycle, `cycle ${cycle} shown`);
    await until(async () => (await hash(page)).get("cycle") === String(cycle), "the cycle in the address");
    const q = await hash(page);
    assert.equal(q.get("plots"), "odom.x,odom.y|sonar.range[3]");
    assert.equal(q.get("open"), "wander");

    await page.reload();
    await page.getByTestId("status").filter({ hasText: "connected" }).waitFor({ timeout: 60_000 });
    await until(async () => JSON.stringify(await plotsShown(page)) === JSON.stringify(["odom.x,odom.y", "sonar.range[3]"]), "the plots again after a reload");
    await until(async () => Number(await page.getByTestId("timeline").getAttribute("data-shown")) === cycle, `paused at cycle ${cycle} again`);
    await until(async () => page.getByTestId("skill-wander").evaluate((d) => d.open), "wander's panel open again");
    assert.match(await text(page.getByTestId("skills-past")), new RegExp(`at cycle ${cycle} \\(paused`));
  });

  test("the address opened in a fresh browser shows the same page; a malformed part is left out", async () => {
    // The address is saved a moment after a change (at most a few times a second; later on a
    // loaded machine): share it once it names the cycle shown, as a user copying it would.
    const shown = await page.getByTestId("timeline").getAttribute("data-shown");
    assert.ok(shown !== null, "the first page shows a cycle");
    await until(async () => (await hash(page)).get("cycle") === shown, `the address names cycle ${shown}`);
    const url = await page.evaluate(() => location.href);
    const fresh = await startBrowser(); // another browser: the address is all it has
    try {
      const other = await openPage(fresh, url);
      await until(async () => JSON.stringify(await plotsShown(other)) === JSON.stringify(["odom.x,odom.y", "sonar.range[3]"]), "the shared plots");
      const cycle = Number((await hash(page)).get("cycle"));
      // On a timeout, say what the bar showed (its mode, the cycle shown, its note, its span).
      const bar = other.getByTestId("timeline");
      const state = async () => `mode ${await bar.getAttribute("data-mode")}, shown ${await bar.getAttribute("data-shown")}, note "${await text(other.getByTestId("tl-note")).catch(() => "?")}", ${await text(other.getByTestId("tl-span")).catch(() => "?")}, status "${await text(other.getByTestId("status")).catch(() => "?")}"`;
      await until(async () => Number(await bar.getAttribute("data-shown")) === cycle, "the shared cycle").catch(async (e) => {
        throw new Error(`${e.message} ${cycle}: ${await state()}`);
      });
      // A hand-made address: a cycle that is no number is ignored, the plot still comes.
      const base = url.split("#")[0];
      const odd = await openPage(fresh, `${base}#plots=odom.theta&cycle=soon`);
      await until(async () => JSON.stringify(await plotsShown(odd)) === JSON.stringify(["odom.theta"]), "the plot of the hand-made address");
      assert.equal(await odd.getByTestId("timeline").getAttribute("data-mode"), "live");
    } finally {
      await stopBrowser(fresh);
    }
  });

  test("a formula's own commas and bars are escaped in the address, and come back whole", async () => {
    const formula = "min(sonar.range[0], sonar.range[1]) > 0.5 || odom.x > 1";
    await page.getByTestId("plot-signal").fill(formula);
    await page.getByTestId("plot-add").click();
    await until(async () => (await plotsShown(page)).includes(formula), "the formula's plot");
    await until(async () => ((await hash(page)).get("plots") ?? "").endsWith("|min(sonar.range[0]%2C sonar.range[1]) > 0.5 %7C%7C odom.x > 1"), "the formula escaped in the address");
    await page.reload();
    await page.getByTestId("status").filter({ hasText: "connected" }).waitFor({ timeout: 60_000 });
    await until(async () => JSON.stringify(await plotsShown(page)) === JSON.stringify(["odom.x,odom.y", "sonar.range[3]", formula]), "the formula whole after a reload");
  });
});
