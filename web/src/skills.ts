// The manager panel (paper: the skill manager window) and one panel per skill (the skill window).

import { Connection, isObject, type Json, type JsonObject } from "./conn";
import { errorText, h, linkControl, num, replayFile, robotControl, setText, show, str } from "./dom";

const LOG_LINES = 200;

function keep(list: HTMLElement, line: string): void {
  list.prepend(h("div", { class: "logline" }, line));
  while (list.childElementCount > LOG_LINES) list.lastElementChild?.remove();
}

/** What Run, Stop and Step drive in a replay: the timeline's playing, not the robot (which ran
 *  the recording to its end). */
export interface Player {
  play(): void;
  stop(): void;
  step(cycles: number): void;
}

export class ManagerPanel {
  readonly el: HTMLElement;
  private player: Player | null = null;
  private readonly runBtn: HTMLButtonElement;
  private readonly stopBtn: HTMLButtonElement;
  private readonly fields = new Map<string, HTMLElement>();
  private readonly switches: HTMLElement;
  private readonly switchMap = new Map<string, HTMLInputElement>();
  private readonly error: HTMLElement;
  private last: { cycle: number; wall: number } | null = null;
  private rate = 0;

  constructor(
    private readonly conn: Connection,
    stale: HTMLElement,
  ) {
    const stepCount = h("input", { type: "number", min: 1, max: 1000000, value: 1, step: 1, "data-testid": "step-count", class: "short" });
    const run = linkControl(h("button", { "data-testid": "run" }, "Run"));
    const stop = linkControl(h("button", { "data-testid": "stop" }, "Stop"));
    this.runBtn = run;
    this.stopBtn = stop;
    const step = linkControl(h("button", { "data-testid": "step" }, "Step"));
    run.addEventListener("click", () => void this.act("run", {}));
    stop.addEventListener("click", () => void this.act("stop", {}));
    step.addEventListener("click", () => {
      const n = Number(stepCount.value);
      if (!Number.isInteger(n) || n < 1) {
        setText(this.error, "the number of cycles to step is a whole number ≥ 1");
        return;
      }
      void this.act("step", { cycles: n });
    });
    const grid = h("dl", { class: "stats" });
    for (const [key, label] of [
      ["state", "state"],
      ["cycle", "cycle"],
      ["rate", "cycle rate"],
      ["period", "period"],
      ["last", "cycle time (last)"],
      ["mean", "cycle time (mean)"],
      ["max", "cycle time (max)"],
      ["overruns", "overruns"],
      ["late", "late starts"],
    ] as const) {
      const dd = h("dd", { "data-testid": `stat-${key}` }, "—");
      this.fields.set(key, dd);
      grid.append(h("dt", {}, label), dd);
    }
    this.switches = h("div", { class: "switches" });
    this.error = h("div", { class: "error", "data-testid": "manager-error" });
    this.el = h(
      "section",
      { class: "panel live", id: "manager" },
      h("h2", {}, "Skill manager", stale),
      h("div", { class: "row" }, run, stop, step, stepCount, "cycles"),
      grid,
      h("h3", {}, "Activation"),
      this.switches,
      this.error,
    );
  }

  /** The robot is a replay: Run plays the recording on the timeline (at its speed) and stops at
   *  its end, Stop stops playing, Step steps the timeline. */
  setReplay(player: Player): void {
    this.player = player;
    setText(this.runBtn, "▶ Play recording");
    this.runBtn.title = "play the recording on the timeline, at the timeline's speed, to its end";
    this.stopBtn.title = "stop playing the recording";
  }

  private async act(verb: string, args: JsonObject): Promise<void> {
    const player = this.player;
    if (player) {
      if (verb === "run") player.play();
      else if (verb === "stop") player.stop();
      else if (verb === "step") player.step(num(args["cycles"], 1));
      setText(this.error, "");
      return;
    }
    try {
      await this.conn.request(verb, args);
      setText(this.error, "");
    } catch (e) {
      setText(this.error, errorText(e));
    }
  }

