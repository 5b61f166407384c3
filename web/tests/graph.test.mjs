// The graph panel (laid out by dagre) in a real browser against the testbed: a node per skill and
// per signal, the wiring as edges, laid out without overlaps inside its panel (no sideways
// scrolling), active skills and each resource's winner as the manager says (over the link).

import assert from "node:assert/strict";
import { after, afterEach, before, describe, test } from "node:test";
import { cli, cliDo, closeGui, openGui, openPage, screenshotPath, until } from "./harness.mjs";

const graphDrawn = (page) => until(async () => (await page.locator("[data-testid=graph] svg g.node").count()) > 0, "the graph drawn");

/** A second, narrow tab with its graph drawn. */
async function openNarrow(browser, url) {
  const page = await openPage(browser, url, { viewport: { width: 390, height: 844 } });
  await graphDrawn(page);
  return page;
}

/** Asks the GUI server's proxy of the link (the manager's own answer), from the page. */
const ask = (page, verb, args = {}) =>
  page.evaluate(
    async ([verb, args]) => {
      const ws = new WebSocket(`ws://${location.host}/ws`);
      try {
        return await new Promise((resolve, reject) => {
          ws.onopen = () => ws.send(JSON.stringify({ id: 1, verb, args }));
          ws.onmessage = (m) => {
            const msg = JSON.parse(m.data);
            if (msg.type === "reply" && msg.id === 1) (msg.error ? reject(new Error(msg.error.message)) : resolve(msg.ok));
          };
          ws.onerror = () => reject(new Error("the WebSocket failed"));
        });
      } finally {
        ws.close();
      }
    },
    [verb, args],
  );

/** The drawn graph: nodes with their boxes on the page, edges, the panel's and the page's widths. */
const drawnGraph = (page) =>
  page.evaluate(() => {
    const box = document.querySelector("[data-testid=graph]");
    const svg = box.querySelector("svg");
    const rect = (el) => {
      const r = el.getBoundingClientRect();
      return { left: r.left, right: r.right, top: r.top, bottom: r.bottom };
    };
    return {
      skills: [...svg.querySelectorAll("g.node.skill")].map((g) => ({ name: g.dataset.node, active: g.dataset.active, rect: rect(g) })),
      signals: [...svg.querySelectorAll("g.node.signal")].map((g) => ({ name: g.dataset.signal, winner: g.dataset.winner, text: g.querySelector("text").textContent, rect: rect(g) })),
      edges: [...svg.querySelectorAll("path.edge")].map((p) => ({ from: p.dataset.from, to: p.dataset.to, winner: p.classList.contains("winner") })),
      svg: rect(svg),
      panel: { ...rect(box.closest(".panel")), clientWidth: box.closest(".panel").clientWidth, scrollWidth: box.closest(".panel").scrollWidth },
      page: { scrollWidth: document.scrollingElement.scrollWidth, innerWidth: window.innerWidth },
    };
  });

const overlap = (a, b) => a.left < b.right - 0.5 && b.left < a.right - 0.5 && a.top < b.bottom - 0.5 && b.top < a.bottom - 0.5;

