// Live plots of signals the user chooses: a signal, a record field (`odom.x`) or an array element
// (`sonar.range[3]`); every numeric leaf of the chosen value gets a line, over a time window.

import { Connection, isObject, type Json, type JsonObject } from "./conn";
import { cssVar, errorText, h, linkControl, numericLeaves, pick, setText } from "./dom";

const COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"];
const MAX_SERIES = 24;

interface Series {
  name: string;
  points: [number, number][];
}

class Plot {
  readonly el: HTMLElement;
  readonly base: string;
  readonly path: string;
  private readonly canvas: HTMLCanvasElement;
  private readonly legend: HTMLElement;
  private readonly series = new Map<string, Series>();
  private received = 0;
  /** When this run's first point came (wall s). */
  private since: number | null = null;
  private last = 0;
  windowS = 30;

  constructor(
    readonly expr: string,
    base: string,
    onRemove: (p: Plot) => void,
  ) {
    this.base = base;
    this.path = expr.slice(base.length);
    this.canvas = h("canvas", { width: 560, height: 180, "data-testid": "plot-canvas", "data-points": 0 });
    this.legend = h("div", { class: "legend" });
    const remove = h("button", { "data-testid": "plot-remove" }, "✕");
    remove.addEventListener("click", () => onRemove(this));
    const win = h("select", { "data-testid": "plot-window" });
    for (const w of [10, 30, 60, 300]) win.append(h("option", { value: w, selected: w === this.windowS }, `${w} s`));
    win.addEventListener("change", () => {
      this.windowS = Number(win.value);
      this.draw(this.last || Date.now() / 1000);
    });
    this.el = h("div", { class: "plot", "data-testid": "plot", "data-expr": expr }, h("div", { class: "row" }, h("strong", {}, expr), win, remove), this.canvas, this.legend);
  }

  /** A new run: the old run's points go. */
  clear(): void {
    this.series.clear();
    this.received = 0;
    this.since = null;
    this.canvas.dataset["points"] = "0";
    this.canvas.dataset["since"] = "";
    this.draw(this.last || Date.now() / 1000);
  }

  add(wall: number, value: Json | undefined): void {
    const v = pick(value, this.path);
    if (v === undefined) return;
    this.last = wall;
    if (this.since === null) {
      this.since = wall;
      this.canvas.dataset["since"] = String(wall);
    }
    for (const [leaf, x] of numericLeaves(v).slice(0, MAX_SERIES)) {
      if (!Number.isFinite(x)) continue;
      const name = this.expr + leaf;
      let s = this.series.get(name);
      if (!s) {
        s = { name, points: [] };
        this.series.set(name, s);
      }
      s.points.push([wall, x]);
      this.received++;
    }
    const cutoff = wall - 300;
    for (const s of this.series.values()) {
      while (s.points.length > 0 && (s.points[0]?.[0] ?? wall) < cutoff) s.points.shift();
    }
    this.canvas.dataset["points"] = String(this.received);
    this.draw(wall);
  }

  private draw(now: number): void {
    const c = this.canvas.getContext("2d");
    if (!c) return;
    const W = this.canvas.width;
    const H = this.canvas.height;
    const pad = { l: 50, r: 8, t: 8, b: 18 };
    c.fillStyle = cssVar("--canvas-bg", "#fff");
    c.fillRect(0, 0, W, H);
    const t0 = now - this.windowS;
    let lo = Infinity;
    let hi = -Infinity;
    for (const s of this.series.values()) {
      for (const [t, y] of s.points) {
        if (t < t0) continue;
        lo = Math.min(lo, y);
        hi = Math.max(hi, y);
      }
    }
    if (!Number.isFinite(lo)) {
      lo = 0;
      hi = 1;
    }
    if (hi - lo < 1e-9) {
      hi += 0.5;
      lo -= 0.5;
    }
    const X = (t: number) => pad.l + ((t - t0) / this.windowS) * (W - pad.l - pad.r);
    const Y = (y: number) => H - pad.b - ((y - lo) / (hi - lo)) * (H - pad.t - pad.b);
    c.strokeStyle = cssVar("--canvas-grid", "#ccc");
    c.lineWidth = 1;
    c.strokeRect(pad.l, pad.t, W - pad.l - pad.r, H - pad.t - pad.b);
    c.fillStyle = cssVar("--canvas-fg", "#333");
    c.font = "11px sans-serif";
    c.fillText(hi.toPrecision(4), 2, pad.t + 10);
    c.fillText(lo.toPrecision(4), 2, H - pad.b);
    c.fillText(`−${this.windowS} s`, pad.l, H - 4);
    c.fillText("now", W - pad.r - 22, H - 4);
    let i = 0;
    this.legend.replaceChildren();
    for (const s of this.series.values()) {
      const color = COLORS[i++ % COLORS.length] ?? "#000";
      c.strokeStyle = color;
      c.lineWidth = 1.5;
      c.beginPath();
      let started = false;
      for (const [t, y] of s.points) {
        if (t < t0) continue;
        if (started) c.lineTo(X(t), Y(y));
        else c.moveTo(X(t), Y(y));
        started = true;
      }
      c.stroke();
      const last = s.points[s.points.length - 1];
      this.legend.append(h("span", { style: `color:${color}` }, `■ ${s.name} = ${last ? last[1].toPrecision(5) : "—"}  `));
    }
  }
}