  /** The robot is gone: say so instead of its last state and rate. */
  disconnected(): void {
    this.set("state", "unknown (disconnected)");
    this.set("rate", "—");
    if (this.last) this.set("cycle", `${this.last.cycle} (last seen)`);
    this.rate = 0;
    this.last = null;
  }

  /** A new run: nothing of the old one carries over (the rate least of all). */
  reset(): void {
    this.rate = 0;
    this.last = null;
    this.switchMap.clear();
    this.switches.replaceChildren();
  }

  update(stats: Json | undefined, skills: JsonObject[], wall: number): void {
    if (isObject(stats)) {
      const cycle = num(stats["cycle"]);
      if (this.last && wall > this.last.wall) {
        const r = (cycle - this.last.cycle) / (wall - this.last.wall);
        this.rate = this.rate === 0 ? r : 0.7 * this.rate + 0.3 * r;
      }
      this.last = { cycle, wall };
      const us = (ns: Json | undefined) => `${(num(ns) / 1000).toFixed(1)} µs`;
      this.set("state", this.player ? `a replay: the robot ran the recording to cycle ${cycle} and stopped` : stats["running"] === true ? "running" : "stopped");
      this.set("cycle", String(cycle));
      // The manager's own measure when it runs (over its last ~20 cycles), else the samples'.
      const measured = num(stats["rate_hz"]);
      this.set("rate", `${(stats["running"] === true && measured > 0 ? measured : this.rate).toFixed(1)} Hz`);
      this.set("period", `${(num(stats["period_s"]) * 1000).toFixed(1)} ms`);
      this.set("last", us(stats["last_cycle_ns"]));
      this.set("mean", us(stats["mean_cycle_ns"]));
      this.set("max", us(stats["max_cycle_ns"]));
      this.set("overruns", String(num(stats["overruns"])));
      this.set("late", String(num(stats["late_starts"])));
    }
    for (const s of skills) {
      const name = str(s["name"]);
      let box = this.switchMap.get(name);
      if (!box) {
        const input = robotControl(h("input", { type: "checkbox", "data-testid": `switch-${name}` }));
        input.addEventListener("change", () => {
          const verb = input.checked ? "activate" : "deactivate";
          void this.act(verb, { skills: [name] });
        });
        this.switchMap.set(name, input);
        this.switches.append(h("label", { class: "switch" }, input, ` ${name}`));
        box = input;
      }
      const active = s["active"] === true;
      if (document.activeElement !== box || box.checked === active) box.checked = active;
      box.parentElement?.classList.toggle("faulted", s["faulted"] !== null && s["faulted"] !== undefined);
    }
  }

  private set(key: string, text: string): void {
    const el = this.fields.get(key);
    if (el) setText(el, text);
  }
}

/** A typed editor for one parameter. */
class ParamEditor {
  readonly row: HTMLTableRowElement;
  private readonly input: HTMLInputElement;
  private readonly current: HTMLElement;
  private readonly error: HTMLElement;
  private readonly type: string;
  private edited = false;

  constructor(
    private readonly conn: Connection,
    private readonly skill: string,
    private readonly spec: JsonObject,
  ) {
    const name = str(spec["name"]);
    this.type = str(spec["type"]);
    const min = spec["min"];
    const max = spec["max"];
    const id = `param-${skill}-${name}`;
    if (this.type === "bool") {
      this.input = robotControl(h("input", { type: "checkbox", "data-testid": id }));
    } else if (this.type === "i64" || this.type === "f64") {
      this.input = h("input", {
        type: "number",
        step: this.type === "i64" ? 1 : "any",
        min: typeof min === "number" ? min : undefined,
        max: typeof max === "number" ? max : undefined,
        "data-testid": id,
        class: "num",
      });
    } else {
      this.input = h("input", { type: "text", "data-testid": id });
    }
    this.setValue(spec["value"]);
    // Typed and not yet set: live updates leave it alone (clicking Set moves the focus off
    // the input before the click is handled, and an update in between would undo the edit).
    this.input.addEventListener("input", () => (this.edited = true));
    const set = robotControl(h("button", { "data-testid": `${id}-set`, title: "set it on the robot now" }, "Set"));
    set.addEventListener("click", () => void this.submit());
    this.input.addEventListener("keydown", (e) => {
      if (e.key === "Enter") void this.submit();
    });
    if (this.type === "bool") this.input.addEventListener("change", () => void this.submit());
    this.current = h("span", { class: "mono", "data-testid": `${id}-value` }, show(spec["value"]));
    this.error = h("div", { class: "error", "data-testid": `${id}-error` });
    const range =
      typeof min === "number" || typeof max === "number"
        ? `[${typeof min === "number" ? min : "−∞"}, ${typeof max === "number" ? max : "∞"}]`
        : "";
    const unit = str(spec["unit"]);
    this.row = h(
      "tr",
      {},
      h("td", { title: str(spec["doc"]) }, name),
      h("td", { class: "dim" }, `${this.type} ${range} ${unit}`.trim()),
      h("td", {}, this.current),
      h("td", {}, this.input, this.type === "bool" ? null : set, this.error),
    );
  }