describe("graph", () => {
  let tb;
  let browser;
  let page;

  before(async () => {
    ({ tb, browser, page } = await openGui([], { ready: graphDrawn }));
  });

  after(() => closeGui({ tb, browser }));

  afterEach(async (t) => {
    if (page) await page.screenshot({ path: screenshotPath(`graph-${t.name.replace(/[^a-z0-9]+/gi, "-")}`), fullPage: true }).catch(() => undefined);
  });

  test("a node per skill and per signal, an edge per writer and reader", async () => {
    const graph = await ask(page, "graph");
    const g = await drawnGraph(page);
    const skills = (await cli(tb.linkPort, "skills")).map((s) => s.name).sort();
    assert.deepEqual(g.skills.map((s) => s.name).sort(), skills, "the manager's skills");
    const drawnSignals = g.signals.map((s) => s.name);
    assert.equal(new Set(drawnSignals).size, drawnSignals.length, "one node per signal");
    // The graph is kept at leaf level (`drive.v`); the page draws the signal a port names (`drive`).
    const nodeOf = (leaf) => drawnSignals.filter((s) => leaf === s || leaf.startsWith(s + ".")).sort((a, b) => b.length - a.length)[0];
    const want = new Set();
    for (const leaf of graph.signals) {
      const node = nodeOf(leaf.signal);
      assert.ok(node, `${leaf.signal} has a node`);
      for (const w of leaf.writers) want.add(`${w}->${node}`);
      for (const r of leaf.readers) want.add(`${node}->${r}`);
    }
    for (const s of drawnSignals) assert.ok(graph.signals.some((l) => nodeOf(l.signal) === s), `${s} is a signal of the manager`);
    const drawnEdges = new Set(g.edges.map((e) => `${e.from}->${e.to}`));
    assert.deepEqual([...drawnEdges].sort(), [...want].sort(), "the wiring, edge for edge");
    assert.equal(drawnEdges.size, g.edges.length, "no edge drawn twice");
  });

  test("laid out without overlaps, inside its panel: no sideways scrolling, at 1400 px and at 390 px", async () => {
    const narrow = await openNarrow(browser, tb.url);
    try {
      for (const [name, p, width] of [["wide", page, 1400], ["narrow", narrow, 390]]) {
        const g = await drawnGraph(p);
        const nodes = [...g.skills, ...g.signals];
        for (let i = 0; i < nodes.length; i++) {
          for (let j = i + 1; j < nodes.length; j++) assert.ok(!overlap(nodes[i].rect, nodes[j].rect), `${name}: ${nodes[i].name} and ${nodes[j].name} overlap`);
        }
        for (const n of nodes) assert.ok(n.rect.left >= g.panel.left && n.rect.right <= g.panel.right, `${name}: ${n.name} inside the panel`);
        assert.ok(g.svg.right - g.svg.left <= g.panel.clientWidth, `${name}: the graph (${g.svg.right - g.svg.left} px) fits the panel (${g.panel.clientWidth} px)`);
        assert.ok(g.panel.scrollWidth <= g.panel.clientWidth, `${name}: the panel does not scroll sideways (${g.panel.scrollWidth} > ${g.panel.clientWidth})`);
        assert.ok(g.page.scrollWidth <= width, `${name}: the page does not scroll sideways (${g.page.scrollWidth} px)`);
        await p.locator("#graph").screenshot({ path: screenshotPath(`graph-${name}`) });
      }
    } finally {
      await narrow.close();
    }
  });

  test("full size draws the graph at its own size, scrolling inside its panel only; fit scales it back", async () => {
    const narrow = await openNarrow(browser, tb.url);
    try {
      for (const [name, p, width] of [["wide", page, 1400], ["narrow", narrow, 390]]) {
        const natural = Number(await p.locator("[data-testid=graph] svg").getAttribute("data-width"));
        assert.ok(natural > 0, `${name}: the layout's width`);
        await p.getByTestId("graph-size").click();
        await until(async () => (await p.getByTestId("graph-size").textContent()) === "Fit", `${name}: full size`);
        let g = await drawnGraph(p);
        assert.ok(Math.abs(g.svg.right - g.svg.left - natural) < 1, `${name}: drawn at its own width ${natural}: ${g.svg.right - g.svg.left}`);
        assert.ok(g.page.scrollWidth <= width, `${name}: the page does not scroll sideways (${g.page.scrollWidth} px)`);
        await p.getByTestId("graph-size").click();
        await until(async () => (await p.getByTestId("graph-size").textContent()) === "Full size", `${name}: fit`);
        g = await drawnGraph(p);
        assert.ok(g.svg.right - g.svg.left <= Math.min(natural, g.panel.clientWidth) + 0.5, `${name}: fitted again`);
        assert.ok(g.panel.scrollWidth <= g.panel.clientWidth, `${name}: the panel does not scroll sideways`);
      }
    } finally {
      await narrow.close();
    }
  });

  test("active skills are highlighted; each resource's winner is marked, node and edge", async () => {
    const node = (name) => page.locator(`[data-testid=graph] g.skill[data-node="${name}"]`);
    await cli(tb.linkPort, "deactivate", "wander");
    try {
      await until(async () => (await node("wander").getAttribute("data-active")) === "false", "wander shown inactive");
      assert.match((await node("wander").getAttribute("class")) ?? "", /\binactive\b/);
    } finally {
      await cli(tb.linkPort, "activate", "wander");
    }
    await until(async () => (await node("wander").getAttribute("data-active")) === "true", "wander shown active");
    assert.match((await node("wander").getAttribute("class")) ?? "", /\bactive\b/);

    // Stopped, the winners hold still: the page and the manager can be compared exactly.
    await cliDo(tb.linkPort, "cycle", "stop");
    await cliDo(tb.linkPort, "cycle", "step", "2");
    try {
      const winners = await ask(page, "winners");
      const resources = winners.filter((w) => w.winner);
      assert.ok(resources.length > 0, `the toy robot has a resource with a winner (drive): ${JSON.stringify(winners)}`);
      for (const w of resources) {
        await until(async () => {
          const g = await drawnGraph(page);
          const sig = g.signals.find((s) => w.signal === s.name || w.signal.startsWith(s.name + "."));
          return sig && sig.winner === w.winner && sig.text.includes(`★${w.winner}`) && g.edges.some((e) => e.from === w.winner && e.to === sig.name && e.winner);
        }, `${w.signal}: ${w.winner} marked the winner in the graph`);
      }
      // Only winners' edges are marked.
      const g = await drawnGraph(page);
      for (const e of g.edges.filter((e) => e.winner)) {
        assert.ok(resources.some((w) => w.winner === e.from && (w.signal === e.to || w.signal.startsWith(e.to + "."))), `${e.from}->${e.to} marked, not a winner`);
      }
    } finally {
      await cliDo(tb.linkPort, "cycle", "run");
    }
  });
});
