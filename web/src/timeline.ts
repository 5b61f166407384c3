// The timeline: a bar under the page over the robot's recent past, kept by the server (`history`,
// `history_frame`). Live, the panels follow the robot's telemetry; paused, the panels that follow
// the timeline (skills and resources, the world view) show the selected cycle: step one cycle,
// drag the slider, play at 0.25×, 1× or 4×, or click an event's mark to jump to its cycle.

import { Connection, isObject, RefusedError, type Json, type JsonObject } from "./conn";
import { errorText, h, linkControl, num, setText, str } from "./dom";

/** What the timeline drives: the panels that follow it. */
export interface PastView {
  /** Show this `history_frame` reply (the state at one cycle). */
  show(frame: JsonObject): void;
  /** Back to the live telemetry. */
  live(): void;
  /** The span held changed (a replay's timeline fills as the history takes the replayed cycles). */
  span?(first: number, last: number): void;
}

interface Mark {
  cycle: number;
  kind: string;
  text: string;
}

interface Span {
  first: number;
  last: number;
  firstT: number;
  lastT: number;
}

const SPEEDS = [0.25, 1, 4, 16, 64];
/** How often the span and the marks are asked for (ms). */
const REFRESH_MS = 1000;
/** Marks closer than this share one button (a fraction of the bar). */
const MARK_BUCKET = 0.005;

export class Timeline {
  readonly el: HTMLElement;
  private readonly liveBtn: HTMLButtonElement;
  private readonly back: HTMLButtonElement;
  private readonly forward: HTMLButtonElement;
  private readonly play: HTMLButtonElement;
  private readonly speed: HTMLSelectElement;
  private readonly slider: HTMLInputElement;
  private readonly marksEl: HTMLElement;
  private readonly cycleEl: HTMLElement;
  private readonly timeEl: HTMLElement;
  private readonly spanEl: HTMLElement;
  private readonly prints: HTMLElement;
  private readonly note: HTMLElement;
  private paused = false;
  private span: Span | null = null;
  private marks: Mark[] = [];
  private marksKey = "";
  /** The sequencer's phases (`phase` marks), drawn on the mission lane, not as marks. */
  private phases: Mark[] = [];
  private laneKey = "";
  private readonly lane: HTMLElement;
  private readonly phaseEl: HTMLElement;
  /** The cycle asked for while paused (the one shown is in the bar's `data-shown`). */
  private selected = 0;
  private inFlight = false;
  private wanted: number | null = null;
  /** Bumped on every change of mode: a reply for an older mode is dropped. */
  private epoch = 0;
  private playTimer: number | null = null;
  private playPos = 0;
  private playLast = 0;
  private refreshTimer: number | null = null;
  private available = true;
  /** Whether the link to the robot (the page's WebSocket) is up. */
  private linkUp = false;
  private everUp = false;
  /** The manager's period (s), from its stats: how many cycles a second of playing covers. */
  private periodS = 0.05;
  /** A cycle to show once the timeline holds it (a layout's), or null. */
  private pendingCycle: number | null = null;
  /** Called when the cycle shown changes, or the bar goes live (the page's layout is saved). */
  onChange: () => void = () => {};
  /** The recording, when the robot is a replay: the bar only ever shows its past. */
  private replayOf: string | null = null;
  private readonly replayEl: HTMLElement;