  private setValue(v: Json | undefined): void {
    if (this.type === "bool") this.input.checked = v === true;
    else if (typeof v === "number") this.input.value = String(v);
    else if (typeof v === "string") this.input.value = v;
  }

  /** The editor's value in its type, or why it is not one. */
  private parse(): { ok: Json } | { err: string } {
    const text = this.input.value.trim();
    switch (this.type) {
      case "bool":
        return { ok: this.input.checked };
      case "i64": {
        if (!/^[-+]?\d+$/.test(text)) return { err: `${str(this.spec["name"])} is an integer (i64), got "${text}"` };
        const n = Number(text);
        if (!Number.isSafeInteger(n)) return { err: `the integer ${text} is too large for this editor` };
        return { ok: n };
      }
      case "f64": {
        const n = Number(text);
        if (text === "" || !Number.isFinite(n)) return { err: `${str(this.spec["name"])} is a number (f64), got "${text}"` };
        return { ok: n };
      }
      default:
        return { ok: this.input.value };
    }
  }

  private async submit(): Promise<void> {
    const parsed = this.parse();
    if ("err" in parsed) {
      setText(this.error, parsed.err);
      return;
    }
    // JSON has one number type: an integral f64 travels as an integer, which the manager accepts.
    const value = parsed.ok;
    try {
      await this.conn.request("set_param", { skill: this.skill, param: str(this.spec["name"]), value });
      setText(this.error, "");
      this.input.classList.remove("refused");
      this.edited = false;
    } catch (e) {
      setText(this.error, errorText(e));
      this.input.classList.add("refused");
    }
  }

  update(spec: JsonObject): void {
    setText(this.current, show(spec["value"]));
    if (!this.edited && document.activeElement !== this.input && this.error.textContent === "") this.setValue(spec["value"]);
  }
}

/** A skill's ports with their values; `inactive` replaces the values' liveness ("inactive since cycle N"). */
function portTable(ports: Json | undefined, testid: string, inactive: string | null = null): HTMLElement {
  const t = h("table", { class: "ports", "data-testid": testid });
  t.append(h("tr", {}, h("th", {}, "port"), h("th", {}, "signal"), h("th", {}, "type"), h("th", {}, "value")));
  if (Array.isArray(ports)) {
    for (const p of ports) {
      if (!isObject(p)) continue;
      t.append(
        h(
          "tr",
          { "data-signal": str(p["signal"]) },
          h("td", {}, str(p["name"])),
          h("td", { class: "mono" }, str(p["signal"])),
          h("td", { class: "dim" }, str(p["type"])),
          inactive === null
            ? h(
                "td",
                { class: "mono value", "data-value": JSON.stringify(p["value"] ?? null) },
                show(p["value"]),
                // An input not written in the manager's latest cycle: its latest value, and when.
                typeof p["written"] === "number" ? h("span", { class: "dim", "data-written": String(p["written"]) }, ` (written at cycle ${p["written"]})`) : null,
              )
            : h(
                "td",
                { class: "mono value inactive-value", "data-value": JSON.stringify(p["value"] ?? null), "data-inactive": "" },
                inactive,
                h("span", { class: "dim" }, ` (last written: ${show(p["value"], 120)})`),
              ),
        ),
      );
    }
  }
  return t;
}

