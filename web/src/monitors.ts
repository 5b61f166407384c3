// Monitors (paper: conditions the manager watches each cycle) and the event log.
// A monitor added with "pause the cycle" stops the cycle at the end of the cycle it fires in, as a
// sequencer's `pause` monitor does over the link; the panel then says which monitor paused it and
// offers Resume (the link's `run`).

import { Connection, isObject, RefusedError, type Json, type JsonObject } from "./conn";
import { errorText, h, linkControl, num, robotControl, setText, show, str } from "./dom";

const EVENT_LINES = 300;
/** How long another session's pause must last before the panel shows it (ms). */
const SEQUENCER_PAUSE_MS = 1500;
/** How often the monitor list is asked for again. */
const MONITOR_REFRESH_MS = 2000;

/** One listed monitor: its row, its cells (id, owner, condition, mode, pause, fired, holds) and
 *  its owner as the last list named it. */
interface MonitorRow {
  tr: HTMLElement;
  cells: HTMLElement[];
  cancel: HTMLButtonElement;
  owner: string;
}

export class Monitors {
  readonly el: HTMLElement;
  private readonly list: HTMLElement;
  private readonly error: HTMLElement;
  private readonly paused: HTMLElement;
  /** The monitors that pause the cycle, with their conditions and owners (a `once` one leaves
   *  the list when it fires). */
  private readonly pausing = new Map<number, { condition: string; owner: string }>();
  /** A pause by another session's monitor is shown only once it has lasted this long: a
   *  sequencer pauses the cycle to act between two cycles and runs it again itself. */
  private pauseTimer: number | null = null;
  /** The monitors fired since the cycle last started (their events may come before `monitor_add`'s reply). */
  private fired: { monitor: number; condition: string; cycle: number }[] = [];
  /** Whether the cycle stopped (`manager_stopped`) since it last started. */
  private stopped = false;
  /** This tab's session (from the hello): the monitors it adds are its own. */
  private session = "";
  /** The listed monitors' rows, by id. */
  private readonly rows = new Map<number, MonitorRow>();
  private readonly header = h("tr", {}, h("th", {}, "id"), h("th", {}, "owner"), h("th", {}, "condition"), h("th", {}, "mode"), h("th", {}, ""), h("th", {}, ""), h("th", {}, ""), h("th", {}, ""));

  constructor(
    private readonly conn: Connection,
    stale: HTMLElement,
  ) {
    const cond = h("input", { type: "text", class: "wide", placeholder: "condition, e.g. sonar.range[0] < 0.3", "data-testid": "monitor-condition" });
    const mode = h("select", { "data-testid": "monitor-mode" }, h("option", { value: "once" }, "once"), h("option", { value: "edge" }, "edge"), h("option", { value: "level" }, "level"));
    const pause = h("input", { type: "checkbox", "data-testid": "monitor-pause" });
    const add = robotControl(h("button", { "data-testid": "monitor-add" }, "Add monitor"));
    add.addEventListener("click", async () => {
      try {
        const reply = await this.conn.request("monitor_add", { condition: cond.value, mode: mode.value, pause: pause.checked });
        if (pause.checked && isObject(reply)) this.pausing.set(num(reply["monitor"]), { condition: cond.value, owner: "this tab" });
        this.check();
        setText(this.error, "");
        cond.value = "";
        await this.refresh();
      } catch (e) {
        setText(this.error, e instanceof RefusedError && e.pointer ? `${e.message}\n${e.pointer}` : errorText(e));
      }
    });
    this.error = h("pre", { class: "error", "data-testid": "monitor-error" });
    this.list = h("table", { class: "monitors", "data-testid": "monitors" });
    this.paused = h("div", { class: "row", hidden: true, "data-testid": "monitor-paused" });
    this.el = h(
      "section",
      { class: "panel live", id: "monitors" },
      h("h2", {}, "Monitors", stale),
      h("div", { class: "row" }, cond, mode, h("label", { title: "stop the cycle at the end of the cycle it fires in" }, pause, " pause the cycle"), add),
      this.error,
      this.paused,
      this.list,
    );
    // Monitors come and go without events of their own (a sequencer's added, a session ended):
    // the list is asked for again every few seconds while the page is shown.
    window.setInterval(() => {
      if (document.visibilityState === "visible") void this.refresh();
    }, MONITOR_REFRESH_MS);
  }

