// Live plots of signals the user chooses: a signal, a record field (`odom.x`) or an array element
// (`sonar.range[3]`); every numeric leaf of the chosen values gets a line, over a time window of
// the robot's own time (its clock, simulated or not; a point per cycle sampled, none while the
// robot stands still; the wall clock only for a telemetry that does not say the robot's time).
// Drawn by uPlot. A plot can hold several signals ("add signal"), be paused (the view freezes,
// points keep being buffered; resuming jumps to live), zoomed (drag across the plot; double-click
// or "Live" returns to the live window), panned (◀ ▶, or the wheel with Shift, or sideways),
// linked (a zoom or a pan on one is every plot's), and exported as CSV (every buffered point).
// The timeline's cycle, when it shows one, is a vertical line on every plot of the robot's time.
// A plot may also draw a formula of the condition language over signals (`abs(drive.w) * 2`,
// `odom.x > 1`, true as 1): the server computes it from the same cycle's values, live and over a
// recording, and a value of it is a gap as soon as one of its signals is.
// A value nobody wrote for longer than its writer's rhythm is a gap, not the old value drawn
// again. An expression the robot's signals cannot have (`odom.z`,
// `sonar.range[99]`) is refused, saying why. Hovering shows each sample's cycle and robot time.

import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { Connection, isObject, type Json, type JsonObject } from "./conn";
import { cssVar, errorText, h, linkControl, numericLeaves, pick, setText } from "./dom";
import { drawXY } from "./xy";

const COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"];
/** Lines per plot, at most. */
const MAX_SERIES = 24;
/** Buffered points per line, at most (and never older than the longest window). */
const MAX_ROWS = 6000;
const MAX_AGE_S = 300;
const HEIGHT = 200;
const PATH_RE = /^[A-Za-z_][A-Za-z0-9_.]*(\[\d+\]|\.[A-Za-z_][A-Za-z0-9_]*)*$/;

/** A chosen expression and the signal queried for it (`odom.x` reads `.x` of `odom`); or a formula
 *  of the condition language (`abs(drive.w) * 2`), a derived series the server computes and sends
 *  under its own text (`base`: the formula, `path` empty). */
export interface Source {
  expr: string;
  base: string;
  path: string;
  formula: boolean;
}

/** The longest formula the server takes, in bytes (characters here: a bound, not an exact check). */
const MAX_FORMULA = 500;

type Mode = "live" | "paused" | "zoomed";

/** A plot's x axis: the robot's time (s, its clock) or, when the telemetry does not say it, the
 *  wall clock (Unix s). */
type Axis = "robot" | "wall";

/** The sample a telemetry message is: the robot's newest cycle and its time (s). */
export interface SampleAt {
  cycle: number;
  timeS: number;
}

/** What is known of a source's writes: the cycle of the last write seen, and the last intervals
 *  seen between its writes (cycles; at most RHYTHM_WRITES). */
interface Writes {
  cycle: number;
  intervals: number[];
}

/** How many of a writer's last intervals between writes make its rhythm. */
const RHYTHM_WRITES = 8;

/** Whether a source's reading, last written in cycle `w`, is stale in a sample of the robot's
 *  cycle `now`: not written for longer than its writer's own rhythm (twice the longest of its
 *  last intervals between writes, taken as 5 cycles until two writes were seen, and 2 cycles
 *  more). Also what is known of its writes, updated. */
function stale(writes: Writes | undefined, w: number, now: number): [boolean, Writes] {
  let next: Writes = writes ?? { cycle: w, intervals: [] };
  if (writes !== undefined && w > writes.cycle) next = { cycle: w, intervals: [...writes.intervals.slice(1 - RHYTHM_WRITES), w - writes.cycle] };
  const rhythm = next.intervals.length === 0 ? 5 : Math.max(...next.intervals);
  return [now - w > 2 * rhythm + 2, next];
}

/** Why `expr` names nothing the robot has, from its signal leaves' types (`odom.x` → `f64`,
 *  `sonar.range` → `f32[24]`), or null when it may (or the leaves are not known yet). */