export class Plots {
  readonly el: HTMLElement;
  private readonly plots: Plot[] = [];
  private readonly list: HTMLElement;
  private readonly input: HTMLInputElement;
  private readonly options: HTMLDataListElement;
  private readonly error: HTMLElement;
  private known: string[] = [];

  constructor(
    private readonly conn: Connection,
    stale: HTMLElement,
  ) {
    this.options = h("datalist", { id: "signal-names" });
    this.input = h("input", { type: "text", list: "signal-names", placeholder: "signal, e.g. odom.x or sonar.range[3]", "data-testid": "plot-signal", class: "wide" });
    const add = linkControl(h("button", { "data-testid": "plot-add" }, "Add plot"));
    add.addEventListener("click", () => void this.add(this.input.value.trim()));
    this.input.addEventListener("keydown", (e) => {
      if (e.key === "Enter") void this.add(this.input.value.trim());
    });
    this.error = h("div", { class: "error", "data-testid": "plot-error" });
    this.list = h("div", { class: "plots" });
    this.el = h("section", { class: "panel live", id: "plots" }, h("h2", {}, "Plots", stale), h("div", { class: "row" }, this.input, this.options, add), this.error, this.list);
  }

  setSignals(names: string[]): void {
    this.known = names;
    this.options.replaceChildren(...names.map((n) => h("option", { value: n })));
  }

  /** The signal to query for an expression: the longest known prefix (or the whole, stripped of `[i]`/`.f`). */
  private baseOf(expr: string): string {
    const cut = (e: string) => e.replace(/(\[\d+\]|\.[A-Za-z_][A-Za-z0-9_]*)$/, "");
    let e = expr;
    while (true) {
      if (this.known.includes(e)) return e;
      const next = cut(e);
      if (next === e || next === "") return expr;
      e = next;
    }
  }

  async add(expr: string): Promise<void> {
    if (expr === "") return;
    if (!/^[A-Za-z_][A-Za-z0-9_.]*(\[\d+\]|\.[A-Za-z_][A-Za-z0-9_]*)*$/.test(expr)) {
      setText(this.error, `"${expr}" is not a signal path (like odom.x or sonar.range[3])`);
      return;
    }
    const base = this.baseOf(expr);
    const plot = new Plot(expr, base, (p) => void this.remove(p));
    this.plots.push(plot);
    try {
      await this.watch();
      setText(this.error, "");
      this.list.append(plot.el);
      // Another signal may have been typed while the server answered: keep it.
      if (this.input.value.trim() === expr) this.input.value = "";
    } catch (e) {
      // Other adds may have been pushed meanwhile: remove this one, not the last.
      const i = this.plots.indexOf(plot);
      if (i >= 0) this.plots.splice(i, 1);
      await this.watch().catch(() => undefined);
      setText(this.error, errorText(e));
    }
  }

  private async remove(p: Plot): Promise<void> {
    const i = this.plots.indexOf(p);
    if (i >= 0) this.plots.splice(i, 1);
    p.el.remove();
    await this.watch().catch(() => undefined);
  }

  /** Tells the server which signals this tab needs (after a reconnection too). */
  async watch(): Promise<void> {
    const signals = [...new Set(this.plots.map((p) => p.base))];
    await this.conn.request("watch", { signals });
  }

  /** A new run: every plot starts again empty. */
  clear(): void {
    for (const p of this.plots) p.clear();
  }

  update(wall: number, signals: Json | undefined): void {
    if (!isObject(signals)) return;
    for (const p of this.plots) {
      const r = signals[p.base];
      if (isObject(r) && "value" in r) p.add(wall, (r as JsonObject)["value"]);
    }
  }
}
