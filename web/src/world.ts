// The world view: the simulator's map (walls, obstacles, doors, barcodes, buttons, the goal office,
// elevator cars) on the robot's floor, the robot (`truth.pose`), its sonar rays (`sonar.range`) and
// the cars' state (`truth.cars`: a car's door is open only on the floor the car is at), the people
// walking on the floor shown (`truth.people`).
// A `truth.pose` without `floor` (a ROS 2 ground-truth Odometry mapped onto it: x, y, theta, v, w)
// is on the floor of the robot's `floor` signal (not drawn until that has a value), or on floor 0
// when the robot has no `floor` signal.
// Zoom with the wheel, pan by dragging, "Reset view" to fit the map again; the view follows the
// robot (its floor, and its position when zoomed in) until the user pans. The canvas is drawn at
// the page's own pixel size, so labels keep their size whatever the window's width.

import { isObject, type Json, type JsonObject } from "./conn";
import { cssVar, h, num, setText } from "./dom";

type Pt = [number, number];

/** Label size in CSS pixels: readable at the default view. */
const LABEL_PX = 13;
const TRAIL_POINTS = 2000;

function pts(j: Json | undefined): Pt[] {
  if (!Array.isArray(j)) return [];
  return j.filter((p): p is Json[] => Array.isArray(p) && p.length >= 2).map((p) => [num(p[0]), num(p[1])]);
}

function segs(j: Json | undefined): [number, number, number, number][] {
  if (!Array.isArray(j)) return [];
  return j.filter((s): s is Json[] => Array.isArray(s) && s.length >= 4).map((s) => [num(s[0]), num(s[1]), num(s[2]), num(s[3])]);
}

function values(reading: Json | undefined): Json | undefined {
  return isObject(reading) ? reading["value"] : undefined;
}

interface Robot {
  x: number;
  y: number;
  theta: number;
  floor: number;
}

/**
 * The robot of the signals: `truth.pose`, its floor from `floor` when the pose has none (0 when the
 * robot has no `floor` signal; none while its `floor` has no value yet, a floor not yet known).
 */
function robotOf(signals: Json | undefined): Robot | null {
  const sig = isObject(signals) ? signals : {};
  const pose = values(sig["truth.pose"]);
  if (!isObject(pose)) return null;
  let floor = pose["floor"];
  if (typeof floor !== "number") {
    floor = sig["floor"] === undefined ? 0 : values(sig["floor"]);
    if (typeof floor !== "number") return null;
  }
  return { x: num(pose["x"]), y: num(pose["y"]), theta: num(pose["theta"]), floor };
}

export class WorldView {
  readonly el: HTMLElement;
  private readonly canvas: HTMLCanvasElement;
  private readonly floorSel: HTMLSelectElement;
  private readonly follow: HTMLInputElement;
  private readonly info: HTMLElement;
  private readonly pastNote: HTMLElement;
  private map: JsonObject | null = null;
  private draws = 0;
  /** The robot's trail on each floor (metres), and when this run's first point came (wall s). */
  private trails = new Map<number, Pt[]>();
  private trailSince: number | null = null;
  private signals: Json | undefined = undefined;
  private robot: Robot | null = null;
  /** The view: zoom over the fitted map, and the world point at the canvas's centre (null: the map's centre). */
  private zoom = 1;
  private center: Pt | null = null;
  private drag: { x: number; y: number } | null = null;
  private view = { W: 0, H: 0, scale: 1, cx: 0, cy: 0 };