class SkillPanel {
  readonly el: HTMLDetailsElement;
  private readonly name: string;
  private readonly head: HTMLElement;
  private readonly state: HTMLElement;
  private readonly since: HTMLElement;
  private readonly activate: HTMLButtonElement;
  private readonly priority: HTMLInputElement;
  private readonly priorityError: HTMLElement;
  private readonly params = new Map<string, ParamEditor>();
  private readonly paramBody: HTMLTableElement;
  private readonly timing: HTMLElement;
  private readonly showData: HTMLInputElement;
  private readonly showInput: HTMLInputElement;
  private readonly showOutput: HTMLInputElement;
  private readonly dataBox: HTMLElement;
  private readonly inputBox: HTMLElement;
  private readonly outputBox: HTMLElement;
  private readonly logParams: HTMLInputElement;
  private readonly paramLog: HTMLElement;
  private readonly verbose: HTMLInputElement;
  private readonly prints: HTMLElement;
  private readonly error: HTMLElement;
  private active = false;
  /** Whether the skill is active on the robot now (what Activate/Deactivate acts on), also while
   *  the panel shows a past cycle. */
  private liveActive = false;
  /** The last info shown, and its "inactive since": shown again at once when a box is ticked. */
  private lastInfo: JsonObject | null = null;
  private lastInactive: string | null = null;
  private lastParams: [string, Json][] = [];
  private lastCycle = 0;
  private priorityEdited = false;

  constructor(
    private readonly conn: Connection,
    info: JsonObject,
  ) {
    this.name = str(info["name"]);
    const n = this.name;
    this.state = h("span", { class: "state", "data-testid": `state-${n}` });
    this.since = h("span", { class: "since", "data-testid": `since-${n}` });
    this.head = h("summary", {}, h("strong", {}, n), ` ${str(info["type_name"])} · ${str(info["kind"])} `, this.state, " ", this.since);
    this.activate = robotControl(h("button", { "data-testid": `activate-${n}` }, "Activate"));
    this.activate.addEventListener("click", () => void this.toggle());
    this.error = h("div", { class: "error", "data-testid": `skill-error-${n}` });
    // The priority decides contention over a resource; the manager applies a change from the next cycle.
    this.priority = h("input", { type: "number", step: "1", class: "short", "data-testid": `priority-${n}` });
    this.priority.value = String(num(info["priority"]));
    // As with parameters: a typed priority stays until it is set.
    this.priority.addEventListener("input", () => (this.priorityEdited = true));
    this.priorityError = h("span", { class: "error", "data-testid": `priority-${n}-error` });
    const setPriority = robotControl(h("button", { "data-testid": `priority-${n}-set`, title: "set it on the robot now" }, "Set"));
    setPriority.addEventListener("click", () => void this.submitPriority());
    this.priority.addEventListener("keydown", (e) => {
      if (e.key === "Enter") void this.submitPriority();
    });
    this.paramBody = h("table", { class: "params" });
    for (const p of Array.isArray(info["params"]) ? info["params"] : []) {
      if (!isObject(p)) continue;
      const ed = new ParamEditor(conn, n, p);
      this.params.set(str(p["name"]), ed);
      this.paramBody.append(ed.row);
    }
    const toggle = (label: string, testid: string) => {
      const box = h("input", { type: "checkbox", "data-testid": testid });
      return [box, h("label", { class: "toggle" }, box, ` ${label}`)] as const;
    };
    const [sd, sdl] = toggle("show data", `show-data-${n}`);
    const [si, sil] = toggle("show input", `show-input-${n}`);
    const [so, sol] = toggle("show output", `show-output-${n}`);
    const [lp, lpl] = toggle("log parameters", `log-params-${n}`);
    const [vb, vbl] = toggle("verbose", `verbose-${n}`);
    robotControl(vb);
    this.showData = sd;
    this.showInput = si;
    this.showOutput = so;
    this.logParams = lp;
    this.verbose = vb;
    this.dataBox = h("pre", { class: "box", hidden: true, "data-testid": `data-${n}` });
    this.inputBox = h("div", { hidden: true, "data-testid": `inputs-${n}` });
    this.outputBox = h("div", { hidden: true, "data-testid": `outputs-${n}` });
    this.paramLog = h("div", { class: "log", hidden: true, "data-testid": `param-log-${n}` });
    this.prints = h("div", { class: "log", hidden: true, "data-testid": `prints-${n}` });
    // Ticked: filled at once from what is shown now (live or the timeline's cycle).
    sd.addEventListener("change", () => {
      this.dataBox.hidden = !sd.checked;
      this.renderBoxes();
    });
    si.addEventListener("change", () => {
      this.inputBox.hidden = !si.checked;
      this.renderBoxes();
    });
    so.addEventListener("change", () => {
      this.outputBox.hidden = !so.checked;
      this.renderBoxes();
    });
    lp.addEventListener("change", () => {
      this.paramLog.hidden = !lp.checked;
      if (lp.checked) {
        keep(this.paramLog, `logging parameters of ${n} from now on`);
        for (const [param, value] of this.lastParams) keep(this.paramLog, `cycle ${this.lastCycle}: ${param} = ${show(value)}`);
      }
    });
    vb.addEventListener("change", () => void this.setVerbose(vb.checked));
    this.timing = h("span", { class: "mono", "data-testid": `timing-${n}` });
    this.el = h(
      "details",
      { class: "skill", "data-skill": n, "data-testid": `skill-${n}` },
      this.head,
      h("p", { class: "dim" }, str(info["doc"])),
      h("div", { class: "row" }, this.activate, " priority ", this.priority, setPriority, this.priorityError, " · timing ", this.timing),
      this.error,
      this.paramBody,
      h("div", { class: "row" }, sdl, sil, sol, lpl, vbl),
      this.dataBox,
      this.inputBox,
      this.outputBox,
      this.paramLog,
      this.prints,
    );
    this.el.addEventListener("toggle", () => this.renderBoxes());
    this.update(info);
  }