  constructor(
    private readonly conn: Connection,
    private readonly view: PastView,
  ) {
    this.liveBtn = linkControl(h("button", { class: "tl-live", "data-testid": "tl-live", title: "pause: look back at the robot's recent past" }, "● Live"));
    this.liveBtn.addEventListener("click", () => void (this.paused ? this.goLive() : this.pause()));
    this.back = linkControl(h("button", { "data-testid": "tl-back", title: "one cycle back (key ←)" }, "◀ 1"));
    this.back.addEventListener("click", () => void this.step(-1));
    this.forward = linkControl(h("button", { "data-testid": "tl-forward", title: "one cycle forward (key →)" }, "1 ▶"));
    this.forward.addEventListener("click", () => void this.step(1));
    this.play = linkControl(h("button", { "data-testid": "tl-play", title: "play the past at the chosen speed" }, "▶ Play"));
    this.play.addEventListener("click", () => this.togglePlaying());
    this.speed = h("select", { "data-testid": "tl-speed", title: "playing speed" }, ...SPEEDS.map((s) => h("option", { value: String(s) }, `${s}×`)));
    this.speed.value = "1";
    this.slider = linkControl(h("input", { type: "range", min: 0, max: 0, step: 1, value: 0, class: "tl-slider", "data-testid": "tl-slider", "aria-label": "cycle" }));
    this.slider.addEventListener("input", () => void this.drag(Number(this.slider.value)));
    this.marksEl = h("div", { class: "tl-marks", "data-testid": "tl-marks" });
    this.cycleEl = h("span", { class: "mono", "data-testid": "tl-cycle" }, "cycle —");
    this.timeEl = h("span", { class: "mono", "data-testid": "tl-time" }, "");
    this.spanEl = h("span", { class: "dim", "data-testid": "tl-span" }, "");
    this.prints = h("div", { class: "tl-prints mono", "data-testid": "tl-prints" });
    this.note = h("span", { class: "tl-note", "data-testid": "tl-note" });
    this.replayEl = h("span", { class: "tl-replay", "data-testid": "tl-replay", hidden: true });
    this.lane = h("div", { class: "tl-lane", "data-testid": "tl-lane", title: "the mission: the phases the sequencer said (robot.phase)" });
    this.phaseEl = h("span", { class: "tl-phase", "data-testid": "tl-phase" });
    this.el = h(
      "footer",
      { class: "timeline", "data-testid": "timeline", "data-mode": "live", "data-link": "down" },
      h("div", { class: "row" }, this.replayEl, this.liveBtn, this.back, this.forward, this.play, this.speed, this.cycleEl, this.timeEl, this.spanEl, this.phaseEl, this.note),
      h("div", { class: "tl-track" }, this.slider, this.marksEl),
      this.lane,
      this.prints,
    );
    this.setButtons();
    document.addEventListener("keydown", (e) => this.onKey(e));
  }

  /** Keys, outside form fields: P pauses or goes live, ← and → step one cycle. */
  private onKey(e: KeyboardEvent): void {
    if (e.ctrlKey || e.metaKey || e.altKey || e.defaultPrevented) return;
    const t = e.target;
    if (t instanceof HTMLInputElement || t instanceof HTMLTextAreaElement || t instanceof HTMLSelectElement) return;
    if (t instanceof HTMLElement && t.isContentEditable) return;
    if (!this.available || this.liveBtn.disabled) return;
    if (e.key === "p" || e.key === "P") {
      e.preventDefault();
      if (this.replayOf !== null) this.togglePlaying();
      else void (this.paused ? this.goLive() : this.pause());
    } else if (e.key === "ArrowLeft" || e.key === "ArrowRight") {
      e.preventDefault();
      void this.step(e.key === "ArrowLeft" ? -1 : 1);
    }
  }

  /** The connection is (again) up: follow the server's history. */
  start(): void {
    if (this.refreshTimer === null) this.refreshTimer = window.setInterval(() => void this.refresh(), REFRESH_MS);
    void this.refresh();
  }

  /** The link to the robot went down (the page reconnects by itself) or came up again: the bar
   *  never says "Live" while nothing live comes. */
  setConnected(up: boolean): void {
    if (up === this.linkUp) return;
    this.linkUp = up;
    if (up) this.everUp = true;
    else this.stopPlaying();
    this.setButtons();
  }

  /** A new run (the robot restarted): its past is not the old one's. */
  reset(): void {
    this.stopPlaying();
    this.span = null;
    this.marks = [];
    this.marksKey = "";
    this.marksEl.replaceChildren();
    this.available = true;
    if (this.paused) this.goLive();
    void this.refresh();
  }

  /** The robot is a replay of `file`: the bar shows only the recording (there is nothing live),
   *  from its first cycle; Play plays it to its end. */
  setReplay(file: string): void {
    this.replayOf = file;
    this.el.dataset["replay"] = file;
    setText(this.replayEl, `Replay of ${file}`);
    this.replayEl.title = "the timeline holds the recording's cycles as replayed; nothing here is live";
    this.replayEl.hidden = false;
    this.liveBtn.hidden = true;
    this.setButtons();
    void this.refresh();
  }

  /** What the manager panel's Run, Stop and Step do in a replay. */
  readonly player = {
    play: (): void => this.startPlaying(),
    stop: (): void => this.stopPlaying(),
    step: (cycles: number): void => void this.step(cycles),
  };

  private togglePlaying(): void {
    if (this.playTimer === null) this.startPlaying();
    else this.stopPlaying();
  }

  /** The cycle shown while paused, or null while live (the page's layout). */
  shownCycle(): number | null {
    const shown = this.el.dataset["shown"];
    return this.paused && shown !== undefined ? Number(shown) : null;
  }

  /** Shows `cycle` once the timeline holds it (a layout's, restored as the page opens). */
  seekWhenHeld(cycle: number): void {
    this.pendingCycle = cycle;
    void this.refresh();
  }