  /** This tab's session, as the hello names it. */
  setSession(session: string): void {
    this.session = session;
  }

  /** Who holds a monitor, for a person: this tab, the robot's program, or a client's name. */
  private owner(m: JsonObject): string {
    const session = m["session"];
    if (typeof session !== "string") return "the robot's program";
    if (session === this.session) return "this tab";
    const client = m["client"];
    return typeof client === "string" && client !== "" ? client : `session ${session.slice(0, 8)}`;
  }

  /** A new run: its monitors are its own. */
  clear(): void {
    this.pausing.clear();
    this.fired = [];
    this.stopped = false;
    this.showPaused(null);
    this.rows.clear();
    this.list.replaceChildren();
  }

  async refresh(): Promise<void> {
    let list: Json;
    try {
      list = await this.conn.request("monitor_list");
    } catch {
      return;
    }
    const monitors = (Array.isArray(list) ? list : []).filter(isObject);
    const listed = new Set<number>();
    const order: HTMLElement[] = [this.header];
    for (const m of monitors) {
      const id = num(m["monitor"]);
      const owner = this.owner(m);
      if (m["pause"] === true && !this.pausing.has(id)) {
        this.pausing.set(id, { condition: str(m["condition"]), owner });
        this.check();
      }
      const row = this.rows.get(id) ?? this.row(id);
      row.owner = owner;
      const cells = [String(id), owner, str(m["condition"]), str(m["mode"]), m["pause"] === true ? "pauses" : "", `fired ${num(m["fired"])}`, m["holds"] === true ? "holds" : ""];
      cells.forEach((text, i) => setText(row.cells[i]!, text));
      row.cancel.title = owner === "this tab" ? "cancel this tab's monitor" : `cancel ${owner}'s monitor (asks first)`;
      listed.add(id);
      order.push(row.tr);
    }
    for (const [id, row] of this.rows) {
      if (!listed.has(id)) {
        row.tr.remove();
        this.rows.delete(id);
      }
    }
    // Rows are kept and updated in place, never rebuilt: a list rebuilt between a click's press
    // and its release (every 2 s, and on every firing) loses the click.
    const current = Array.from(this.list.children);
    if (order.length !== current.length || order.some((el, i) => el !== current[i])) this.list.replaceChildren(...order);
  }

  /** A monitor's row; its Cancel reads the owner when clicked, as the last list named it. */
  private row(id: number): MonitorRow {
    const cells = Array.from({ length: 7 }, (_, i) => h("td", i === 1 ? { "data-testid": `monitor-owner-${id}` } : i === 2 ? { class: "mono" } : {}));
    const cancel = linkControl(h("button", {}, "Cancel"));
    const row: MonitorRow = { tr: h("tr", { "data-monitor": id }, ...cells, h("td", {}, cancel)), cells, cancel, owner: "" };
    cancel.addEventListener("click", async () => {
      // Another session's monitor: its sequencer may be waiting on it. Ask, then tell the
      // manager the user confirmed (`force`); the owner gets a `monitor_cancelled` event.
      const owner = row.owner;
      const mine = owner === "this tab";
      if (!mine && !window.confirm(`Monitor ${id} belongs to ${owner}, which may be waiting for it to fire. Cancel it anyway? (${owner} is told.)`)) return;
      try {
        await this.conn.request("monitor_cancel", mine ? { monitor: id } : { monitor: id, force: true });
        await this.refresh();
      } catch (e) {
        setText(this.error, errorText(e));
      }
    });
    this.rows.set(id, row);
    return row;
  }