  constructor(stale: HTMLElement) {
    this.canvas = h("canvas", { width: 640, height: 480, class: "world", "data-testid": "world-canvas" });
    this.floorSel = h("select", { "data-testid": "world-floor" }, h("option", { value: "auto" }, "the robot's floor"));
    this.floorSel.addEventListener("change", () => this.draw());
    this.follow = h("input", { type: "checkbox", checked: true, "data-testid": "world-follow" });
    this.follow.addEventListener("change", () => {
      if (this.follow.checked) this.center = null;
      this.draw();
    });
    const reset = h("button", { "data-testid": "world-reset", title: "fit the whole floor, follow the robot" }, "Reset view");
    reset.addEventListener("click", () => this.resetView());
    this.info = h("span", { class: "mono", "data-testid": "world-info" }, "no truth.pose signal yet");
    this.pastNote = h("span", { class: "past-note", "data-testid": "world-past" });
    this.el = h(
      "section",
      { class: "panel live", id: "world" },
      h("h2", {}, "World", stale, this.pastNote),
      h("div", { class: "row" }, "floor ", this.floorSel, h("label", {}, this.follow, " follow the robot"), reset),
      h("div", { class: "row" }, this.info),
      this.canvas,
      h("div", { class: "dim" }, "wheel: zoom · drag: pan"),
    );
    this.canvas.addEventListener("wheel", (e) => this.onWheel(e), { passive: false });
    this.canvas.addEventListener("pointerdown", (e) => {
      this.drag = { x: e.clientX, y: e.clientY };
      this.canvas.setPointerCapture(e.pointerId);
      this.canvas.classList.add("dragging");
    });
    this.canvas.addEventListener("pointermove", (e) => {
      if (!this.drag) return;
      const dx = e.clientX - this.drag.x;
      const dy = e.clientY - this.drag.y;
      if (dx === 0 && dy === 0) return;
      this.drag = { x: e.clientX, y: e.clientY };
      const k = this.pixelRatio() / this.view.scale;
      // Panning takes the view away from the robot: stop following (Reset view follows again).
      this.follow.checked = false;
      this.center = [this.view.cx - dx * k, this.view.cy + dy * k];
      this.draw();
    });
    const endDrag = () => {
      this.drag = null;
      this.canvas.classList.remove("dragging");
    };
    this.canvas.addEventListener("pointerup", endDrag);
    this.canvas.addEventListener("pointercancel", endDrag);
  }

  setMap(world: Json | undefined): void {
    this.map = isObject(world) ? world : null;
    const floors = this.map && Array.isArray(this.map["floors"]) ? this.map["floors"].filter(isObject) : [];
    const chosen = this.floorSel.value;
    this.floorSel.replaceChildren(h("option", { value: "auto" }, "the robot's floor"), ...floors.map((f) => h("option", { value: String(num(f["level"])) }, `floor ${num(f["level"])}`)));
    if ([...this.floorSel.options].some((o) => o.value === chosen)) this.floorSel.value = chosen;
  }

  /** A new run: the old run's trails go. */
  clear(): void {
    this.trails.clear();
    this.trailSince = null;
    this.robot = null;
    this.signals = undefined;
    this.draw();
  }

  resetView(): void {
    this.zoom = 1;
    this.center = null;
    this.follow.checked = true;
    this.floorSel.value = "auto";
    this.draw();
  }

  private pixelRatio(): number {
    return window.devicePixelRatio || 1;
  }

  private onWheel(e: WheelEvent): void {
    e.preventDefault();
    const factor = Math.exp(-e.deltaY * 0.0015);
    const zoom = Math.min(50, Math.max(0.5, this.zoom * factor));
    const { W, H, scale, cx, cy } = this.view;
    if (!this.follow.checked || !this.robot) {
      // Zoom about the point under the cursor.
      const r = this.canvas.getBoundingClientRect();
      const px = (e.clientX - r.left) * (W / Math.max(1, r.width));
      const py = (e.clientY - r.top) * (H / Math.max(1, r.height));
      const wx = cx + (px - W / 2) / scale;
      const wy = cy - (py - H / 2) / scale;
      const s2 = (scale / this.zoom) * zoom;
      this.center = [wx - (px - W / 2) / s2, wy + (py - H / 2) / s2];
    }
    this.zoom = zoom;
    this.draw();
  }