  /** Whether the panels that follow the timeline show the past. */
  isPaused(): boolean {
    return this.paused;
  }

  /** A live sample's cycle and time, shown while live. */
  liveAt(cycle: number, timeS: number, periodS: number): void {
    if (periodS > 0) this.periodS = periodS;
    if (this.paused) return;
    setText(this.cycleEl, `cycle ${cycle}`);
    setText(this.timeEl, `t = ${timeS.toFixed(2)} s`);
  }

  private setButtons(): void {
    this.el.dataset["mode"] = this.paused ? "paused" : "live";
    this.el.dataset["link"] = this.linkUp ? "up" : "down";
    if (!this.linkUp) {
      setText(this.liveBtn, this.everUp ? "○ Disconnected" : "○ Connecting…");
      this.liveBtn.title = "not connected to the robot: nothing shown is live (the page reconnects by itself)";
    } else {
      setText(this.liveBtn, this.paused ? "❚❚ Paused" : "● Live");
      this.liveBtn.title = this.paused ? "go live: back to the robot's telemetry (key P)" : "pause: look back at the robot's recent past (key P)";
    }
    this.liveBtn.classList.toggle("disconnected", !this.linkUp);
    this.liveBtn.classList.toggle("paused", this.paused && this.linkUp);
    document.body.classList.toggle("past", this.paused);
    setText(this.play, this.playTimer === null ? "▶ Play" : "■ Stop");
  }

  private async refresh(): Promise<void> {
    let reply: Json;
    try {
      reply = await this.conn.request("history");
    } catch (e) {
      if (e instanceof RefusedError && e.kind === "unavailable") {
        this.available = false;
        setText(this.note, errorText(e));
        this.el.classList.add("unavailable");
      }
      return;
    }
    if (!isObject(reply)) return;
    this.available = true;
    this.el.classList.remove("unavailable");
    if (typeof reply["first_cycle"] !== "number" || typeof reply["last_cycle"] !== "number") {
      setText(this.spanEl, "no cycle recorded yet");
      return;
    }
    const before = this.span;
    this.span = { first: num(reply["first_cycle"]), last: num(reply["last_cycle"]), firstT: num(reply["first_time_s"]), lastT: num(reply["last_time_s"]) };
    if (before?.first !== this.span.first || before.last !== this.span.last) this.view.span?.(this.span.first, this.span.last);
    const dropped = num(reply["dropped"]);
    setText(this.spanEl, `holds cycles ${this.span.first}–${this.span.last}${dropped > 0 ? ` (${dropped} lost)` : ""}`);
    this.slider.min = String(this.span.first);
    this.slider.max = String(this.span.last);
    const pending = this.pendingCycle;
    if (pending !== null && pending >= this.span.first && pending <= this.span.last) {
      this.pendingCycle = null;
      void this.jump(pending);
    } else if (pending !== null && !this.paused && this.replayOf === null) {
      // Not held (any more): said, and the bar stays live.
      this.pendingCycle = null;
      setText(this.note, `cycle ${pending} is not on the timeline (it holds ${this.span.first}–${this.span.last})`);
    } else if (this.replayOf !== null && !this.paused) {
      // A replay opens at the recording's first cycle, ready to play.
      this.enterPaused();
      this.selected = this.span.first;
      void this.seek(this.span.first);
    } else if (!this.paused) this.slider.value = String(this.span.last);
    else if (this.selected < this.span.first) void this.seek(this.span.first);
    const all = (Array.isArray(reply["marks"]) ? reply["marks"] : []).filter(isObject).map((m) => ({ cycle: num(m["cycle"]), kind: str(m["kind"]), text: str(m["text"]) }));
    this.marks = all.filter((m) => m.kind !== "phase");
    this.phases = all.filter((m) => m.kind === "phase");
    this.drawMarks();
    this.drawLane();
    if (!this.paused) this.showPhase(this.span.last);
  }

