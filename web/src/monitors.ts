// Monitors (paper: conditions the manager watches each cycle) and the event log.
// A monitor added with "pause the cycle" stops the cycle at the end of the cycle it fires in, as a
// sequencer's `pause` monitor does over the link; the panel then says which monitor paused it and
// offers Resume (the link's `run`).

import { Connection, isObject, RefusedError, type Json, type JsonObject } from "./conn";
import { errorText, h, linkControl, num, robotControl, setText, show, str } from "./dom";

const EVENT_LINES = 300;
/** How often the monitor list is asked for again. */
const MONITOR_REFRESH_MS = 2000;

export class Monitors {
  readonly el: HTMLElement;
  private readonly list: HTMLElement;
  private readonly error: HTMLElement;
  private readonly paused: HTMLElement;
  /** The monitors that pause the cycle, with their conditions (a `once` one leaves the list when it fires). */
  private readonly pausing = new Map<number, string>();
  /** The monitors fired since the cycle last started (their events may come before `monitor_add`'s reply). */
  private fired: { monitor: number; condition: string; cycle: number }[] = [];
  /** Whether the cycle stopped (`manager_stopped`) since it last started. */
  private stopped = false;
  /** This tab's session (from the hello): the monitors it adds are its own. */
  private session = "";

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
        if (pause.checked && isObject(reply)) this.pausing.set(num(reply["monitor"]), cond.value);
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
    this.list.replaceChildren();
  }

  async refresh(): Promise<void> {
    let list: Json;
    try {
      list = await this.conn.request("monitor_list");
    } catch {
      return;
    }
    const rows = (Array.isArray(list) ? list : []).filter(isObject).map((m) => {
      const id = num(m["monitor"]);
      if (m["pause"] === true && !this.pausing.has(id)) {
        this.pausing.set(id, str(m["condition"]));
        this.check();
      }
      const owner = this.owner(m);
      const mine = owner === "this tab";
      const cancel = linkControl(h("button", { title: mine ? "cancel this tab's monitor" : `cancel ${owner}'s monitor (asks first)` }, "Cancel"));
      cancel.addEventListener("click", async () => {
        // Another session's monitor: its sequencer may be waiting on it. Ask, then tell the
        // manager the user confirmed (`force`); the owner gets a `monitor_cancelled` event.
        if (!mine && !window.confirm(`Monitor ${id} belongs to ${owner}, which may be waiting for it to fire. Cancel it anyway? (${owner} is told.)`)) return;
        try {
          await this.conn.request("monitor_cancel", mine ? { monitor: id } : { monitor: id, force: true });
          await this.refresh();
        } catch (e) {
          setText(this.error, errorText(e));
        }
      });
      return h(
        "tr",
        { "data-monitor": id },
        h("td", {}, String(id)),
        h("td", { "data-testid": `monitor-owner-${id}` }, owner),
        h("td", { class: "mono" }, str(m["condition"])),
        h("td", {}, str(m["mode"])),
        h("td", {}, m["pause"] === true ? "pauses" : ""),
        h("td", {}, `fired ${num(m["fired"])}`),
        h("td", {}, m["holds"] === true ? "holds" : ""),
        h("td", {}, cancel),
      );
    });
    this.list.replaceChildren(h("tr", {}, h("th", {}, "id"), h("th", {}, "owner"), h("th", {}, "condition"), h("th", {}, "mode"), h("th", {}, ""), h("th", {}, ""), h("th", {}, ""), h("th", {}, "")), ...rows);
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
    if (!f) {
      this.paused.hidden = true;
      this.paused.replaceChildren();
      return;
    }
    const resume = robotControl(h("button", { "data-testid": "monitor-resume" }, "Resume"));
    resume.addEventListener("click", async () => {
      try {
        await this.conn.request("run");
        setText(this.error, "");
      } catch (e) {
        setText(this.error, errorText(e));
      }
    });
    this.paused.replaceChildren(h("strong", {}, `The cycle is paused by monitor ${f.monitor}`), ` (${f.condition}, fired at cycle ${f.cycle}) `, resume);
    this.paused.hidden = false;
  }
}

export class EventLog {
  readonly el: HTMLElement;
  private readonly list: HTMLElement;
  private readonly prints: HTMLInputElement;

  constructor() {
    this.prints = h("input", { type: "checkbox", checked: true });
    this.list = h("div", { class: "log events", "data-testid": "event-log" });
    this.el = h("section", { class: "panel", id: "events" }, h("h2", {}, "Events"), h("label", {}, this.prints, " show prints"), this.list);
  }

  add(e: JsonObject): void {
    const kind = str(e["kind"]);
    if (kind === "print" && !this.prints.checked) return;
    const rest: JsonObject = { ...e };
    delete rest["kind"];
    delete rest["cycle"];
    const line = h("div", { class: `logline ev-${kind}`, "data-kind": kind }, h("span", { class: "dim" }, `cycle ${num(e["cycle"])} `), h("strong", {}, kind), ` ${show(rest, 300)}`);
    this.list.prepend(line);
    this.trim();
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

  private trim(): void {
    while (this.list.childElementCount > EVENT_LINES) this.list.lastElementChild?.remove();
  }
}
