// The world view's elevator cars: a car's door is open only on the floor the car is at; on every
// other floor the landing door is closed (issue 38: "car 2 at floor 4 shows an open door on floor
// 0"). The testbed's `gui.cars` device (`--cars`) writes `truth.cars` for the fixture map's one
// car, its floor and door set as parameters over the link.

import assert from "node:assert/strict";
import { after, afterEach, before, describe, test } from "node:test";
import { cli, cliDo, closeGui, openGui, screenshotPath, until } from "./harness.mjs";

describe("the world view's cars", () => {
  let tb;
  let browser;
  let page;

  before(async () => {
    ({ tb, browser, page } = await openGui(["--cars"]));
  });

  after(() => closeGui({ tb, browser }));

  afterEach(async (t) => {
    if (page) await page.screenshot({ path: screenshotPath(`world-${t.name.replace(/[^a-z0-9]+/gi, "-")}`), fullPage: true }).catch(() => undefined);
  });

  const canvas = () => page.getByTestId("world-canvas");
  /** The texts of the labels drawn. */
  const labels = async () => JSON.parse((await canvas().getAttribute("data-labels")) ?? "[]").map((l) => l.text);
  /** The cars as drawn on the floor shown: id, floor, whether it is there, its door's state. */
  const cars = async () => JSON.parse((await canvas().getAttribute("data-cars")) ?? "[]");

  test("a car's open door is drawn open on its own floor only; the landing doors elsewhere are closed", async () => {
    // The car at floor 1 with its door open; the robot (the circle) on floor 0.
    await cliDo(tb.linkPort, "param", "set", "cars", "floor", "1");
    await cliDo(tb.linkPort, "param", "set", "cars", "door", "1");
    await until(async () => {
      const v = (await cli(tb.linkPort, "query", "truth.cars")).value;
      return v && v.floor[0] === 1 && v.door[0] === 1;
    }, "the car at floor 1, its door open (over the link)");
    await until(async () => (await labels()).includes("fl 1"), "the car's floor drawn");
    assert.equal(await canvas().getAttribute("data-floor"), "0", "the robot's floor is shown");

    // On floor 1, where the car is, its door is drawn open (once the page has the sample with
    // the door open: the page samples the robot at its own pace).
    await page.getByTestId("world-floor").selectOption("1");
    let drawn = await until(async () => {
      const c = await cars();
      return c.length === 1 && c[0].here && c[0].door === "open" && c;
    }, "the car drawn on floor 1, where it is, its door open");
    assert.deepEqual(drawn, [{ id: 1, floor: 1, here: true, door: "open" }]);
    let ls = await labels();
    assert.ok(ls.includes("open") && !ls.includes("closed"), `the door's label on floor 1: ${JSON.stringify(ls)}`);

    // On floor 0 the same car (door open) is not there: its landing door is closed.
    await page.getByTestId("world-floor").selectOption("0");
    drawn = await until(async () => {
      const c = await cars();
      return (await canvas().getAttribute("data-floor")) === "0" && c.length === 1 && c;
    }, "floor 0 shown");
    assert.deepEqual(drawn, [{ id: 1, floor: 1, here: false, door: "closed" }]);
    ls = await labels();
    assert.ok(ls.includes("closed") && !ls.includes("open"), `the door's label on floor 0: ${JSON.stringify(ls)}`);

    // Between floors (moving) its door is closed on every floor, whatever the car's door reads.
    await cliDo(tb.linkPort, "param", "set", "cars", "floor", "0.5");
    drawn = await until(async () => {
      const c = await cars();
      return c.length === 1 && c[0].floor === 0.5 && c;
    }, "the car between floors 0 and 1");
    assert.deepEqual(drawn, [{ id: 1, floor: 0.5, here: false, door: "closed" }]);
    await page.getByTestId("world-floor").selectOption("0");
    drawn = await until(async () => {
      const c = await cars();
      return (await canvas().getAttribute("data-floor")) === "0" && c.length === 1 && c;
    }, "floor 0 shown");
    assert.deepEqual(drawn, [{ id: 1, floor: 0.5, here: false, door: "closed" }]);

    // Back at floor 0, door half open: shown as such on floor 0.
    await cliDo(tb.linkPort, "param", "set", "cars", "door", "0.5");
    await cliDo(tb.linkPort, "param", "set", "cars", "floor", "0");
    drawn = await until(async () => {
      const c = await cars();
      return c.length === 1 && c[0].here && c[0].door === "50 %" && c;
    }, "the car at floor 0, its door half open");
    assert.deepEqual(drawn, [{ id: 1, floor: 0, here: true, door: "50 %" }]);
  });
});
