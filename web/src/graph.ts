// The graph view: skills and signals as the manager wired them (`graph`), active skills
// highlighted, each resource's winner (`winners`) marked.

import { isObject, type Json, type JsonObject } from "./conn";
import { h, str } from "./dom";

const SVG = "http://www.w3.org/2000/svg";

function s<K extends keyof SVGElementTagNameMap>(tag: K, attrs: Record<string, string | number>, text?: string): SVGElementTagNameMap[K] {
  const el = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, String(v));
  if (text !== undefined) el.textContent = text;
  return el;
}

interface GSkill {
  name: string;
  kind: string;
  active: boolean;
  inputs: string[];
  outputs: string[];
}

interface GSignal {
  signal: string;
  type: string;
  writers: string[];
  readers: string[];
  leaves: string[];
}

function strings(j: Json | undefined): string[] {
  return Array.isArray(j) ? j.filter((x): x is string => typeof x === "string") : [];
}

export class GraphView {
  readonly el: HTMLElement;
  private readonly svgBox: HTMLElement;
  private skills: GSkill[] = [];
  private signals: GSignal[] = [];
  private winners = new Map<string, string | null>();
  private shape = "";
  private leafNames: string[] = [];

  constructor(stale: HTMLElement) {
    this.svgBox = h("div", { class: "graph", "data-testid": "graph" });
    this.el = h(
      "section",
      { class: "panel live", id: "graph" },
      h("h2", {}, "Graph", stale),
      h("p", { class: "dim" }, "skills (boxes, green: active) → signals (ovals; double: a resource, ★ its winner this cycle)"),
      this.svgBox,
    );
  }

  /** The reply of `graph`. */
  setGraph(g: Json): void {
    if (!isObject(g)) return;
    this.skills = (Array.isArray(g["skills"]) ? g["skills"] : []).filter(isObject).map((x) => ({
      name: str(x["name"]),
      kind: str(x["kind"]),
      active: x["active"] === true,
      inputs: strings(x["inputs"]),
      outputs: strings(x["outputs"]),
    }));
    const leaves: Omit<GSignal, "leaves">[] = (Array.isArray(g["signals"]) ? g["signals"] : []).filter(isObject).map((x) => ({
      signal: str(x["signal"]),
      type: str(x["type"]),
      writers: strings(x["writers"]),
      readers: strings(x["readers"]),
    }));
    this.leafNames = leaves.map((x) => x.signal);
    // The graph is kept at leaf level (`drive.v`, `drive.w`); show the signals the skills' ports name (`drive`).
    const ports = new Set<string>();
    for (const sk of this.skills) for (const p of [...sk.inputs, ...sk.outputs]) ports.add(p);
    const groups = new Map<string, GSignal>();
    for (const leaf of leaves) {
      const port = [...ports].filter((p) => leaf.signal === p || leaf.signal.startsWith(p + ".")).sort((a, b) => b.length - a.length)[0] ?? leaf.signal;
      const g0 = groups.get(port) ?? { signal: port, type: "", writers: [], readers: [], leaves: [] };
      for (const w of leaf.writers) if (!g0.writers.includes(w)) g0.writers.push(w);
      for (const r of leaf.readers) if (!g0.readers.includes(r)) g0.readers.push(r);
      g0.leaves.push(leaf.signal === port ? leaf.type : `${leaf.signal.slice(port.length + 1)}: ${leaf.type}`);
      groups.set(port, g0);
    }
    for (const g0 of groups.values()) g0.type = g0.leaves.length === 1 && !g0.leaves[0]?.includes(":") ? (g0.leaves[0] ?? "") : `{${g0.leaves.join(", ")}}`;
    this.signals = [...groups.values()];
    this.shape = "";
    this.render();
  }

  signalNames(): string[] {
    return [...new Set([...this.signals.map((x) => x.signal), ...this.leafNames])].sort();
  }

  /** Live state from telemetry: activity and winners. */
  update(skills: JsonObject[], winners: Json | undefined): void {
    const active = new Map(skills.map((x) => [str(x["name"]), x["active"] === true]));
    for (const sk of this.skills) sk.active = active.get(sk.name) ?? sk.active;
    this.winners.clear();
    if (Array.isArray(winners)) {
      for (const w of winners) {
        if (!isObject(w)) continue;
        const leaf = str(w["signal"]);
        const group = this.signals.find((x) => leaf === x.signal || leaf.startsWith(x.signal + "."));
        const key = group ? group.signal : leaf;
        const who = typeof w["winner"] === "string" ? w["winner"] : null;
        const before = this.winners.get(key);
        this.winners.set(key, before === undefined || before === who ? who : [before, who].filter((x) => x).join("+"));
      }
    }
    this.render();
  }