  /** Bounds of the map (all floors), or a 10 m square around the origin and the trail without one. */
  private bounds(): [number, number, number, number] {
    let [x0, y0, x1, y1] = [Infinity, Infinity, -Infinity, -Infinity];
    const grow = (x: number, y: number) => {
      if (!Number.isFinite(x) || !Number.isFinite(y)) return;
      x0 = Math.min(x0, x);
      y0 = Math.min(y0, y);
      x1 = Math.max(x1, x);
      y1 = Math.max(y1, y);
    };
    const floors = this.map && Array.isArray(this.map["floors"]) ? this.map["floors"].filter(isObject) : [];
    for (const f of floors) {
      for (const s of segs(f["walls"])) {
        grow(s[0], s[1]);
        grow(s[2], s[3]);
      }
      for (const o of Array.isArray(f["obstacles"]) ? f["obstacles"] : []) for (const p of pts(o)) grow(p[0], p[1]);
    }
    if (!Number.isFinite(x0)) {
      grow(-5, -5);
      grow(5, 5);
      for (const t of this.trails.values()) for (const p of t) grow(p[0], p[1]);
    }
    if (this.robot) grow(this.robot.x, this.robot.y);
    const m = 0.5;
    return [x0 - m, y0 - m, x1 + m, y1 + m];
  }

  private setSignals(signals: Json | undefined): void {
    this.robot = robotOf(signals);
    this.signals = signals;
  }

  /** A past cycle (the timeline, paused): the robot, sonar, cars and people as they were then;
   *  the trails are left as they are. `note`: which cycle, in the panel's title. */
  showPast(signals: Json | undefined, note: string): void {
    setText(this.pastNote, note);
    this.setSignals(signals);
    this.draw();
  }

  update(signals: Json | undefined, wall: number): void {
    setText(this.pastNote, "");
    this.setSignals(signals);
    if (this.robot) this.addTrail(this.robot, wall);
    this.draw();
  }

  /** A live sample while the view shows the past: the trail grows, nothing else changes. */
  keepTrail(signals: Json | undefined, wall: number): void {
    const robot = robotOf(signals);
    if (robot) this.addTrail(robot, wall);
  }

  private addTrail(robot: Robot, wall: number): void {
    const trail = this.trails.get(robot.floor) ?? [];
    const last = trail[trail.length - 1];
    if (!last || Math.hypot(last[0] - robot.x, last[1] - robot.y) >= 0.01) {
      trail.push([robot.x, robot.y]);
      if (trail.length > TRAIL_POINTS) trail.shift();
    }
    this.trails.set(robot.floor, trail);
    this.trailSince ??= wall;
  }

