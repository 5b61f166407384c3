// The situate debugging GUI: one WebSocket to the server, panels fed by its telemetry and events.

import "./style.css";
import { Connection, isObject, RefusedError, type Json, type JsonObject } from "./conn";
import { errorText, h, num, setText, show, str } from "./dom";
import { GraphView } from "./graph";
import { Plots } from "./plots";
import { ManagerPanel, SkillPanels } from "./skills";
import { WorldView } from "./world";

const EVENT_LINES = 300;

class Monitors {
  readonly el: HTMLElement;
  private readonly list: HTMLElement;
  private readonly error: HTMLElement;

  constructor(private readonly conn: Connection) {
    const cond = h("input", { type: "text", class: "wide", placeholder: "condition, e.g. sonar.range[0] < 0.3", "data-testid": "monitor-condition" });
    const mode = h("select", { "data-testid": "monitor-mode" }, h("option", { value: "once" }, "once"), h("option", { value: "edge" }, "edge"), h("option", { value: "level" }, "level"));
    const add = h("button", { "data-testid": "monitor-add" }, "Add monitor");
    add.addEventListener("click", async () => {
      try {
        await this.conn.request("monitor_add", { condition: cond.value, mode: mode.value });
        setText(this.error, "");
        cond.value = "";
        await this.refresh();
      } catch (e) {
        setText(this.error, e instanceof RefusedError && e.pointer ? `${e.message}\n${e.pointer}` : errorText(e));
      }
    });
    this.error = h("pre", { class: "error", "data-testid": "monitor-error" });
    this.list = h("table", { class: "monitors", "data-testid": "monitors" });
    this.el = h("section", { class: "panel", id: "monitors" }, h("h2", {}, "Monitors"), h("div", { class: "row" }, cond, mode, add), this.error, this.list);
  }

  async refresh(): Promise<void> {
    let list: Json;
    try {
      list = await this.conn.request("monitor_list");
    } catch {
      return;
    }
    const rows = (Array.isArray(list) ? list : []).filter(isObject).map((m) => {
      const cancel = h("button", {}, "Cancel");
      cancel.addEventListener("click", async () => {
        try {
          await this.conn.request("monitor_cancel", { monitor: num(m["monitor"]) });
          await this.refresh();
        } catch (e) {
          setText(this.error, errorText(e));
        }
      });
      return h("tr", {}, h("td", {}, String(num(m["monitor"]))), h("td", { class: "mono" }, str(m["condition"])), h("td", {}, str(m["mode"])), h("td", {}, `fired ${num(m["fired"])}`), h("td", {}, m["holds"] === true ? "holds" : ""), h("td", {}, cancel));
    });
    this.list.replaceChildren(h("tr", {}, h("th", {}, "id"), h("th", {}, "condition"), h("th", {}, "mode"), h("th", {}, ""), h("th", {}, ""), h("th", {}, "")), ...rows);
  }
}

class EventLog {
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
    while (this.list.childElementCount > EVENT_LINES) this.list.lastElementChild?.remove();
  }
}

function start(): void {
  const root = document.getElementById("app");
  if (!root) return;
  const status = h("span", { class: "status", "data-testid": "status" }, "connecting…");
  const robot = h("span", { class: "robot", "data-testid": "robot" }, "");
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  let graphAsked = false;
  // The panels are created after the connection object (they send through it).
  const conn: Connection = new Connection(`${proto}//${location.host}/ws`, {
    hello: (msg) => {
      world.setMap(msg["world"]);
      void (async () => {
        try {
          const g = await conn.request("graph");
          graph.setGraph(g);
          plots.setSignals(graph.signalNames());
          graphAsked = true;
        } catch (e) {
          setText(status, `graph: ${errorText(e)}`);
        }
        await monitors.refresh();
      })();
    },
    telemetry: (msg) => {
      const wall = num(msg["wall_s"], Date.now() / 1000);
      const stats = msg["stats"];
      const skills = (Array.isArray(msg["skills"]) ? msg["skills"] : []).filter(isObject);
      if (isObject(stats)) setText(robot, `robot ${str(stats["robot"])}`);
      manager.update(stats, skills, wall);
      panels.update(skills, isObject(stats) ? num(stats["cycle"]) : 0);
      if (graphAsked) graph.update(skills, msg["winners"]);
      plots.update(wall, msg["signals"]);
      world.update(msg["signals"]);
      document.body.dataset["samples"] = String(Number(document.body.dataset["samples"] ?? "0") + 1);
    },
    event: (e) => {
      events.add(e);
      panels.event(e);
      const kind = e["kind"];
      if (kind === "monitor_fired") void monitors.refresh();
    },
    status: (connected, text) => {
      setText(status, text);
      status.classList.toggle("bad", !connected);
    },
  });
  const manager = new ManagerPanel(conn);
  const panels = new SkillPanels(conn);
  const graph = new GraphView();
  const plots = new Plots(conn);
  const world = new WorldView();
  const monitors = new Monitors(conn);
  const events = new EventLog();
  conn.onOpen = () => void plots.watch().catch(() => undefined);
  root.append(
    h("header", {}, h("h1", {}, "situate"), robot, status),
    h("main", {}, h("div", { class: "col" }, manager.el, panels.el, monitors.el), h("div", { class: "col" }, world.el, plots.el, graph.el, events.el)),
  );
}

start();
