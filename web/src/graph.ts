// The graph view: skills and signals as the manager wired them (`graph`), laid out as a layered
// graph by dagre (left to right, as the data flows), active skills highlighted, each
// resource's winner (`winners`) marked. The SVG scales to its panel with a viewBox.

import { isObject, type Json, type JsonObject } from "./conn";
import dagre, { type EdgeLabel, type GraphLabel, type NodeLabel } from "@dagrejs/dagre";
import { h, setText, str } from "./dom";

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
  private leafTypeMap = new Map<string, string>();
  private signals: GSignal[] = [];
  private winners = new Map<string, string | null>();
  private shape = "";
  private leafNames: string[] = [];
  /** The drawn nodes (`k:skill`, `s:signal`) and edges, marked on every update without a new layout. */
  private readonly nodes = new Map<string, SVGGElement>();
  private edges: { from: string; to: string; el: SVGPathElement }[] = [];
  private readonly sizeButton: HTMLButtonElement;
  private full = false;

  constructor(stale: HTMLElement) {
    this.svgBox = h("div", { class: "graph", "data-testid": "graph" });
    // Fit (the default) scales the graph to the panel; full size draws it at its own size, the
    // panel scrolling sideways when it is wider (the page never does).
    this.sizeButton = h("button", { "data-testid": "graph-size", title: "fit the graph to the panel, or draw it at full size (the panel scrolls)" }, "Full size");
    this.sizeButton.addEventListener("click", () => {
      this.full = !this.full;
      this.applySize();
    });
    this.el = h(
      "section",
      { class: "panel live", id: "graph" },
      h("h2", {}, "Graph", stale),
      h("div", { class: "row" }, h("span", { class: "dim graph-help" }, "skills (boxes; rounded: devices; green: active) → signals (ovals; double: a resource, ★ its winner this cycle)"), this.sizeButton),
      this.svgBox,
    );
  }

  /** Fit to the panel (viewBox, never wider than the panel nor than the graph), or full size. */
  private applySize(): void {
    setText(this.sizeButton, this.full ? "Fit" : "Full size");
    this.svgBox.classList.toggle("full", this.full);
    const svg = this.svgBox.querySelector("svg");
    if (!svg) return;
    const w = svg.dataset["width"] ?? "0";
    svg.style.width = this.full ? `${w}px` : "";
    svg.style.maxWidth = this.full ? "none" : `${w}px`;
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
    this.leafTypeMap = new Map(leaves.map((x) => [x.signal, x.type]));
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

  /** Every signal leaf (`odom.x`, `sonar.range`) and its type (`f64`, `f32[24]`). */
  leafTypes(): Map<string, string> {
    return new Map(this.leafTypeMap);
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

  /** Lays the graph out (dagre, left to right) when its shape changed; then marks activity and winners. */
  private render(): void {
    const key = JSON.stringify([this.skills.map((x) => [x.name, x.kind, x.inputs, x.outputs]), this.signals.map((x) => [x.signal, x.writers, x.readers])]);
    if (key !== this.shape) {
      this.shape = key;
      this.layout();
    }
    this.mark();
  }

  private layout(): void {
    const g = new dagre.graphlib.Graph<GraphLabel, NodeLabel, EdgeLabel>({ multigraph: false });
    g.setGraph({ rankdir: "LR", nodesep: 10, ranksep: 34, edgesep: 6, marginx: 4, marginy: 4 });
    g.setDefaultEdgeLabel(() => ({}));
    const H = 26;
    // A skill's kind is in its tooltip and its shape, not its label: narrower ranks.
    for (const sk of this.skills) g.setNode(`k:${sk.name}`, { width: textWidth(sk.name) + 14, height: H });
    for (const sig of this.signals) {
      // A resource's label grows by "★winner": room for its longest writer.
      const longest = Math.max(0, ...sig.writers.map((w) => w.length));
      const label = sig.writers.length > 1 ? `${sig.signal} ★${"m".repeat(longest)}` : sig.signal;
      g.setNode(`s:${sig.signal}`, { width: textWidth(label) + 28, height: H });
    }
    const known = (id: string) => g.hasNode(id);
    for (const sig of this.signals) {
      for (const w of sig.writers) if (known(`k:${w}`)) g.setEdge(`k:${w}`, `s:${sig.signal}`);
      for (const r of sig.readers) if (known(`k:${r}`)) g.setEdge(`s:${sig.signal}`, `k:${r}`);
    }
    dagre.layout(g);
    // The drawing's box: nodes and edge points (an edge turned back by a cycle can bend outside
    // the box dagre reports).
    let [x0, y0, x1, y1] = [0, 0, g.graph().width ?? 0, g.graph().height ?? 0];
    const grow = (x: number, y: number) => {
      [x0, y0, x1, y1] = [Math.min(x0, x), Math.min(y0, y), Math.max(x1, x), Math.max(y1, y)];
    };
    for (const e of g.edges()) for (const p of g.edge(e).points ?? []) grow(p.x - 4, p.y - 4), grow(p.x + 4, p.y + 4);
    [x0, y0] = [Math.floor(x0), Math.floor(y0)];
    const gw = Math.ceil(x1) - x0;
    const gh = Math.ceil(y1) - y0;
    // The SVG scales to its panel (viewBox), never wider than its natural size.
    const svg = s("svg", { viewBox: `${x0} ${y0} ${gw} ${gh}`, preserveAspectRatio: "xMidYMin meet", "data-width": gw, "data-height": gh });
    const defs = s("defs", {});
    const marker = s("marker", { id: "arrow", viewBox: "0 0 10 10", refX: 10, refY: 5, markerWidth: 7, markerHeight: 7, markerUnits: "userSpaceOnUse", orient: "auto" });
    marker.append(s("path", { d: "M0,0 L10,5 L0,10 z", fill: "#666" }));
    defs.append(marker);
    svg.append(defs);
    this.edges = [];
    for (const e of g.edges()) {
      const pts = g.edge(e).points ?? [];
      if (pts.length === 0) continue;
      const d = pts.map((p, i) => `${i === 0 ? "M" : "L"}${p.x.toFixed(1)},${p.y.toFixed(1)}`).join(" ");
      const path = s("path", { d, class: "edge", fill: "none", "marker-end": "url(#arrow)", "data-from": e.v.slice(2), "data-to": e.w.slice(2) });
      svg.append(path);
      this.edges.push({ from: e.v, to: e.w, el: path });
    }
    this.nodes.clear();
    for (const sk of this.skills) {
      const n = g.node(`k:${sk.name}`);
      if (n.x === undefined || n.y === undefined) continue;
      const grp = s("g", { class: "node skill", "data-node": sk.name, "data-kind": sk.kind });
      grp.append(s("rect", { x: n.x - n.width / 2, y: n.y - n.height / 2, width: n.width, height: n.height, rx: sk.kind === "device" ? 9 : 2 }));
      grp.append(s("text", { x: n.x, y: n.y + 4, "text-anchor": "middle" }, sk.name));
      grp.append(s("title", {}, `${sk.name} (${sk.kind})\nreads: ${sk.inputs.join(", ") || "—"}\nwrites: ${sk.outputs.join(", ") || "—"}`));
      svg.append(grp);
      this.nodes.set(`k:${sk.name}`, grp);
    }
    for (const sig of this.signals) {
      const n = g.node(`s:${sig.signal}`);
      if (n.x === undefined || n.y === undefined) continue;
      const resource = sig.writers.length > 1;
      const grp = s("g", { class: `node signal${resource ? " resource" : ""}`, "data-signal": sig.signal, "data-winner": "" });
      grp.append(s("ellipse", { cx: n.x, cy: n.y, rx: n.width / 2, ry: n.height / 2 }));
      if (resource) grp.append(s("ellipse", { cx: n.x, cy: n.y, rx: n.width / 2 - 3, ry: n.height / 2 - 3 }));
      grp.append(s("text", { x: n.x, y: n.y + 4, "text-anchor": "middle" }, sig.signal));
      grp.append(s("title", {}, `${sig.signal}: ${sig.type}\nwriters: ${sig.writers.join(", ")}\nreaders: ${sig.readers.join(", ")}`));
      svg.append(grp);
      this.nodes.set(`s:${sig.signal}`, grp);
    }
    this.svgBox.replaceChildren(svg);
    this.applySize();
  }

  /** Active skills and each resource's winner (and its edge), on the laid-out graph. */
  private mark(): void {
    for (const sk of this.skills) {
      const grp = this.nodes.get(`k:${sk.name}`);
      if (!grp) continue;
      grp.setAttribute("class", `node skill ${sk.active ? "active" : "inactive"}`);
      grp.setAttribute("data-active", String(sk.active));
    }
    for (const sig of this.signals) {
      const grp = this.nodes.get(`s:${sig.signal}`);
      if (!grp) continue;
      const winner = this.winners.get(sig.signal) ?? null;
      grp.setAttribute("data-winner", winner ?? "");
      const text = grp.querySelector("text");
      const label = sig.writers.length > 1 && winner ? `${sig.signal} ★${winner}` : sig.signal;
      if (text && text.textContent !== label) text.textContent = label;
    }
    for (const e of this.edges) {
      const win = e.from.startsWith("k:") && this.winners.get(e.to.slice(2)) === e.from.slice(2);
      e.el.setAttribute("class", win ? "edge winner" : "edge");
    }
  }
}

/** About how wide a label is at the graph's 11 px font (the layout needs node sizes before drawing). */
function textWidth(text: string): number {
  return Math.ceil(text.length * 6.4);
}