  /** One button per group of nearby marks, placed along the slider (moved, not made again, while
   *  the groups stay the same: a mark under the pointer stays clickable). */
  private drawMarks(): void {
    const span = this.span;
    if (!span) return;
    const width = Math.max(1, span.last - span.first);
    const groups: Mark[][] = [];
    let bucket = -1;
    for (const m of this.marks) {
      if (m.cycle < span.first || m.cycle > span.last) continue;
      const b = Math.floor((m.cycle - span.first) / width / MARK_BUCKET);
      const group = groups.at(-1);
      if (b === bucket && group) group.push(m);
      else groups.push([m]);
      bucket = b;
    }
    const left = (cycle: number) => `${((cycle - span.first) / width) * 100}%`;
    const key = groups.map((g) => g.map((m) => `${m.cycle}:${m.kind}`).join(",")).join(";");
    if (key === this.marksKey) {
      groups.forEach((g, i) => {
        const el = this.marksEl.children.item(i);
        if (el instanceof HTMLElement) el.style.left = left((g[0] as Mark).cycle);
      });
      return;
    }
    this.marksKey = key;
    this.marksEl.replaceChildren(
      ...groups.map((g) => {
        const first = g[0] as Mark;
        const title = g.map((m) => `cycle ${m.cycle}: ${m.text}`).join("\n");
        const b = h("button", {
          class: `tl-mark tl-${first.kind}`,
          "data-testid": "tl-mark",
          "data-cycle": first.cycle,
          "data-kind": first.kind,
          "data-text": g.map((m) => m.text).join("; "),
          title,
          "aria-label": title,
        });
        b.style.left = left(first.cycle);
        b.addEventListener("click", () => void this.jump(first.cycle));
        return b;
      }),
    );
  }

  /** The mission lane: each phase the sequencer said, from its cycle to the next phase's (or the
   *  span's end), labelled; clicking one shows its first cycle. */
  private drawLane(): void {
    const span = this.span;
    if (!span) return;
    const width = Math.max(1, span.last - span.first);
    const pct = (cycle: number) => ((Math.min(span.last, Math.max(span.first, cycle)) - span.first) / width) * 100;
    const segments = this.phases
      .map((p, i) => ({ p, end: this.phases[i + 1]?.cycle ?? span.last + 1 }))
      .filter(({ p, end }) => end > span.first && p.cycle <= span.last);
    this.lane.hidden = segments.length === 0;
    const place = (b: HTMLElement, cycle: number, end: number) => {
      const left = pct(cycle);
      b.style.left = `${left}%`;
      b.style.width = `${Math.max(0.3, pct(end) - left)}%`;
    };
    // The span grows every refresh on a live run: the segments are moved in place then, and built
    // again only when the phases shown change (a button rebuilt between a click's press and its
    // release loses the click).
    const key = JSON.stringify(segments.map(({ p }) => [p.cycle, p.text]));
    if (key === this.laneKey) {
      segments.forEach(({ p, end }, i) => {
        const el = this.lane.children.item(i);
        if (el instanceof HTMLElement) place(el, p.cycle, end);
      });
      return;
    }
    this.laneKey = key;
    this.lane.replaceChildren(
      ...segments.map(({ p, end }) => {
        const title = `cycle ${p.cycle}: ${p.text}`;
        const b = h("button", { class: "tl-seg", "data-testid": "tl-phase-seg", "data-cycle": p.cycle, "data-text": p.text, title, "aria-label": title }, p.text);
        place(b, p.cycle, end);
        b.addEventListener("click", () => void this.jump(Math.max(this.span?.first ?? p.cycle, p.cycle)));
        return b;
      }),
    );
  }

  /** The phase the mission was in at `cycle`, on the bar. */
  private showPhase(cycle: number): void {
    let at: Mark | undefined;
    for (const p of this.phases) if (p.cycle <= cycle) at = p;
    setText(this.phaseEl, at ? `mission: ${at.text}` : "");
    this.phaseEl.title = at ? `since cycle ${at.cycle}` : "";
  }

  /** Pauses at the newest cycle held. */
  async pause(): Promise<void> {
    if (this.paused) return;
    await this.refresh();
    if (!this.available || !this.span) {
      if (this.available) setText(this.note, "nothing recorded yet");
      return;
    }
    this.enterPaused();
    await this.seek(this.span.last);
  }

  private enterPaused(): void {
    if (this.paused) return;
    this.paused = true;
    this.epoch++;
    this.selected = this.span?.last ?? 0;
    setText(this.note, "");
    this.setButtons();
  }

  /** Back to live telemetry (never in a replay: there is none). */
  goLive(): void {
    this.stopPlaying();
    if (this.replayOf !== null) return;
    this.paused = false;
    this.epoch++;
    this.wanted = null;
    delete this.el.dataset["shown"];
    setText(this.prints, "");
    setText(this.note, "");
    if (this.span) this.slider.value = String(this.span.last);
    this.setButtons();
    this.view.live();
    this.onChange();
  }

  private async step(d: number): Promise<void> {
    this.stopPlaying();
    if (!this.paused) await this.pause();
    if (!this.paused) return;
    await this.seek((this.wanted ?? this.selected) + d);
  }

  private async drag(cycle: number): Promise<void> {
    this.stopPlaying();
    if (!this.paused) {
      if (!this.span) return;
      this.enterPaused();
    }
    await this.seek(cycle);
  }