  event(e: JsonObject): void {
    switch (e["kind"]) {
      case "monitor_fired":
        this.fired.push({ monitor: num(e["monitor"]), condition: str(e["condition"]), cycle: num(e["cycle"]) });
        if (this.fired.length > 100) this.fired.shift();
        void this.refresh();
        break;
      case "monitor_cancelled":
        void this.refresh();
        break;
      case "manager_stopped":
        this.stopped = true;
        this.check();
        break;
      case "manager_started":
        this.fired = [];
        this.stopped = false;
        this.showPaused(null);
        break;
      default:
        break;
    }
  }

  /** Shows which monitor paused the cycle, if one did: the last pausing monitor fired before the stop. */
  private check(): void {
    if (!this.stopped) return;
    const f = [...this.fired].reverse().find((x) => this.pausing.has(x.monitor));
    if (f) this.showPaused(f);
  }

  private showPaused(f: { monitor: number; condition: string; cycle: number } | null): void {
    if (this.pauseTimer !== null) window.clearTimeout(this.pauseTimer);
    this.pauseTimer = null;
    if (!f) {
      this.paused.hidden = true;
      this.paused.replaceChildren();
      return;
    }
    const owner = this.pausing.get(f.monitor)?.owner ?? "this tab";
    if (owner !== "this tab") {
      // Another session's pause (a sequencer's): said only when it lasts, and said as theirs.
      this.pauseTimer = window.setTimeout(() => {
        this.pauseTimer = null;
        if (!this.stopped) return;
        const resume = robotControl(h("button", { "data-testid": "monitor-resume", title: `${owner} runs the cycle again itself; resume only if it seems stuck` }, "Resume anyway"));
        resume.addEventListener("click", () => void this.resume());
        this.paused.replaceChildren(
          h("strong", {}, `The cycle is paused by ${owner}'s monitor ${f.monitor}`),
          ` (${f.condition}, fired at cycle ${f.cycle}): ${owner} stops the cycle to act between two cycles, and runs it again when done. `,
          resume,
        );
        this.paused.dataset["owner"] = owner;
        this.paused.hidden = false;
      }, SEQUENCER_PAUSE_MS);
      return;
    }
    const resume = robotControl(h("button", { "data-testid": "monitor-resume" }, "Resume"));
    resume.addEventListener("click", () => void this.resume());
    this.paused.replaceChildren(h("strong", {}, `The cycle is paused by monitor ${f.monitor}`), ` (${f.condition}, fired at cycle ${f.cycle}) `, resume);
    this.paused.dataset["owner"] = owner;
    this.paused.hidden = false;
  }

  private async resume(): Promise<void> {
    try {
      await this.conn.request("run");
      setText(this.error, "");
    } catch (e) {
      setText(this.error, errorText(e));
    }
  }
}

/** The kinds of event the log's filter offers from the start (others are added as they come). */
const KNOWN_KINDS = ["phase", "activation_applied", "param_changed", "priority_changed", "skill_faulted", "monitor_fired", "monitor_cancelled", "manager_started", "manager_stopped", "worker_failed", "print"];

/** The event log, a console like rqt_console's: every event as it comes (newest first), filtered
 *  by kind (a toggle per kind), by skill and by text; the filter hides lines, it drops none. */
export class EventLog {
  readonly el: HTMLElement;
  private readonly list: HTMLElement;
  private readonly kinds: HTMLElement;
  private readonly kindBoxes = new Map<string, HTMLInputElement>();
  private readonly skill: HTMLSelectElement;
  private readonly text: HTMLInputElement;
  private readonly count: HTMLElement;
  private readonly skills = new Set<string>();