  private async toggle(): Promise<void> {
    try {
      await this.conn.request(this.liveActive ? "deactivate" : "activate", { skills: [this.name] });
      setText(this.error, "");
    } catch (e) {
      setText(this.error, errorText(e));
    }
  }

  private async submitPriority(): Promise<void> {
    const text = this.priority.value.trim();
    const value = Number(text);
    // The manager takes a 32-bit signed priority; anything else never leaves the page.
    if (!/^[-+]?\d+$/.test(text) || value < -2147483648 || value > 2147483647) {
      setText(this.priorityError, `the priority is a 32-bit integer, got "${text}"`);
      return;
    }
    try {
      await this.conn.request("set_priority", { skill: this.name, priority: value });
      setText(this.priorityError, "");
      this.priorityEdited = false;
    } catch (e) {
      setText(this.priorityError, errorText(e));
    }
  }

  private async setVerbose(on: boolean): Promise<void> {
    this.prints.hidden = !on;
    try {
      await this.conn.request("set_verbose", { skill: this.name, verbose: on });
      setText(this.error, "");
    } catch (e) {
      setText(this.error, errorText(e));
    }
  }

  /** `inactiveSince`: for an inactive skill, "inactive since cycle N" (its outputs are not live). */
  update(info: JsonObject, cycle = 0, inactiveSince: string | null = null): void {
    this.lastCycle = cycle;
    this.active = info["active"] === true;
    const fault = info["faulted"];
    const state = typeof fault === "string" ? `faulted: ${fault}` : this.active ? "active" : "inactive";
    setText(this.state, state);
    const inactive = this.active ? null : (inactiveSince ?? "inactive");
    setText(this.since, inactive === null ? "" : inactive.replace(/^inactive /, ""));
    this.el.classList.toggle("active", this.active);
    this.el.classList.toggle("faulted", typeof fault === "string");
    // Paused on the timeline the panel shows a past cycle, but the button acts on the robot now:
    // it says so, and follows the skill's state now (`live_active`, from `skillsAt`).
    const past = typeof info["live_active"] === "boolean";
    this.liveActive = past ? info["live_active"] === true : this.active;
    setText(this.activate, `${this.liveActive ? "Deactivate" : "Activate"}${past ? " now" : ""}`);
    if (replayFile() === null) {
      this.activate.title = past ? `acts on the robot now (${this.liveActive ? "active" : "inactive"} now), not on the cycle shown` : "";
    }
    if (!this.priorityEdited && document.activeElement !== this.priority && this.priorityError.textContent === "") {
      this.priority.value = String(num(info["priority"]));
    }
    const t = info["timing"];
    if (isObject(t)) {
      const runs = num(t["runs"]);
      const mean = runs > 0 ? num(t["total_ns"]) / runs / 1000 : 0;
      setText(
        this.timing,
        `${runs} runs, last ${(num(t["last_ns"]) / 1000).toFixed(1)} µs, mean ${mean.toFixed(1)} µs, max ${(num(t["max_ns"]) / 1000).toFixed(1)} µs`,
      );
    }
    this.lastParams = [];
    for (const p of Array.isArray(info["params"]) ? info["params"] : []) {
      if (!isObject(p)) continue;
      this.params.get(str(p["name"]))?.update(p);
      this.lastParams.push([str(p["name"]), p["value"] ?? null]);
    }
    this.lastInfo = info;
    this.lastInactive = inactive;
    this.renderBoxes();
  }