export function refusal(expr: string, leaves: Map<string, string>): string | null {
  if (leaves.size === 0) return null;
  const tokens: (string | number)[] = [];
  const re = /([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]|\./gy;
  let m: RegExpExecArray | null;
  while ((m = re.exec(expr)) !== null) {
    if (m[1] !== undefined) tokens.push(m[1]);
    else if (m[2] !== undefined) tokens.push(Number(m[2]));
  }
  const fieldsOf = (path: string) => [...new Set([...leaves.keys()].filter((l) => l.startsWith(path + ".")).map((l) => l.slice(path.length + 1).split(/[.[]/)[0] ?? ""))];
  let path = "";
  /** The type of `path` when it is a leaf or an element of one; null: a record (or a namespace). */
  let type: string | null = null;
  for (const tok of tokens) {
    if (path === "") {
      path = String(tok);
      type = leaves.get(path) ?? null;
      // Not a known name at all: the server refuses it, with its own suggestion.
      if (type === null && fieldsOf(path).length === 0) return null;
      continue;
    }
    if (type === null) {
      const fields = fieldsOf(path);
      if (typeof tok === "number") return `${expr}: ${path} is a record (fields ${fields.join(", ")}), not an array: no element [${tok}]`;
      if (!fields.includes(tok)) return `${expr}: no field ${tok} in ${path}, whose fields are ${fields.join(", ")}`;
      path = `${path}.${tok}`;
      type = leaves.get(path) ?? null;
    } else {
      // A record inside an array (or any type not spelled simply): not checked here.
      if (type.includes("{")) return null;
      const arr = /^(.*)\[(\d*)\]$/.exec(type);
      if (typeof tok === "number") {
        if (!arr) return `${expr}: ${path} is ${type}, not an array: no element [${tok}]`;
        const n = arr[2] === "" ? null : Number(arr[2]);
        if (n !== null && tok >= n) return `${expr}: index ${tok} is out of ${path}'s range 0..${n - 1} (${path} is ${type})`;
        path = `${path}[${tok}]`;
        type = arr[1] ?? "";
      } else {
        return `${expr}: ${path} is ${type}, which has no field ${tok}`;
      }
    }
  }
  return null;
}

class Plot {
  readonly el: HTMLElement;
  readonly sources: Source[] = [];
  private readonly chartBox: HTMLElement;
  private readonly title: HTMLElement;
  private readonly pauseButton: HTMLButtonElement;
  private readonly addInput: HTMLInputElement;
  private readonly yMin: HTMLInputElement;
  private readonly yMax: HTMLInputElement;
  /** The y axis' fixed range, or null: autoscale. */
  private yFixed: [number, number] | null = null;
  private chart: uPlot | null = null;
  /** The buffer: one time column and one column per line, aligned (null: no value at that time). */
  private times: number[] = [];
  /** Per sample, the robot's newest cycle and its time (s), when the sample said, and when it came
   *  (wall s). */
  private cycles: (number | null)[] = [];
  private robotTimes: (number | null)[] = [];
  private walls: number[] = [];
  /** The x axis, set by the first sample of a run (null: none yet). */
  private axis: Axis | null = null;
  private readonly names: string[] = [];
  private readonly columns = new Map<string, (number | null)[]>();
  /** Per source (its expression), its writes seen. */
  private readonly writes = new Map<string, Writes>();
  private received = 0;
  /** Values not written for longer than their writer's rhythm (gaps), per line. */
  private readonly gaps = new Map<string, number>();
  /** The first buffered sample drawn (the legend's index 0). */
  private viewStart = 0;
  /** When this run's first point came (wall s). */
  private since: number | null = null;
  private mode: Mode = "live";
  /** The paused view's end (wall s), or the zoomed view. */
  private frozenEnd = 0;
  private zoom: { min: number; max: number } = { min: 0, max: 0 };
  private draws = 0;
  /** A replay's plot: the whole recording on the robot's time (the x axis: its clock, s), from
   *  the timeline (`history_series`), and a playhead at the timeline's cycle. */
  private recording = false;
  /** `history_series` asks made for this plot (`Plots.fill`: only the latest is shown). */
  fills = 0;
  /** While the recording's points are added (no redraw per point). */
  private bulk = false;
  private playheadT: number | null = null;
  /** The timeline's cycle's time as last asked, drawn or not (a plot's axis may not be known yet). */
  private askedPlayhead: number | null = null;
  private readonly liveButton: HTMLButtonElement;
  private readonly windowSelect: HTMLSelectElement;
  /** XY: the plot's second line against its first (`odom.y` against `odom.x`), over the same
   *  time range, on a canvas of its own. */
  private xy = false;
  private readonly xyToggle: HTMLInputElement;
  private readonly xyCanvas: HTMLCanvasElement;
  private readonly resizer = new ResizeObserver(() => this.resize());
  private readonly scheme = window.matchMedia("(prefers-color-scheme: dark)");
  private readonly onScheme = () => this.rebuild();
  windowS = 30;

  constructor(
    first: Source,
    onRemove: (p: Plot) => void,
    onAddSignal: (p: Plot, expr: string) => Promise<void>,
  ) {
    this.sources.push(first);
    this.chartBox = h("div", { class: "plot-chart", "data-testid": "plot-canvas", "data-points": 0, "data-state": "live" });
    this.title = h("strong", { "data-testid": "plot-title" }, first.expr);
    const remove = h("button", { "data-testid": "plot-remove", title: "remove this plot" }, "✕");
    remove.addEventListener("click", () => onRemove(this));
    const win = h("select", { "data-testid": "plot-window", title: "time window" });
    for (const w of [10, 30, 60, 300]) win.append(h("option", { value: w, selected: w === this.windowS }, `${w} s`));
    win.addEventListener("change", () => {
      this.windowS = Number(win.value);
      if (this.mode === "zoomed") this.mode = "live";
      this.redraw();
    });
    this.pauseButton = h("button", { "data-testid": "plot-pause", title: "freeze the view (points are still buffered)" }, "Pause");
    this.pauseButton.addEventListener("click", () => (this.mode === "live" ? this.pause() : this.goLive()));
    const live = h("button", { "data-testid": "plot-reset", title: "back to the live window (after a zoom or a pause)" }, "Live");
    live.addEventListener("click", () => this.goLive());
    this.liveButton = live;
    this.windowSelect = win;
    const csv = h("button", { "data-testid": "plot-csv", title: "download every buffered point as CSV" }, "CSV");
    const panBack = h("button", { "data-testid": "plot-pan-back", title: "earlier: move the view back by half its width (or Shift + wheel)" }, "◀");
    panBack.addEventListener("click", () => this.pan(-0.5));
    const panForward = h("button", { "data-testid": "plot-pan-forward", title: "later: move the view on by half its width (or Shift + wheel)" }, "▶");
    panForward.addEventListener("click", () => this.pan(0.5));
    // The y axis fits the lines drawn (autoscale) unless both ends are given.
    const yEnd = (which: string) => {
      const el = h("input", { type: "number", step: "any", placeholder: `y ${which}`, title: `y axis ${which} (empty: autoscale)`, "data-testid": `plot-y-${which}`, class: "plot-y" });
      el.addEventListener("change", () => this.setY());
      return el;
    };
    this.yMin = yEnd("min");
    this.yMax = yEnd("max");
    csv.addEventListener("click", () => this.download());
    this.addInput = h("input", { type: "text", list: "signal-names", placeholder: "add signal", "data-testid": "plot-add-signal", class: "plot-more" });
    const addButton = linkControl(h("button", { "data-testid": "plot-add-signal-button" }, "+"));
    const addSignal = () => {
      const expr = this.addInput.value.trim();
      if (expr === "") return;
      void onAddSignal(this, expr).then(() => {
        if (this.addInput.value.trim() === expr && this.has(expr)) this.addInput.value = "";
      });
    };
    addButton.addEventListener("click", addSignal);
    this.addInput.addEventListener("keydown", (e) => {
      if (e.key === "Enter") addSignal();
    });
    this.xyToggle = h("input", { type: "checkbox", "data-testid": "plot-xy", disabled: true });
    this.xyToggle.addEventListener("change", () => this.setXY(this.xyToggle.checked));
    const xyLabel = h("label", { class: "toggle", title: "the second line against the first (e.g. odom.y against odom.x): a plot of two lines" }, this.xyToggle, " XY");
    this.xyCanvas = h("canvas", { class: "plot-xy", "data-testid": "plot-xy-canvas", hidden: true });
    this.el = h(
      "div",
      { class: "plot", "data-testid": "plot", "data-expr": first.expr },
      h("div", { class: "row" }, this.title, win, this.pauseButton, panBack, panForward, live, csv, xyLabel, remove),
      this.chartBox,
      this.xyCanvas,
      h("div", { class: "row" }, this.addInput, addButton, this.yMin, this.yMax),
    );
    this.resizer.observe(this.chartBox);
    this.scheme.addEventListener("change", this.onScheme);
    // Sideways (a trackpad's), or Shift + wheel: pan. The plain wheel scrolls the page.
    this.chartBox.addEventListener(
      "wheel",
      (e) => {
        const raw = Math.abs(e.deltaX) > Math.abs(e.deltaY) ? e.deltaX : e.shiftKey ? e.deltaY : 0;
        if (raw === 0 || this.times.length === 0) return;
        e.preventDefault();
        // In pixels, whatever the browser counts in (lines: Firefox's wheel; pages).
        const width = Math.max(1, this.chartBox.clientWidth);
        const d = raw * (e.deltaMode === WheelEvent.DOM_DELTA_LINE ? 16 : e.deltaMode === WheelEvent.DOM_DELTA_PAGE ? width : 1);
        this.pan(Math.max(-0.5, Math.min(0.5, d / width)));
      },
      { passive: false },
    );
  }

  has(expr: string): boolean {
    return this.sources.some((s) => s.expr === expr);
  }

  addSource(src: Source): void {
    if (this.has(src.expr)) return;
    this.sources.push(src);
    setText(this.title, this.sources.map((s) => s.expr).join(", "));
    this.el.dataset["expr"] = this.sources.map((s) => s.expr).join(",");
  }

  removeSource(expr: string): void {
    const i = this.sources.findIndex((s) => s.expr === expr);
    if (i < 0 || this.sources.length === 1) return;
    this.sources.splice(i, 1);
    this.writes.delete(expr);
    setText(this.title, this.sources.map((s) => s.expr).join(", "));
    this.el.dataset["expr"] = this.sources.map((s) => s.expr).join(",");
  }

  /** A new run: the old run's points go, and the view is live again. */
  clear(): void {
    this.times = [];
    this.cycles = [];
    this.robotTimes = [];
    this.walls = [];
    this.axis = null;
    this.names.length = 0;
    this.columns.clear();
    this.writes.clear();
    this.gaps.clear();
    this.chartBox.dataset["gaps"] = "{}";
    this.received = 0;
    this.since = null;
    this.chartBox.dataset["points"] = "0";
    this.chartBox.dataset["since"] = "";
    this.setMode("live");
    this.rebuild();
  }

  /** One telemetry sample: a point per numeric leaf of every source present in it, a gap (null)
   *  for a stale one (`at`: the sample's cycle and robot time, when the telemetry said). On the
   *  robot's time, a sample of a cycle already drawn adds nothing (the robot stood still). */
  add(wall: number, signals: JsonObject, at: SampleAt | null = null): void {
    const axis: Axis = this.axis ?? (at !== null || this.recording ? "robot" : "wall");
    if (axis === "robot") {
      if (at === null) return;
      const lastCycle = this.cycles[this.cycles.length - 1];
      const lastT = this.times[this.times.length - 1];
      if (lastCycle === at.cycle || (lastT !== undefined && at.timeS <= lastT)) return;
    }
    const x = axis === "robot" && at !== null ? at.timeS : wall;
    const row: [string, number | null][] = [];
    for (const src of this.sources) {
      const r = signals[src.base];
      if (!isObject(r) || !("value" in r)) continue;
      const v = pick((r as JsonObject)["value"], src.path);
      if (v === undefined) continue;
      let old = false;
      const w = r["cycle"];
      if (at !== null && typeof w === "number") {
        const [s, writes] = stale(this.writes.get(src.expr), w, at.cycle);
        this.writes.set(src.expr, writes);
        old = s;
      }
      for (const [leaf, x] of numericLeaves(v)) if (Number.isFinite(x)) row.push([src.expr + leaf, old ? null : x]);
    }
    if (row.length === 0) return;
    if (this.axis === null) {
      this.axis = axis;
      this.chartBox.dataset["axis"] = axis;
      // A cycle the timeline showed before the axis was known: its line now.
      this.setPlayhead(this.askedPlayhead);
    }
    if (this.since === null) {
      this.since = wall;
      this.chartBox.dataset["since"] = String(wall);
    }
    let newLines = false;
    for (const [name] of row) {
      if (this.columns.has(name) || this.names.length >= MAX_SERIES) continue;
      this.names.push(name);
      this.columns.set(name, new Array<number | null>(this.times.length).fill(null));
      newLines = true;
    }
    this.times.push(x);
    this.cycles.push(at?.cycle ?? null);
    this.robotTimes.push(at?.timeS ?? null);
    this.walls.push(wall);
    if (at !== null) this.chartBox.dataset["cycle"] = String(at.cycle);
    const values = new Map(row);
    let gap = false;
    for (const name of this.names) {
      // A line of no source in this sample (removed, or absent): a gap.
      const x = values.get(name) ?? null;
      this.columns.get(name)?.push(x);
      if (typeof x === "number") this.received++;
      else if (x === null && values.has(name)) {
        this.gaps.set(name, (this.gaps.get(name) ?? 0) + 1);
        gap = true;
      }
    }
    if (!this.recording) this.trim(x);
    this.chartBox.dataset["points"] = String(this.received);
    if (gap) this.chartBox.dataset["gaps"] = JSON.stringify(Object.fromEntries(this.gaps));
    if (this.bulk) return;
    if (newLines) this.rebuild();
    else if (this.mode === "live") this.redraw();
  }

  /** Shows a recording (a replay's timeline): `series` is a `history_series` reply for this
   *  plot's signals, its points on the robot's time; stale values are gaps by the same rule as
   *  live. Live samples are no longer taken. */
  setSeries(series: JsonObject): void {
    this.clear();
    this.recording = true;
    this.chartBox.dataset["state"] = "recording";
    this.el.dataset["recording"] = "";
    setText(this.liveButton, "All");
    this.liveButton.title = "the whole recording again (after a zoom)";
    this.pauseButton.hidden = true;
    this.windowSelect.hidden = true;
    const nums = (j: Json | undefined) => (Array.isArray(j) ? j.map((x) => (typeof x === "number" ? x : null)) : []);
    const cycles = nums(series["cycles"]);
    const times = nums(series["times"]);
    const bySignal = isObject(series["signals"]) ? series["signals"] : {};
    this.bulk = true;
    cycles.forEach((cycle, i) => {
      const t = times[i];
      if (cycle === null || t === null || t === undefined) return;
      const at: JsonObject = {};
      for (const [name, sig] of Object.entries(bySignal)) {
        if (!isObject(sig)) continue;
        const value = Array.isArray(sig["values"]) ? sig["values"][i] : null;
        const written = Array.isArray(sig["written"]) ? sig["written"][i] : null;
        if (value !== null && value !== undefined && typeof written === "number") at[name] = { value, cycle: written };
      }
      this.add(t, at, { cycle, timeS: t });
    });
    this.bulk = false;
    this.chartBox.dataset["series"] = String(cycles.length);
    this.rebuild();
  }

  /** The timeline's cycle, at robot time `t` (null: none shown), drawn as a vertical line (on a
   *  plot of the robot's time). */
  setPlayhead(t: number | null): void {
    this.askedPlayhead = t;
    if (t !== null && !this.onRobotTime()) t = null;
    if (t === this.playheadT) return;
    this.playheadT = t;
    this.chartBox.dataset["playhead"] = t === null ? "" : String(t);
    this.chart?.redraw(false, false);
  }

  /** Whether this plot shows a recording (no live samples). */
  isRecording(): boolean {
    return this.recording;
  }

  /** Whether its x axis is the robot's time (a recording's always is). */
  onRobotTime(): boolean {
    return this.recording || this.axis === "robot";
  }

  /** Bounded memory: at most MAX_ROWS points per line, none older than MAX_AGE_S. */
  private trim(now: number): void {
    // Dropped in batches (64 samples at least): splicing every sample would copy the whole buffer
    // at the sample rate.
    let drop = this.times.length > MAX_ROWS ? this.times.length - MAX_ROWS + 64 : 0;
    while (drop < this.times.length && (this.times[drop] ?? now) < now - MAX_AGE_S) drop++;
    if (drop < 64) return;
    this.times.splice(0, drop);
    this.cycles.splice(0, drop);
    this.robotTimes.splice(0, drop);
    this.walls.splice(0, drop);
    for (const c of this.columns.values()) c.splice(0, drop);
  }

  private last(): number {
    return this.times[this.times.length - 1] ?? Date.now() / 1000;
  }

  /** The x range to show. */
  private view(): { min: number; max: number } {
    if (this.mode === "zoomed") return this.zoom;
    if (this.recording) return { min: this.times[0] ?? 0, max: this.last() };
    const end = this.mode === "paused" ? this.frozenEnd : this.last();
    return { min: end - this.windowS, max: end };
  }

  private setMode(mode: Mode): void {
    this.mode = mode;
    this.chartBox.dataset["state"] = this.recording && mode === "live" ? "recording" : mode;
    setText(this.pauseButton, mode === "live" ? "Pause" : "Resume");
  }

  pause(): void {
    this.frozenEnd = this.last();
    this.setMode("paused");
    this.redraw();
  }

  /** Back to the live window (a recording's plot: the whole recording); the other plots follow. */
  goLive(emit = true): void {
    this.setMode("live");
    this.redraw();
    if (emit) this.onView(null);
  }

  /** Shows only `min`..`max` on the x axis; the other plots follow (their x axes are linked). */
  zoomTo(min: number, max: number, emit = true): void {
    if (!(max > min)) return;
    this.zoom = { min, max };
    this.setMode("zoomed");
    this.redraw();
    if (emit) this.onView({ min, max });
  }

  /** Moves the view by `fraction` of its width (negative: earlier); the other plots follow. An
   *  empty plot has no time to move along. */
  pan(fraction: number): void {
    if (this.times.length === 0) return;
    const v = this.view();
    const d = (v.max - v.min) * fraction;
    this.zoomTo(v.min + d, v.max + d);
  }

  /** Called when the user zooms or pans this plot (or returns it to live: null): the others follow. */
  onView: (view: { min: number; max: number } | null) => void = () => {};

  /** Both ends given (min < max): a fixed y range; otherwise autoscale. */
  private setY(): void {
    const lo = this.yMin.value.trim() === "" ? NaN : Number(this.yMin.value);
    const hi = this.yMax.value.trim() === "" ? NaN : Number(this.yMax.value);
    const fixed: [number, number] | null = Number.isFinite(lo) && Number.isFinite(hi) && lo < hi ? [lo, hi] : null;
    const bad = (this.yMin.value.trim() !== "" || this.yMax.value.trim() !== "") && fixed === null;
    this.yMin.classList.toggle("refused", bad);
    this.yMax.classList.toggle("refused", bad);
    this.chartBox.dataset["yFixed"] = fixed ? JSON.stringify(fixed) : "";
    if (JSON.stringify(fixed) === JSON.stringify(this.yFixed)) return;
    this.yFixed = fixed;
    this.rebuild();
  }

  private resize(): void {
    const w = Math.floor(this.chartBox.clientWidth);
    if (w <= 0) return;
    if (!this.chart) this.rebuild();
    else if (this.chart.width !== w) this.chart.setSize({ width: w, height: HEIGHT });
  }

  /** A new chart (its lines changed, or the colour scheme). */
  private rebuild(): void {
    this.chart?.destroy();
    this.chart = null;
    const width = Math.floor(this.chartBox.clientWidth);
    if (width <= 0) return;
    const fg = cssVar("--canvas-fg", "#333");
    const grid = cssVar("--canvas-grid", "#ccc");
    const axis = (): uPlot.Axis => ({ stroke: fg, grid: { stroke: grid, width: 1 }, ticks: { stroke: grid, width: 1 } });
    const opts: uPlot.Options = {
      width,
      height: HEIGHT,
      scales: { x: { time: !this.onRobotTime() }, ...(this.yFixed ? { y: { auto: false, range: this.yFixed } } : {}) },
      axes: [this.onRobotTime() ? { ...axis(), label: "robot time (s)" } : axis(), { ...axis(), size: 60 }],
      // The legend's time: the sample's cycle and robot time (and, live, when it was sampled).
      series: [{ label: "at", value: (_u, _v, _s, idx) => (idx === null ? "—" : this.sampleText(this.viewStart + idx)) }, ...this.names.map((name, i) => ({ label: name, stroke: COLORS[i % COLORS.length] ?? "#000", width: 1.5 }))],
      cursor: {
        drag: { x: true, y: false, setScale: false },
        // Double-click: back to the live window (uPlot's own would show all the buffer).
        bind: { dblclick: () => () => (this.goLive(), null) },
      },
      hooks: {
        setSelect: [
          (u) => {
            if (u.select.width < 3) return;
            const min = u.posToVal(u.select.left, "x");
            const max = u.posToVal(u.select.left + u.select.width, "x");
            u.setSelect({ left: 0, top: 0, width: 0, height: 0 }, false);
            this.zoomTo(min, max);
          },
        ],
        draw: [
          (u) => {
            // The timeline's cycle (a replay's, or a live robot's paused timeline).
            const t = this.playheadT;
            if (t === null) return;
            const x = u.valToPos(t, "x", true);
            const ctx = u.ctx;
            ctx.save();
            ctx.strokeStyle = fg;
            ctx.lineWidth = 2 * (window.devicePixelRatio || 1);
            ctx.beginPath();
            ctx.moveTo(x, u.bbox.top);
            ctx.lineTo(x, u.bbox.top + u.bbox.height);
            ctx.stroke();
            ctx.restore();
          },
        ],
        setScale: [
          (u, key) => {
            // One attribute per axis, so that a reader never sees the ends of two different views.
            if (key === "x" || key === "y") this.chartBox.dataset[`${key}Range`] = JSON.stringify([u.scales[key]?.min ?? null, u.scales[key]?.max ?? null]);
          },
        ],
      },
    };
    this.chart = new uPlot(opts, [[]], this.chartBox);
    this.redraw();
  }

  /** XY on or off (on only with two lines). */
  private setXY(on: boolean): void {
    this.xy = on && this.names.length === 2;
    this.xyToggle.checked = this.xy;
    this.xyCanvas.hidden = !this.xy;
    this.chartBox.hidden = this.xy;
    this.el.dataset["xy"] = this.xy ? "on" : "off";
    if (!this.xy) this.resize();
    this.redraw();
  }

  /** The second line against the first over rows `i0`..`i1` (see `xy.ts`). */
  private drawXY(i0: number, i1: number): void {
    const [xName, yName] = this.names;
    const column = (name: string | undefined) => (name !== undefined ? this.columns.get(name) : undefined) ?? [];
    const n = drawXY(this.xyCanvas, Math.max(100, Math.floor(this.el.clientWidth)), HEIGHT, { name: xName ?? "", values: column(xName) }, { name: yName ?? "", values: column(yName) }, i0, i1, COLORS);
    this.el.dataset["xyPoints"] = String(n);
  }

  /** Draws the view: the buffered points inside it (copied: the buffer keeps growing). */
  private redraw(): void {
    this.xyToggle.disabled = this.names.length !== 2;
    if (this.xy && this.names.length !== 2) this.setXY(false);
    if (this.xy) {
      const v = this.view();
      this.drawXY(lowerBound(this.times, v.min), lowerBound(this.times, v.max + 1e-9));
      return;
    }
    const u = this.chart;
    if (!u) return;
    const { min, max } = this.view();
    const i0 = lowerBound(this.times, min);
    const i1 = lowerBound(this.times, max + 1e-9);
    this.viewStart = i0;
    const data: uPlot.AlignedData = [this.times.slice(i0, i1), ...this.names.map((n) => (this.columns.get(n) ?? []).slice(i0, i1))];
    u.batch(() => {
      u.setData(data, false);
      u.setScale("x", { min, max });
    });
    // Not hovered, the legend shows each line's newest drawn value.
    const n = data[0].length;
    if ((u.cursor.left ?? -1) < 0 && n > 0) u.setLegend({ idx: n - 1 });
    this.draws++;
    this.chartBox.dataset["draws"] = String(this.draws);
    // Per line, how many of the drawn points have a value (what the tests read).
    const drawn: Record<string, number> = {};
    this.names.forEach((n, i) => (drawn[n] = (data[i + 1] ?? []).filter((x) => x !== null && x !== undefined).length));
    this.chartBox.dataset["drawn"] = JSON.stringify(drawn);
    // Per line, its newest drawn cell: a number, or null (a gap).
    const last: Record<string, number | null> = {};
    this.names.forEach((n, i) => (last[n] = (data[i + 1] ?? [])[data[0].length - 1] ?? null));
    this.chartBox.dataset["last"] = JSON.stringify(last);
  }

  /** Which sample the buffer's row `i` is: its cycle and robot time, and its wall-clock time. */
  private sampleText(i: number): string {
    const wall = this.walls[i];
    if (wall === undefined) return "—";
    const cycle = this.cycles[i];
    const t = this.robotTimes[i];
    if (this.recording) return `cycle ${cycle ?? "—"}, t = ${(t ?? 0).toFixed(2)} s`;
    const d = new Date(wall * 1000);
    const two = (n: number) => String(n).padStart(2, "0");
    const clock = `${two(d.getHours())}:${two(d.getMinutes())}:${two(d.getSeconds())}.${String(d.getMilliseconds()).padStart(3, "0")}`;
    return cycle === null || cycle === undefined ? clock : `cycle ${cycle}, t = ${(t ?? 0).toFixed(2)} s (${clock})`;
  }

  /** The buffer as CSV, a row per sample: on the robot's time `robot_t_s` (its clock) and `cycle`,
   *  else `t_s` (the wall clock, Unix seconds); then a column per line. */
  csv(): string {
    const quote = (s: string) => (/[",\n]/.test(s) ? `"${s.replace(/"/g, '""')}"` : s);
    const robot = this.onRobotTime();
    const lines = [[...(robot ? ["robot_t_s", "cycle"] : ["t_s"]), ...this.names].map(quote).join(",")];
    this.times.forEach((t, i) => {
      lines.push([String(t), ...(robot ? [String(this.cycles[i] ?? "")] : []), ...this.names.map((n) => {
        const v = this.columns.get(n)?.[i];
        return v === null || v === undefined ? "" : String(v);
      })].join(","));
    });
    return lines.join("\n") + "\n";
  }

  private download(): void {
    const url = URL.createObjectURL(new Blob([this.csv()], { type: "text/csv" }));
    const stamp = new Date().toISOString().replace(/[:.]/g, "-");
    const name = `plot-${this.sources.map((s) => s.expr).join("+").replace(/[^A-Za-z0-9_.+-]+/g, "_")}-${stamp}.csv`;
    const a = h("a", { href: url, download: name });
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(url), 60_000);
  }

  destroy(): void {
    this.resizer.disconnect();
    this.scheme.removeEventListener("change", this.onScheme);
    this.chart?.destroy();
    this.chart = null;
  }
}

/** What to ask the server for, for `sources`: the signals, and the formulas, each once. */
function watched(sources: Source[]): { signals: string[]; formulas: string[] } {
  return {
    signals: [...new Set(sources.filter((s) => !s.formula).map((s) => s.base))],
    formulas: [...new Set(sources.filter((s) => s.formula).map((s) => s.expr))],
  };
}

/** The first index whose time is at least `t` (times ascending). */
function lowerBound(times: number[], t: number): number {
  let lo = 0;
  let hi = times.length;
  while (lo < hi) {
    const mid = (lo + hi) >> 1;
    if ((times[mid] ?? Infinity) < t) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

export class Plots {
  readonly el: HTMLElement;
  private readonly plots: Plot[] = [];
  private readonly list: HTMLElement;
  private readonly input: HTMLInputElement;
  private readonly options: HTMLDataListElement;
  private readonly error: HTMLElement;
  private known: string[] = [];
  private leaves = new Map<string, string>();
  /** A replay: plots show the recording (the timeline's) on the robot's time. */
  private recording = false;
  /** Called when the plots or their signals change (the page's layout is saved). */
  onChange: () => void = () => {};
  private playheadT: number | null = null;

  constructor(
    private readonly conn: Connection,
    stale: HTMLElement,
  ) {
    this.options = h("datalist", { id: "signal-names" });
    this.input = h("input", { type: "text", list: "signal-names", placeholder: "a signal (odom.x, sonar.range[3]) or a formula (abs(drive.w) * 2)", "data-testid": "plot-signal", class: "wide" });
    const add = linkControl(h("button", { "data-testid": "plot-add" }, "Add plot"));
    add.addEventListener("click", () => void this.add(this.input.value.trim()));
    this.input.addEventListener("keydown", (e) => {
      if (e.key === "Enter") void this.add(this.input.value.trim());
    });
    this.error = h("div", { class: "error", "data-testid": "plot-error" });
    this.list = h("div", { class: "plots" });
    this.el = h(
      "section",
      { class: "panel live", id: "plots" },
      h("h2", {}, "Plots", stale),
      h("div", { class: "row" }, this.input, this.options, add),
      h("p", { class: "dim plot-help" }, "a signal, or a formula of the condition language (abs(drive.w) * 2); x: the robot's time; drag across a plot: zoom; ◀ ▶ or Shift + wheel: pan; double-click or Live: back to live"),
      this.error,
      this.list,
    );
  }

  /** The robot's signals (for the field's suggestions) and its leaves' types (to refuse what
   *  none of them has). */
  setSignals(names: string[], leaves: Map<string, string> = new Map()): void {
    this.known = names;
    this.leaves = leaves;
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

  private source(expr: string): Source | null {
    if (!PATH_RE.test(expr)) {
      // A formula: the server compiles it (and says what is wrong, at which column).
      if (expr.length > MAX_FORMULA) {
        setText(this.error, `a formula of ${expr.length} characters: at most ${MAX_FORMULA}`);
        return null;
      }
      return { expr, base: expr, path: "", formula: true };
    }
    const why = refusal(expr, this.leaves);
    if (why !== null) {
      setText(this.error, why);
      return null;
    }
    const base = this.baseOf(expr);
    return { expr, base, path: expr.slice(base.length), formula: false };
  }

  async add(expr: string): Promise<void> {
    if (expr === "") return;
    const src = this.source(expr);
    if (!src) return;
    const plot = new Plot(src, (p) => void this.remove(p), (p, e) => this.addTo(p, e));
    // Zoom and pan are linked: every plot shows the time range the user chose on one.
    plot.onView = (view) => {
      for (const other of this.plots) {
        // Only plots on the same time: the robot's (live or recorded), or the wall clock.
        if (other === plot || other.isRecording() !== plot.isRecording() || other.onRobotTime() !== plot.onRobotTime()) continue;
        if (view === null) other.goLive(false);
        else other.zoomTo(view.min, view.max, false);
      }
    };
    this.plots.push(plot);
    // The timeline's cycle, if it shows one, drawn once the plot knows its time axis.
    plot.setPlayhead(this.playheadT);
    try {
      await this.watch();
      setText(this.error, "");
      this.list.append(plot.el);
      this.onChange();
      if (this.recording) await this.fill(plot);
      // Another signal may have been typed while the server answered: keep it.
      if (this.input.value.trim() === expr) this.input.value = "";
    } catch (e) {
      // Other adds may have been pushed meanwhile: remove this one, not the last.
      const i = this.plots.indexOf(plot);
      if (i >= 0) this.plots.splice(i, 1);
      plot.destroy();
      await this.watch().catch(() => undefined);
      setText(this.error, errorText(e));
    }
  }

  /** Another signal on an existing plot (refused like a new plot's when the server does not know it). */
  private async addTo(plot: Plot, expr: string): Promise<void> {
    if (plot.has(expr)) return;
    const src = this.source(expr);
    if (!src) return;
    plot.addSource(src);
    try {
      await this.watch();
      setText(this.error, "");
      this.onChange();
      if (this.recording) await this.fill(plot);
    } catch (e) {
      plot.removeSource(expr);
      await this.watch().catch(() => undefined);
      setText(this.error, errorText(e));
    }
  }

  private async remove(p: Plot): Promise<void> {
    const i = this.plots.indexOf(p);
    if (i >= 0) this.plots.splice(i, 1);
    p.el.remove();
    p.destroy();
    this.onChange();
    await this.watch().catch(() => undefined);
  }

  /** The plots shown, each its expressions in order (the page's layout). */
  layout(): string[][] {
    return this.plots.map((p) => p.sources.map((s) => s.expr));
  }

  /** Shows the plots of a layout (after those shown: each plot's first expression makes it, the
   *  others are added to it); one the robot cannot have is refused as when typed. */
  async restore(groups: string[][]): Promise<void> {
    for (const group of groups) {
      const [first, ...rest] = group;
      if (first === undefined) continue;
      await this.add(first);
      const plot = this.plots.find((p) => p.sources[0]?.expr === first);
      if (!plot) continue;
      for (const expr of rest) await this.addTo(plot, expr);
    }
  }

  /** Tells the server which signals this tab needs (after a reconnection too). */
  async watch(): Promise<void> {
    await this.conn.request("watch", watched(this.plots.flatMap((p) => p.sources)));
  }

  /** The robot is a replay: every plot shows the whole recording on the robot's time (asked
   *  again with `refill` when the timeline grows). */
  setRecording(): void {
    this.recording = true;
    this.el.dataset["recording"] = "";
    const help = this.el.querySelector(".plot-help");
    if (help) setText(help, "a replay: each plot shows the whole recording on the robot's time, the line at the timeline's cycle; drag across a plot: zoom; ◀ ▶ or Shift + wheel: pan; double-click or All: the whole recording");
    this.refill();
  }

  /** Asks for every plot's series again (the timeline holds more cycles). */
  refill(): void {
    if (!this.recording) return;
    for (const p of this.plots) void this.fill(p).catch((e: unknown) => setText(this.error, errorText(e)));
  }

  private async fill(p: Plot): Promise<void> {
    const { signals, formulas } = watched(p.sources);
    // Only the latest ask counts: an earlier one answered later (a plot's first signal, then a
    // second added before the first reply) would put back a series without the new signal.
    const ask = ++p.fills;
    const series = await this.conn.request("history_series", { signals, formulas, max_points: 2000 });
    if (!isObject(series) || !this.plots.includes(p) || ask !== p.fills) return;
    p.setSeries(series);
    p.setPlayhead(this.playheadT);
  }

  /** The timeline's cycle shown, at robot time `t` (null: live), on every plot of the robot's time. */
  playhead(t: number | null): void {
    this.playheadT = t;
    for (const p of this.plots) p.setPlayhead(t);
  }

  /** A new run: every plot starts again empty. */
  clear(): void {
    for (const p of this.plots) p.clear();
  }

  update(wall: number, signals: Json | undefined, at: SampleAt | null = null): void {
    if (!isObject(signals) || this.recording) return;
    for (const p of this.plots) p.add(wall, signals, at);
  }
}