  private draw(): void {
    const sig = isObject(this.signals) ? this.signals : {};
    const sonar = values(sig["sonar.range"]);
    const cars = values(sig["truth.cars"]);
    const people = values(sig["truth.people"]);
    const robot = this.robot;
    const floor = this.floorSel.value === "auto" ? (robot?.floor ?? 0) : Number(this.floorSel.value);
    // Draw at the page's pixel size (sharp, labels at their size at any width).
    const dpr = this.pixelRatio();
    const cssW = this.canvas.clientWidth > 0 ? this.canvas.clientWidth : 640;
    const [bx0, by0, bx1, by1] = this.bounds();
    // As tall as the building's shape asks, within reason (a wide building leaves no empty band).
    const W = Math.max(100, Math.round(cssW * dpr));
    const H = Math.round(W * Math.min(0.85, Math.max(0.5, (by1 - by0) / (bx1 - bx0))));
    if (this.canvas.width !== W) this.canvas.width = W;
    if (this.canvas.height !== H) this.canvas.height = H;
    const c = this.canvas.getContext("2d");
    if (!c) return;
    const scale = Math.min(W / (bx1 - bx0), H / (by1 - by0)) * this.zoom;
    let [cx, cy]: Pt = this.center ?? [(bx0 + bx1) / 2, (by0 + by1) / 2];
    if (this.follow.checked && robot && this.zoom > 1) [cx, cy] = [robot.x, robot.y];
    this.view = { W, H, scale, cx, cy };
    const X = (x: number) => W / 2 + (x - cx) * scale;
    const Y = (y: number) => H / 2 - (y - cy) * scale;
    const labels: { text: string; px: number }[] = [];
    const labelFont = `${LABEL_PX * dpr}px sans-serif`;
    const halo = cssVar("--canvas-halo", "rgba(255,255,255,0.85)");
    // Labels are drawn last, on top, each moved down until it overlaps no other (cars side by side).
    // Minor labels (barcodes, buttons) give way: drawn only where they overlap nothing.
    const queued: { text: string; x: number; y: number; color: string; minor: boolean }[] = [];
    const label = (text: string, x: number, y: number, color: string, minor = false) => queued.push({ text, x, y, color, minor });
    const drawLabels = () => {
      c.font = labelFont;
      c.lineWidth = 3 * dpr;
      c.strokeStyle = halo;
      c.lineJoin = "round";
      const line = (LABEL_PX + 3) * dpr;
      const placed: [number, number, number, number][] = [];
      for (const q of [...queued.filter((x) => !x.minor), ...queued.filter((x) => x.minor)]) {
        const w = c.measureText(q.text).width;
        let y = q.y;
        const hits = (yy: number) => placed.some(([x0, y0, x1, y1]) => q.x < x1 && q.x + w > x0 && yy - line < y1 && yy > y0);
        if (q.minor && hits(y)) continue;
        for (let tries = 0; tries < 3 && hits(y); tries++) y += line;
        placed.push([q.x, y - line, q.x + w, y]);
        c.strokeText(q.text, q.x, y);
        c.fillStyle = q.color;
        c.fillText(q.text, q.x, y);
        labels.push({ text: q.text, px: LABEL_PX });
      }
    };
    const fg = cssVar("--canvas-fg", "#222");
    const labelColor = cssVar("--canvas-label", "#123");
    c.fillStyle = cssVar("--canvas-bg", "#fafafa");
    c.fillRect(0, 0, W, H);
    const floors = this.map && Array.isArray(this.map["floors"]) ? this.map["floors"].filter(isObject) : [];
    const f = floors.find((x) => num(x["level"]) === floor);
    if (f) {
      const office = pts(f["office"]);
      if (office.length > 2) this.poly(c, office, X, Y, "rgba(255, 215, 0, 0.25)", null);
      for (const o of Array.isArray(f["obstacles"]) ? f["obstacles"] : []) this.poly(c, pts(o), X, Y, "#bbb", "#888");
      c.lineWidth = 3 * dpr;
      c.strokeStyle = fg;
      for (const s of segs(f["walls"])) this.line(c, s, X, Y);
      c.lineWidth = 3 * dpr;
      c.strokeStyle = "#3a7";
      c.setLineDash([6, 4]);
      for (const s of segs(f["doors"])) this.line(c, s, X, Y);
      c.setLineDash([]);
      for (const b of Array.isArray(f["barcodes"]) ? f["barcodes"].filter(isObject) : []) {
        c.fillStyle = "#36f";
        c.fillRect(X(num(b["x"])) - 3 * dpr, Y(num(b["y"])) - 3 * dpr, 6 * dpr, 6 * dpr);
        label(String(num(b["id"])), X(num(b["x"])) + 5 * dpr, Y(num(b["y"])) - 5 * dpr, "#36f", true);
      }
      for (const b of Array.isArray(f["buttons"]) ? f["buttons"].filter(isObject) : []) {
        c.fillStyle = "#c0c";
        c.beginPath();
        c.arc(X(num(b["x"])), Y(num(b["y"])), 4 * dpr, 0, 2 * Math.PI);
        c.fill();
        if (typeof b["label"] === "string") label(b["label"], X(num(b["x"])) + 6 * dpr, Y(num(b["y"])) + 14 * dpr, "#c0c", true);
      }
    }
    // Elevator cars: drawn on every floor; solid when the car is at this floor. Its door is open
    // only where the car is: on every other floor (and while it moves) the landing door is closed.
    const carList = this.map && Array.isArray(this.map["cars"]) ? this.map["cars"].filter(isObject) : [];
    const carFloor = isObject(cars) && Array.isArray(cars["floor"]) ? cars["floor"] : [];
    const carDoor = isObject(cars) && Array.isArray(cars["door"]) ? cars["door"] : [];
    const carsDrawn: { id: number; floor: number | null; here: boolean; door: string | null }[] = [];
    carList.forEach((car, i) => {
      const at = num(carFloor[i], NaN);
      const here = Number.isFinite(at) && Math.abs(at - floor) < 0.05;
      const [x0, y0, x1, y1] = [num(car["x0"]), num(car["y0"]), num(car["x1"]), num(car["y1"])];
      c.fillStyle = here ? "rgba(70, 130, 180, 0.35)" : "rgba(70, 130, 180, 0.08)";
      c.fillRect(X(Math.min(x0, x1)), Y(Math.max(y0, y1)), Math.abs(x1 - x0) * scale, Math.abs(y1 - y0) * scale);
      const door = segs([car["door"] ?? null])[0];
      const carOpen = num(carDoor[i], NaN);
      // The door as seen on this floor: the car's own where the car is, else the landing's (closed).
      const open = !Number.isFinite(carOpen) ? NaN : here ? carOpen : 0;
      if (door) {
        c.strokeStyle = open > 0.5 ? "#3a7" : "#d44";
        c.lineWidth = 4 * dpr;
        c.setLineDash(open > 0.02 ? [4 * dpr, 4 * dpr] : []);
        this.line(c, door, X, Y);
        c.setLineDash([]);
      }
      const lx = X(Math.min(x0, x1)) + 3 * dpr;
      const ly = Y(Math.max(y0, y1)) + (LABEL_PX + 2) * dpr;
      // Short lines (the cars stand side by side): "car 1", its floor, its door.
      label(`car ${num(car["id"])}`, lx, ly, labelColor);
      if (Number.isFinite(at)) label(`fl ${Number.isInteger(at) ? at : at.toFixed(1)}`, lx, ly + (LABEL_PX + 3) * dpr, labelColor);
      let state: string | null = null;
      if (door && Number.isFinite(open)) {
        state = open > 0.98 ? "open" : open < 0.02 ? "closed" : `${Math.round(open * 100)} %`;
        label(state, lx, ly + 2 * (LABEL_PX + 3) * dpr, open > 0.5 ? "#2a8a2a" : "#d44");
      }
      carsDrawn.push({ id: num(car["id"]), floor: Number.isFinite(at) ? at : null, here, door: state });
    });
    // People on this floor: small circles.
    let peopleDrawn = 0;
    if (isObject(people) && Array.isArray(people["x"]) && Array.isArray(people["y"]) && Array.isArray(people["floor"])) {
      const [px, py, pf] = [people["x"], people["y"], people["floor"]];
      c.fillStyle = "rgba(120, 60, 160, 0.7)";
      for (let i = 0; i < px.length; i++) {
        if (num(pf[i], NaN) !== floor) continue;
        c.beginPath();
        c.arc(X(num(px[i])), Y(num(py[i])), Math.max(3 * dpr, 0.25 * scale), 0, 2 * Math.PI);
        c.fill();
        peopleDrawn++;
      }
    }
    // The trail, the sonar rays, the robot.
    const trail = this.trails.get(floor) ?? [];
    if (trail.length > 1) {
      c.strokeStyle = "rgba(128, 128, 128, 0.6)";
      c.lineWidth = 1.5 * dpr;
      c.beginPath();
      trail.forEach(([x, y], i) => (i ? c.lineTo(X(x), Y(y)) : c.moveTo(X(x), Y(y))));
      c.stroke();
    }
    drawLabels();
    const counts: Record<string, number> = {};
    for (const [f, t] of this.trails) counts[String(f)] = t.length;
    Object.assign(this.canvas.dataset, {
      labels: JSON.stringify(labels),
      cars: JSON.stringify(carsDrawn),
      trail: JSON.stringify(counts),
      people: String(peopleDrawn),
      trailSince: this.trailSince === null ? "" : String(this.trailSince),
      floor: String(floor),
      zoom: this.zoom.toFixed(3),
      centerX: cx.toFixed(3),
      centerY: cy.toFixed(3),
      // The robot as drawn (its pose in the sample this draw used), for tests; empty off its floor.
      robotX: robot && robot.floor === floor ? robot.x.toFixed(3) : "",
      robotY: robot && robot.floor === floor ? robot.y.toFixed(3) : "",
    });
    if (robot && robot.floor === floor) {
      const radius = this.map ? num(this.map["robot_radius"], 0.25) : 0.25;
      if (Array.isArray(sonar)) {
        c.strokeStyle = "rgba(255, 120, 0, 0.6)";
        c.lineWidth = dpr;
        sonar.forEach((r, i) => {
          let range = num(r, Infinity);
          if (!Number.isFinite(range)) range = 10;
          const a = robot.theta + (i * 15 * Math.PI) / 180;
          c.beginPath();
          c.moveTo(X(robot.x), Y(robot.y));
          c.lineTo(X(robot.x + range * Math.cos(a)), Y(robot.y + range * Math.sin(a)));
          c.stroke();
        });
      }
      const px = X(robot.x);
      const py = Y(robot.y);
      c.fillStyle = "#d00";
      c.beginPath();
      const pr = Math.max(4 * dpr, radius * scale);
      c.arc(px, py, pr, 0, 2 * Math.PI);
      c.fill();
      c.strokeStyle = "#fff";
      c.lineWidth = 2 * dpr;
      c.beginPath();
      c.moveTo(px, py);
      c.lineTo(X(robot.x + radius * Math.cos(robot.theta)), Y(robot.y + radius * Math.sin(robot.theta)));
      c.stroke();
      this.draws++;
      this.canvas.dataset["robotPx"] = px.toFixed(1);
      this.canvas.dataset["robotPy"] = py.toFixed(1);
      this.canvas.dataset["robotPr"] = pr.toFixed(1);
      this.canvas.dataset["draws"] = String(this.draws);
    }
    if (robot) {
      setText(this.info, `robot at (${robot.x.toFixed(2)}, ${robot.y.toFixed(2)}) m, θ ${((((robot.theta * 180) / Math.PI) % 360) + 360) % 360 | 0}°, floor ${robot.floor}; showing floor ${floor}`);
    }
  }

  private line(c: CanvasRenderingContext2D, s: [number, number, number, number], X: (x: number) => number, Y: (y: number) => number): void {
    c.beginPath();
    c.moveTo(X(s[0]), Y(s[1]));
    c.lineTo(X(s[2]), Y(s[3]));
    c.stroke();
  }

  private poly(c: CanvasRenderingContext2D, p: Pt[], X: (x: number) => number, Y: (y: number) => number, fill: string, stroke: string | null): void {
    if (p.length < 2) return;
    c.beginPath();
    p.forEach(([x, y], i) => (i ? c.lineTo(X(x), Y(y)) : c.moveTo(X(x), Y(y))));
    c.closePath();
    c.fillStyle = fill;
    c.fill();
    if (stroke) {
      c.strokeStyle = stroke;
      c.lineWidth = 1;
      c.stroke();
    }
  }
}