  /** The data, input and output boxes ticked, from the last info shown. */
  private renderBoxes(): void {
    const info = this.lastInfo;
    const inactive = this.lastInactive;
    if (!info || !this.el.open) return;
    if (this.showData.checked) {
      const params: JsonObject = {};
      for (const p of Array.isArray(info["params"]) ? info["params"] : []) if (isObject(p)) params[str(p["name"])] = p["value"] ?? null;
      const data = { name: info["name"], type: info["type_name"], kind: info["kind"], active: info["active"], faulted: info["faulted"], priority: info["priority"], verbose: info["verbose"], params, timing: info["timing"] };
      setText(this.dataBox, JSON.stringify(data, null, 2));
    }
    if (this.showInput.checked) this.inputBox.replaceChildren(portTable(info["inputs"], `input-table-${this.name}`));
    if (this.showOutput.checked) this.outputBox.replaceChildren(portTable(info["outputs"], `output-table-${this.name}`, inactive));
    if (info["verbose"] === true && !this.verbose.checked && document.activeElement !== this.verbose) {
      this.verbose.checked = true;
      this.prints.hidden = false;
    }
  }

  event(e: JsonObject): void {
    const kind = e["kind"];
    if (kind === "print" && this.verbose.checked) {
      keep(this.prints, `cycle ${num(e["cycle"])}: ${str(e["line"])}`);
    } else if (kind === "param_changed" && this.logParams.checked) {
      keep(this.paramLog, `cycle ${num(e["cycle"])}: ${str(e["param"])} = ${show(e["value"])}`);
    } else if (kind === "skill_faulted") {
      setText(this.error, `faulted at cycle ${num(e["cycle"])}: ${str(e["cause"])}`);
    }
  }
}

/** Since when a skill is inactive, from the server's `activity` (the cycle of its last change). */
function inactiveSince(activity: Json | undefined, name: string): string {
  if (!isObject(activity)) return "inactive";
  const changed = activity["changed"];
  const at = isObject(changed) ? changed[name] : undefined;
  if (typeof at === "number") return `inactive since cycle ${at}`;
  // No change seen since the GUI started watching: inactive at least since then.
  const from = num(activity["observed_from"]);
  return from === 0 ? "inactive since cycle 0" : `inactive since cycle ≤ ${from}`;
}

export class SkillPanels {
  readonly el: HTMLElement;
  private readonly panels = new Map<string, SkillPanel>();
  private readonly list: HTMLElement;
  private readonly resources: HTMLTableElement;
  private readonly resourcesTitle: HTMLElement;
  private readonly pastNote: HTMLElement;
  private resourcesKey = "";
  /** Panels to open once they exist (a layout restored before the first telemetry). */
  private toOpen = new Set<string>();
  /** Called when a panel is opened or closed (the page's layout is saved). */
  onChange: () => void = () => {};