  constructor() {
    this.list = h("div", { class: "log events", "data-testid": "event-log" });
    this.kinds = h("div", { class: "row log-kinds", "data-testid": "event-kinds" });
    this.skill = h("select", { "data-testid": "event-skill", title: "only the events of this skill" }, h("option", { value: "" }, "every skill"));
    this.text = h("input", { type: "search", placeholder: "filter: text in the event", "data-testid": "event-text", class: "wide" });
    this.count = h("span", { class: "dim", "data-testid": "event-count" });
    for (const k of KNOWN_KINDS) this.kindBox(k);
    this.skill.addEventListener("change", () => this.apply());
    this.text.addEventListener("input", () => this.apply());
    this.el = h("section", { class: "panel", id: "events" }, h("h2", {}, "Events"), this.kinds, h("div", { class: "row" }, this.skill, this.text, this.count), this.list);
  }

  /** The toggle of one kind (made when the kind is first seen). */
  private kindBox(kind: string): HTMLInputElement {
    let box = this.kindBoxes.get(kind);
    if (!box) {
      box = h("input", { type: "checkbox", checked: true, "data-testid": `event-kind-${kind}` });
      box.addEventListener("change", () => this.apply());
      this.kindBoxes.set(kind, box);
      this.kinds.append(h("label", { class: "toggle", title: `show ${kind} events` }, box, ` ${kind.replace(/_/g, " ")}`));
    }
    return box;
  }

  add(e: JsonObject): void {
    const kind = str(e["kind"]);
    this.kindBox(kind);
    const skill = typeof e["skill"] === "string" ? e["skill"] : "";
    const skills = [skill, ...(Array.isArray(e["activated"]) ? e["activated"] : []), ...(Array.isArray(e["deactivated"]) ? e["deactivated"] : [])].filter((x): x is string => typeof x === "string" && x !== "");
    for (const s of skills) {
      if (this.skills.has(s)) continue;
      this.skills.add(s);
      this.skill.append(h("option", { value: s }, s));
    }
    const rest: JsonObject = { ...e };
    delete rest["kind"];
    delete rest["cycle"];
    const cycle = typeof e["cycle"] === "number" ? `cycle ${e["cycle"]} ` : "";
    const line = h("div", { class: `logline ev-${kind}`, "data-kind": kind, "data-skills": skills.join(" ") }, h("span", { class: "dim" }, cycle), h("strong", {}, kind), ` ${show(rest, 300)}`);
    this.show(line);
    this.list.prepend(line);
    this.trim();
    this.counted();
  }

  /** A line of the log's own (not an event), e.g. what the lines after it are. */
  note(text: string): void {
    this.list.prepend(h("div", { class: "logline log-note", "data-kind": "note" }, text));
    this.trim();
  }

  /** A new run: the old run's events stay below a separator, greyed out. */
  newRun(text: string): void {
    for (const line of this.list.children) line.classList.add("old-run");
    this.list.prepend(h("div", { class: "logline run-separator", "data-kind": "new_run", "data-testid": "run-separator" }, text));
    this.trim();
  }

  /** Whether a line passes the filter (the log's own lines always do). */
  private passes(line: Element): boolean {
    const kind = line.getAttribute("data-kind") ?? "";
    if (kind === "note" || kind === "new_run") return true;
    if (this.kindBoxes.get(kind)?.checked === false) return false;
    const skill = this.skill.value;
    if (skill !== "" && !(line.getAttribute("data-skills") ?? "").split(" ").includes(skill)) return false;
    const text = this.text.value.trim().toLowerCase();
    return text === "" || (line.textContent ?? "").toLowerCase().includes(text);
  }

  private show(line: HTMLElement): void {
    line.hidden = !this.passes(line);
  }

  private apply(): void {
    for (const line of this.list.children) if (line instanceof HTMLElement) this.show(line);
    this.counted();
  }

  private counted(): void {
    const events = [...this.list.children].filter((l) => !["note", "new_run"].includes(l.getAttribute("data-kind") ?? ""));
    const shown = events.filter((l) => !(l as HTMLElement).hidden).length;
    setText(this.count, shown === events.length ? `${events.length} events` : `showing ${shown} of ${events.length} events`);
  }

  private trim(): void {
    while (this.list.childElementCount > EVENT_LINES) this.list.lastElementChild?.remove();
  }
}
