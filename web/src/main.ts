// The situate debugging GUI: one WebSocket to the server, panels fed by its telemetry and events.
//
// Time is part of every value shown: while the robot is not connected the header says so, every
// live panel says when its values were last seen and the controls that need the robot are
// disabled; a hello with another run id (the robot restarted) clears the old run's plots, trails
// and monitors and separates its events.

import "./style.css";
import { Connection, isObject, type Json, type JsonObject } from "./conn";
import { errorText, h, num, replayFile, setLinkUp, setReplay, setText, staleNote, str } from "./dom";
import { GraphView } from "./graph";
import * as layout from "./layout";
import { EventLog, Monitors } from "./monitors";
import { Plots } from "./plots";
import { ManagerPanel, SkillPanels } from "./skills";
import { skillsAt, Timeline } from "./timeline";
import { WorldView } from "./world";

function clock(unixS: number): string {
  return new Date(unixS * 1000).toLocaleTimeString();
}

function start(): void {
  const root = document.getElementById("app");
  if (!root) return;
  const status = h("span", { class: "status", "data-testid": "status" }, "connecting…");
  const robot = h("span", { class: "robot", "data-testid": "robot" }, "");
  const runInfo = h("span", { class: "run", "data-testid": "run-info" }, "");
  const staleBanner = h("div", { class: "banner bad", "data-testid": "stale-banner" });
  const outcome = h("div", { class: "banner", hidden: true, "data-testid": "outcome" });
  const replayBanner = h("div", { class: "banner replay", hidden: true, "data-testid": "replay-banner" });
  const share = h("button", { "data-testid": "share", title: "copy a link to this page as laid out now: its plots, open panels and the cycle shown" }, "Copy link");
  const shareNote = h("span", { class: "dim", "data-testid": "share-note" });
  /** The layout is restored once, from the address or storage, when the first hello's graph is
   *  known; until then (and while it is restored) nothing is saved over it. */
  let layoutReady = false;
  let saveTimer: number | null = null;
  const saveNow = () => {
    if (saveTimer !== null) window.clearTimeout(saveTimer);
    saveTimer = null;
    if (layoutReady) layout.save({ plots: plots.layout(), open: panels.openPanels(), cycle: timeline.shownCycle() });
  };
  // At most a few saves a second (playing the timeline shows ten cycles a second).
  const saveLayout = () => {
    saveTimer ??= window.setTimeout(saveNow, 250);
  };
  share.addEventListener("click", async () => {
    saveNow();
    try {
      await navigator.clipboard.writeText(location.href);
      setText(shareNote, "link copied");
    } catch {
      setText(shareNote, location.href);
    }
  });
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  let graphAsked = false;
  let runId: string | null = null;
  /** The last telemetry: its cycle, and when it came (performance.now(), ms). */
  let lastSeen: { cycle: number; at: number } | null = null;
  let staleTimer: number | null = null;
  /** The last telemetry's skills, activity, winners and signals (the timeline's past is shown
   *  over them, and going live shows them again at once). */
  let live: { skills: JsonObject[]; cycle: number; activity: Json | undefined; winners: Json | undefined; signals: Json | undefined; wall: number } | null = null;

  const showStale = () => {
    const text = lastSeen ? `last seen at cycle ${lastSeen.cycle}, ${Math.round((performance.now() - lastSeen.at) / 1000)} s ago` : "never seen";
    for (const note of document.querySelectorAll(".stale-note")) setText(note, text);
    setText(staleBanner, `Not connected to the robot: the values below are not live (${text}). Reconnecting… The timeline's marks and the event log stay; the cycles behind them were in the robot's process. If it died, a run recorded with --record opens again, up to its last complete cycle: situate replay FILE --view --recover --gui.`);
  };
  const setStale = (stale: boolean) => {
    document.body.classList.toggle("stale", stale);
    if (stale) {
      showStale();
      staleTimer ??= window.setInterval(showStale, 1000);
    } else {
      if (staleTimer !== null) window.clearInterval(staleTimer);
      staleTimer = null;
      for (const note of document.querySelectorAll(".stale-note")) setText(note, "");
      setText(staleBanner, "");
    }
  };
  const showOutcome = (o: Json | undefined) => {
    if (isObject(o) && typeof o["summary"] === "string") {
      const ok = o["ok"] === true;
      setText(outcome, `Mission outcome — ${o["summary"]}`);
      outcome.classList.toggle("ok", ok);
      outcome.classList.toggle("bad", !ok);
      outcome.dataset["ok"] = String(ok);
      outcome.hidden = false;
    } else {
      outcome.hidden = true;
      setText(outcome, "");
    }
  };

  // The panels are created after the connection object (they send through it).
  const conn: Connection = new Connection(`${proto}//${location.host}/ws`, {
    hello: (msg) => {
      const run = msg["run"];
      const id = isObject(run) ? str(run["id"]) : "";
      const started = isObject(run) ? num(run["started_unix_s"]) : 0;
      if (runId !== null && id !== runId) {
        // The robot restarted: nothing of the old run may pass for this one.
        plots.clear();
        world.clear();
        monitors.clear();
        panels.clear();
        manager.reset();
        events.newRun(`── new run ${id}, started ${clock(started)}; the events below are of the previous run (${runId}) ──`);
        lastSeen = null;
        live = null;
        timeline.reset();
      }
      runId = id;
      monitors.setSession(str(msg["session"]));
      document.body.dataset["run"] = id;
      setText(runInfo, `run ${id} · started ${clock(started)}`);
      showOutcome(msg["outcome"]);
      const replay = msg["replay"];
      if (isObject(replay) && replayFile() === null) {
        // A replay: say so everywhere, and show the recording's events (they happened before
        // this page connected).
        const file = str(replay["file"]);
        setReplay(file);
        setText(status, "connected to a replay (not live)");
        document.body.dataset["mode"] = "replay";
        setText(replayBanner, `Replay of ${file}: ${str(replay["summary"])}. Nothing here is live: Play (on the timeline, or Run) plays the recording; the controls that would change the robot are off.`);
        replayBanner.hidden = false;
        document.title = `situate · replay of ${file}`;
        timeline.setReplay(file);
        manager.setReplay(timeline.player);
        plots.setRecording();
        void (async () => {
          try {
            const r = await conn.request("replay_events");
            const list = isObject(r) && Array.isArray(r["events"]) ? r["events"] : [];
            const total = isObject(r) ? num(r["total"]) : list.length;
            for (const e of list) if (isObject(e)) events.add(e);
            events.note(`the events recorded in ${file}, newest first${total > list.length ? ` (the newest ${list.length} of ${total})` : ""}:`);
          } catch (e) {
            events.note(`the recording's events: ${errorText(e)}`);
          }
        })();
      }
      world.setMap(msg["world"]);
      void (async () => {
        try {
          const g = await conn.request("graph");
          graph.setGraph(g);
          plots.setSignals(graph.signalNames(), graph.leafTypes());
          graphAsked = true;
          if (!layoutReady) {
            const start = layout.initial();
            if (start) {
              panels.setOpen(start.open);
              await plots.restore(start.plots);
              if (start.cycle !== null) timeline.seekWhenHeld(start.cycle);
            }
            layoutReady = true;
            saveNow();
          }
        } catch (e) {
          setText(status, `graph: ${errorText(e)}`);
        }
        await monitors.refresh();
      })();
    },
    telemetry: (msg) => {
      if (typeof msg["run"] === "string" && runId !== null && msg["run"] !== runId) return;
      const wall = num(msg["wall_s"], Date.now() / 1000);
      const stats = msg["stats"];
      const skills = (Array.isArray(msg["skills"]) ? msg["skills"] : []).filter(isObject);
      if (isObject(stats)) {
        setText(robot, `robot ${str(stats["robot"])}`);
        lastSeen = { cycle: num(stats["cycle"]), at: performance.now() };
      }
      setStale(false);
      manager.update(stats, skills, wall);
      const cycle = isObject(stats) ? num(stats["cycle"]) : 0;
      live = { skills, cycle, activity: msg["activity"], winners: msg["winners"], signals: msg["signals"], wall };
      if (isObject(stats)) timeline.liveAt(cycle, num(stats["time_s"]), num(stats["period_s"]));
      // Paused, the skills and the world show the timeline's cycle; the rest stays live.
      if (!timeline.isPaused()) {
        panels.update(skills, cycle, msg["activity"], msg["winners"]);
        world.update(msg["signals"], wall);
      } else {
        world.keepTrail(msg["signals"], wall);
        if (pastFrame) showPastSkills(pastFrame);
      }
      if (graphAsked && !timeline.isPaused()) graph.update(skills, msg["winners"]);
      plots.update(wall, msg["signals"], isObject(stats) ? { cycle, timeS: num(stats["time_s"]) } : null);
      document.body.dataset["samples"] = String(Number(document.body.dataset["samples"] ?? "0") + 1);
    },
    event: (e) => {
      events.add(e);
      panels.event(e);
      monitors.event(e);
    },
    outcome: (o) => showOutcome(o),
    status: (connected, text) => {
      const file = replayFile();
      setText(status, connected && file !== null ? `${text} to a replay (not live)` : text);
      status.classList.toggle("bad", !connected);
      setLinkUp(connected);
      timeline.setConnected(connected);
      if (!connected) {
        manager.disconnected();
        setStale(true);
      }
    },
  });
  const manager = new ManagerPanel(conn, staleNote());
  const panels = new SkillPanels(conn, staleNote());
  const graph = new GraphView(staleNote());
  const plots = new Plots(conn, staleNote());
  const world = new WorldView(staleNote());
  const monitors = new Monitors(conn, staleNote());
  const events = new EventLog();
  /** The timeline's frame shown while paused: the skill panels show it over each live sample (the
   *  buttons, which act on the robot now, follow the live state). */
  let pastFrame: JsonObject | null = null;
  const showPastSkills = (frame: JsonObject) => {
    const cycle = num(frame["cycle"]);
    const file = replayFile();
    const note = file === null ? `at cycle ${cycle} (paused: not live)` : `at cycle ${cycle} (replay of ${file}: not live)`;
    const past = skillsAt(live?.skills ?? [], frame);
    panels.update(past, cycle, frame["activity"], frame["winners"], note);
    return { cycle, note, past };
  };
  const timeline = new Timeline(conn, {
    show: (frame) => {
      pastFrame = frame;
      const { note, past } = showPastSkills(frame);
      world.showPast(frame["signals"], note);
      if (graphAsked) graph.update(past, frame["winners"]);
      plots.playhead(num(frame["time_s"]));
    },
    span: () => plots.refill(),
    live: () => {
      pastFrame = null;
      plots.playhead(null);
      if (!live) return;
      panels.update(live.skills, live.cycle, live.activity, live.winners);
      world.update(live.signals, live.wall);
      if (graphAsked) graph.update(live.skills, live.winners);
    },
  });
  plots.onChange = saveLayout;
  panels.onChange = saveLayout;
  timeline.onChange = saveLayout;
  conn.onOpen = () => {
    void plots.watch().catch(() => undefined);
    timeline.start();
  };
  root.append(
    h("header", {}, h("h1", {}, "situate"), robot, runInfo, status, share, shareNote),
    staleBanner,
    replayBanner,
    outcome,
    h("main", {}, h("div", { class: "col" }, manager.el, panels.el, monitors.el), h("div", { class: "col" }, world.el, plots.el, graph.el, events.el)),
    timeline.el,
  );
}

start();