  private render(): void {
    const key = JSON.stringify([this.skills.map((x) => [x.name, x.active]), [...this.winners]]);
    if (key === this.shape) return;
    this.shape = key;
    // Layers: a skill sits one layer after the skills writing what it reads (cycles cut at a bound).
    const layer = new Map<string, number>(this.skills.map((x) => [x.name, 0]));
    const writers = new Map(this.signals.map((x) => [x.signal, x.writers]));
    for (let pass = 0; pass < this.skills.length; pass++) {
      let changed = false;
      for (const sk of this.skills) {
        if (sk.kind === "device") continue;
        for (const input of sk.inputs) {
          for (const w of writers.get(input) ?? []) {
            const want = (layer.get(w) ?? 0) + 1;
            if (want > (layer.get(sk.name) ?? 0) && want <= this.skills.length) {
              layer.set(sk.name, want);
              changed = true;
            }
          }
        }
      }
      if (!changed) break;
    }
    const colW = 150;
    const rowH = 46;
    const cols = new Map<number, number>();
    const pos = new Map<string, [number, number]>();
    for (const sk of this.skills) {
      const col = 2 * (layer.get(sk.name) ?? 0);
      const row = cols.get(col) ?? 0;
      cols.set(col, row + 1);
      pos.set(`k:${sk.name}`, [20 + col * colW, 20 + row * rowH]);
    }
    for (const sig of this.signals) {
      const wl = Math.max(-1, ...sig.writers.map((w) => layer.get(w) ?? 0));
      const col = 2 * wl + 1;
      const row = cols.get(col) ?? 0;
      cols.set(col, row + 1);
      pos.set(`s:${sig.signal}`, [20 + Math.max(0, col) * colW, 20 + row * rowH]);
    }
    const width = 40 + (Math.max(0, ...cols.keys()) + 1) * colW;
    const height = 40 + Math.max(1, ...cols.values()) * rowH;
    const svg = s("svg", { width, height, viewBox: `0 0 ${width} ${height}` });
    const defs = s("defs", {});
    const marker = s("marker", { id: "arrow", viewBox: "0 0 10 10", refX: 10, refY: 5, markerWidth: 6, markerHeight: 6, orient: "auto" });
    marker.append(s("path", { d: "M0,0 L10,5 L0,10 z", fill: "#666" }));
    defs.append(marker);
    svg.append(defs);
    const boxW = 124;
    const boxH = 28;
    const edge = (from: string, to: string, cls: string) => {
      const a = pos.get(from);
      const b = pos.get(to);
      if (!a || !b) return;
      const [x1, y1, x2, y2] = [a[0] + boxW, a[1] + boxH / 2, b[0], b[1] + boxH / 2];
      // Forward edges bend gently; an edge back to an earlier column (a device reading a command) loops below.
      const d =
        x2 > x1
          ? `M${x1},${y1} C${x1 + 30},${y1} ${x2 - 30},${y2} ${x2},${y2}`
          : `M${x1},${y1} C${x1 + 60},${y1 + 60} ${x2 - 60},${y2 + 60} ${x2},${y2}`;
      svg.append(s("path", { d, class: cls, fill: "none", "marker-end": "url(#arrow)" }));
    };
    for (const sig of this.signals) {
      const winner = this.winners.get(sig.signal);
      for (const w of sig.writers) edge(`k:${w}`, `s:${sig.signal}`, w === winner ? "edge winner" : "edge");
      for (const r of sig.readers) edge(`s:${sig.signal}`, `k:${r}`, "edge");
    }
    for (const sk of this.skills) {
      const p = pos.get(`k:${sk.name}`);
      if (!p) continue;
      const g = s("g", { class: `node skill ${sk.active ? "active" : "inactive"}`, "data-node": sk.name, "data-active": String(sk.active) });
      g.append(s("rect", { x: p[0], y: p[1], width: boxW, height: boxH, rx: 3 }));
      g.append(s("text", { x: p[0] + 6, y: p[1] + 18 }, `${sk.name} (${sk.kind})`));
      svg.append(g);
    }
    for (const sig of this.signals) {
      const p = pos.get(`s:${sig.signal}`);
      if (!p) continue;
      const resource = sig.writers.length > 1;
      const winner = this.winners.get(sig.signal);
      const g = s("g", { class: `node signal${resource ? " resource" : ""}`, "data-signal": sig.signal, "data-winner": winner ?? "" });
      g.append(s("ellipse", { cx: p[0] + boxW / 2, cy: p[1] + boxH / 2, rx: boxW / 2, ry: boxH / 2 }));
      if (resource) g.append(s("ellipse", { cx: p[0] + boxW / 2, cy: p[1] + boxH / 2, rx: boxW / 2 - 3, ry: boxH / 2 - 3 }));
      const label = resource && winner ? `${sig.signal} ★${winner}` : sig.signal;
      g.append(s("text", { x: p[0] + boxW / 2, y: p[1] + 18, "text-anchor": "middle" }, label));
      g.append(s("title", {}, `${sig.signal}: ${sig.type}\nwriters: ${sig.writers.join(", ")}\nreaders: ${sig.readers.join(", ")}`));
      svg.append(g);
    }
    this.svgBox.replaceChildren(svg);
  }
}