  constructor(
    private readonly conn: Connection,
    stale: HTMLElement,
  ) {
    this.list = h("div", {});
    this.resources = h("table", { class: "resources", "data-testid": "resources" });
    this.resourcesTitle = h("h3", {}, "Resources: who wins now");
    this.pastNote = h("span", { class: "past-note", "data-testid": "skills-past" });
    this.el = h(
      "section",
      { class: "panel live", id: "skills" },
      h("h2", {}, "Skills", stale, this.pastNote),
      this.resourcesTitle,
      this.resources,
      this.list,
    );
  }

  /** A new run: its skills may differ; panels are built again from its telemetry. */
  clear(): void {
    this.panels.clear();
    this.list.replaceChildren();
    this.resources.replaceChildren();
    this.resourcesKey = "";
  }

  /** `past`: the skills as of a past cycle (the timeline, paused), said in the panel's title;
   *  null: live. */
  update(skills: JsonObject[], cycle: number, activity?: Json, winners?: Json, past: string | null = null): void {
    setText(this.pastNote, past ?? "");
    setText(this.resourcesTitle, past === null ? "Resources: who wins now" : `Resources: who won at cycle ${cycle}`);
    for (const s of skills) {
      const name = str(s["name"]);
      const since = s["active"] === true ? null : inactiveSince(activity, name);
      const p = this.panels.get(name);
      if (p) p.update(s, cycle, since);
      else {
        const panel = new SkillPanel(this.conn, s);
        this.panels.set(name, panel);
        this.list.append(panel.el);
        if (this.toOpen.delete(name)) panel.el.open = true;
        panel.el.addEventListener("toggle", () => this.onChange());
        panel.update(s, cycle, since);
      }
    }
    this.showResources(winners, past !== null);
  }

  /** The skill panels open (the page's layout). */
  openPanels(): string[] {
    return [...this.panels].filter(([, p]) => p.el.open).map(([name]) => name);
  }

  /** Opens these skills' panels (now, or when they are made). */
  setOpen(names: string[]): void {
    for (const n of names) {
      const p = this.panels.get(n);
      if (p) p.el.open = true;
      else this.toOpen.add(n);
    }
  }

  /** Every resource (a signal leaf with several writers), its writers and who wins it now. */
  private showResources(winners: Json | undefined, past: boolean): void {
    const rows = (Array.isArray(winners) ? winners : []).filter(isObject).map((w) => ({
      signal: str(w["signal"]),
      writers: (Array.isArray(w["writers"]) ? w["writers"] : []).filter((x): x is string => typeof x === "string"),
      winner: typeof w["winner"] === "string" ? w["winner"] : null,
      cycle: num(w["cycle"]),
    }));
    const key = JSON.stringify([past, rows]);
    if (key === this.resourcesKey) return;
    this.resourcesKey = key;
    if (rows.length === 0) {
      this.resources.replaceChildren(h("tr", {}, h("td", { class: "dim" }, "no resource: no signal has several writers")));
      return;
    }
    this.resources.replaceChildren(
      h("tr", {}, h("th", {}, "resource"), h("th", {}, "writers"), h("th", {}, past ? "winner then" : "winner now")),
      ...rows.map((r) =>
        h(
          "tr",
          { "data-resource": r.signal },
          h("td", { class: "mono" }, r.signal),
          h("td", {}, r.writers.join(", ")),
          h(
            "td",
            { class: "winner", "data-winner": r.winner ?? "" },
            r.winner === null ? h("span", { class: "dim" }, "nobody wrote it") : h("strong", {}, r.winner),
            r.winner === null ? "" : h("span", { class: "dim" }, ` (cycle ${r.cycle})`),
          ),
        ),
      ),
    );
  }

  event(e: JsonObject): void {
    const skill = e["skill"];
    if (typeof skill === "string") this.panels.get(skill)?.event(e);
  }
}