  private async jump(cycle: number): Promise<void> {
    this.stopPlaying();
    if (!this.paused) {
      await this.refresh();
      if (!this.span) return;
      this.enterPaused();
    }
    await this.seek(cycle);
  }

  /** Shows `cycle` (clamped to the span held); one request at a time, the latest asked wins. */
  private async seek(cycle: number): Promise<void> {
    const span = this.span;
    if (!span || !this.paused) return;
    const c = Math.min(span.last, Math.max(span.first, Math.round(cycle)));
    this.selected = c;
    this.slider.value = String(c);
    this.wanted = c;
    if (this.inFlight) return;
    this.inFlight = true;
    try {
      while (this.wanted !== null && this.paused) {
        const want: number = this.wanted;
        this.wanted = null;
        const epoch = this.epoch;
        try {
          const frame = await this.conn.request("history_frame", { cycle: want });
          if (epoch !== this.epoch || !this.paused || !isObject(frame)) continue;
          this.showFrame(frame);
        } catch (e) {
          setText(this.note, errorText(e));
          // The window moved on: ask for the span again.
          await this.refresh();
        }
      }
    } finally {
      this.inFlight = false;
    }
  }

  private showFrame(frame: JsonObject): void {
    const cycle = num(frame["cycle"]);
    this.el.dataset["shown"] = String(cycle);
    setText(this.cycleEl, `cycle ${cycle}${frame["exact"] === false ? " (no frame: the last before it)" : ""}`);
    setText(this.timeEl, `t = ${num(frame["time_s"]).toFixed(2)} s`);
    this.showPhase(cycle);
    this.onChange();
    const prints = (Array.isArray(frame["prints"]) ? frame["prints"] : []).filter(isObject);
    setText(this.prints, prints.length === 0 ? "" : `prints of cycle ${cycle}: ${prints.map((p) => `${str(p["skill"])}: ${str(p["line"])}`).join(" · ")}`);
    setText(this.note, "");
    this.view.show(frame);
  }

  private startPlaying(): void {
    if (this.playTimer !== null) return;
    const begin = () => {
      const span = this.span;
      if (!span) return;
      // From the start of the window when playing from its end.
      this.playPos = this.selected >= span.last ? span.first : this.selected;
      this.playLast = performance.now();
      this.playTimer = window.setInterval(() => this.tick(), 100);
      this.setButtons();
      void this.seek(this.playPos);
    };
    if (!this.paused) void this.pause().then(begin);
    else begin();
  }

  private tick(): void {
    const span = this.span;
    if (!span || !this.paused) {
      this.stopPlaying();
      return;
    }
    const now = performance.now();
    const dt = (now - this.playLast) / 1000;
    this.playLast = now;
    this.playPos += (Number(this.speed.value) * dt) / Math.max(1e-4, this.periodS);
    if (this.playPos >= span.last) {
      this.playPos = span.last;
      this.stopPlaying();
    }
    void this.seek(this.playPos);
  }

  private stopPlaying(): void {
    if (this.playTimer !== null) window.clearInterval(this.playTimer);
    this.playTimer = null;
    this.setButtons();
  }
}

/** The live skills' info with what a past frame says of them (activation, fault, parameters,
 *  ports' values); what the frame does not hold (timing, priority, verbosity) is left out or live. */
export function skillsAt(live: JsonObject[], frame: JsonObject): JsonObject[] {
  const past = new Map((Array.isArray(frame["skills"]) ? frame["skills"] : []).filter(isObject).map((s) => [str(s["name"]), s]));
  const byName = (list: Json | undefined) => new Map((Array.isArray(list) ? list : []).filter(isObject).map((x) => [str(x["name"]), x]));
  return live.map((s) => {
    const p = past.get(str(s["name"]));
    if (!p) return s;
    const params = byName(p["params"]);
    const overlay = (key: string) => {
      const ports = byName(p[key]);
      return (Array.isArray(s[key]) ? s[key] : []).filter(isObject).map((x) => ({ ...x, value: ports.get(str(x["name"]))?.["value"] ?? null }));
    };
    const copy: JsonObject = {
      ...s,
      active: p["active"] ?? null,
      // What the activation button acts on: the skill now, not at the cycle shown.
      live_active: s["active"] === true,
      faulted: p["faulted"] ?? null,
      params: (Array.isArray(s["params"]) ? s["params"] : []).filter(isObject).map((x) => ({ ...x, value: params.get(str(x["name"]))?.["value"] ?? x["value"] ?? null })),
      inputs: overlay("inputs"),
      outputs: overlay("outputs"),
    };
    delete copy["timing"];
    return copy;
  });
}
