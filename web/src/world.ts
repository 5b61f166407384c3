// The world view: the simulator's map (walls, obstacles, doors, barcodes, buttons, the goal office,
// elevator cars) on the robot's floor, the robot (`truth.pose`), its sonar rays (`sonar.range`) and
// the cars' state (`truth.cars`), the people walking on the floor shown (`truth.people`).

import { isObject, type Json, type JsonObject } from "./conn";
import { h, num, setText } from "./dom";

type Pt = [number, number];

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

export class WorldView {
  readonly el: HTMLElement;
  private readonly canvas: HTMLCanvasElement;
  private readonly floorSel: HTMLSelectElement;
  private readonly info: HTMLElement;
  private map: JsonObject | null = null;
  private draws = 0;
  private trail: Pt[] = [];

  constructor() {
    this.canvas = h("canvas", { width: 640, height: 480, "data-testid": "world-canvas" });
    this.floorSel = h("select", { "data-testid": "world-floor" }, h("option", { value: "auto" }, "the robot's floor"));
    this.info = h("span", { class: "mono", "data-testid": "world-info" }, "no truth.pose signal yet");
    this.el = h("section", { class: "panel", id: "world" }, h("h2", {}, "World"), h("div", { class: "row" }, "floor ", this.floorSel, " ", this.info), this.canvas);
  }

  setMap(world: Json | undefined): void {
    this.map = isObject(world) ? world : null;
    const floors = this.map && Array.isArray(this.map["floors"]) ? this.map["floors"].filter(isObject) : [];
    this.floorSel.replaceChildren(h("option", { value: "auto" }, "the robot's floor"), ...floors.map((f) => h("option", { value: String(num(f["level"])) }, `floor ${num(f["level"])}`)));
  }

  /** Bounds of the map (all floors), or a 10 m square around the origin without one. */
  private bounds(extra: Pt | null): [number, number, number, number] {
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
      for (const p of this.trail) grow(p[0], p[1]);
    }
    if (extra) grow(extra[0], extra[1]);
    const m = 0.5;
    return [x0 - m, y0 - m, x1 + m, y1 + m];
  }

  update(signals: Json | undefined): void {
    const sig = isObject(signals) ? signals : {};
    const pose = values(sig["truth.pose"]);
    const sonar = values(sig["sonar.range"]);
    const cars = values(sig["truth.cars"]);
    const people = values(sig["truth.people"]);
    const hasPose = isObject(pose);
    const robot: { x: number; y: number; theta: number; floor: number } | null = hasPose
      ? { x: num(pose["x"]), y: num(pose["y"]), theta: num(pose["theta"]), floor: num(pose["floor"]) }
      : null;
    if (robot) {
      this.trail.push([robot.x, robot.y]);
      if (this.trail.length > 600) this.trail.shift();
    }
    const floor = this.floorSel.value === "auto" ? (robot?.floor ?? 0) : Number(this.floorSel.value);
    const c = this.canvas.getContext("2d");
    if (!c) return;
    const W = this.canvas.width;
    const H = this.canvas.height;
    const [bx0, by0, bx1, by1] = this.bounds(robot ? [robot.x, robot.y] : null);
    const scale = Math.min(W / (bx1 - bx0), H / (by1 - by0));
    const X = (x: number) => (x - bx0) * scale;
    const Y = (y: number) => H - (y - by0) * scale;
    c.fillStyle = "#fafafa";
    c.fillRect(0, 0, W, H);
    const floors = this.map && Array.isArray(this.map["floors"]) ? this.map["floors"].filter(isObject) : [];
    const f = floors.find((x) => num(x["level"]) === floor);
    if (f) {
      const office = pts(f["office"]);
      if (office.length > 2) this.poly(c, office, X, Y, "rgba(255, 215, 0, 0.25)", null);
      for (const o of Array.isArray(f["obstacles"]) ? f["obstacles"] : []) this.poly(c, pts(o), X, Y, "#bbb", "#888");
      c.lineWidth = 3;
      c.strokeStyle = "#222";
      for (const s of segs(f["walls"])) this.line(c, s, X, Y);
      c.lineWidth = 3;
      c.strokeStyle = "#3a7";
      c.setLineDash([6, 4]);
      for (const s of segs(f["doors"])) this.line(c, s, X, Y);
      c.setLineDash([]);
      c.font = "10px sans-serif";
      for (const b of Array.isArray(f["barcodes"]) ? f["barcodes"].filter(isObject) : []) {
        c.fillStyle = "#00f";
        c.fillRect(X(num(b["x"])) - 3, Y(num(b["y"])) - 3, 6, 6);
        c.fillText(String(num(b["id"])), X(num(b["x"])) + 4, Y(num(b["y"])) - 4);
      }
      for (const b of Array.isArray(f["buttons"]) ? f["buttons"].filter(isObject) : []) {
        c.fillStyle = "#c0c";
        c.beginPath();
        c.arc(X(num(b["x"])), Y(num(b["y"])), 4, 0, 2 * Math.PI);
        c.fill();
        c.fillText(typeof b["label"] === "string" ? b["label"] : "", X(num(b["x"])) + 5, Y(num(b["y"])) + 10);
      }
    }
    // Elevator cars: drawn on every floor; solid when the car is at this floor.
    const carList = this.map && Array.isArray(this.map["cars"]) ? this.map["cars"].filter(isObject) : [];
    const carFloor = isObject(cars) && Array.isArray(cars["floor"]) ? cars["floor"] : [];
    const carDoor = isObject(cars) && Array.isArray(cars["door"]) ? cars["door"] : [];
    carList.forEach((car, i) => {
      const at = num(carFloor[i], NaN);
      const here = Number.isFinite(at) && Math.abs(at - floor) < 0.05;
      const [x0, y0, x1, y1] = [num(car["x0"]), num(car["y0"]), num(car["x1"]), num(car["y1"])];
      c.fillStyle = here ? "rgba(70, 130, 180, 0.35)" : "rgba(70, 130, 180, 0.08)";
      c.fillRect(X(Math.min(x0, x1)), Y(Math.max(y0, y1)), Math.abs(x1 - x0) * scale, Math.abs(y1 - y0) * scale);
      c.fillStyle = "#246";
      c.font = "11px sans-serif";
      c.fillText(`car ${num(car["id"])}${Number.isFinite(at) ? ` @ ${at.toFixed(2)}` : ""}`, X(Math.min(x0, x1)) + 2, Y(Math.max(y0, y1)) + 12);
      const door = segs([car["door"] ?? null])[0];
      if (door) {
        const open = num(carDoor[i], 0);
        c.strokeStyle = open > 0.5 ? "#3a7" : "#a33";
        c.lineWidth = 4;
        c.setLineDash(open > 0.02 ? [4, 4] : []);
        this.line(c, door, X, Y);
        c.setLineDash([]);
      }
    });
    // People on this floor: small circles.
    if (isObject(people) && Array.isArray(people["x"]) && Array.isArray(people["y"]) && Array.isArray(people["floor"])) {
      const [px, py, pf] = [people["x"], people["y"], people["floor"]];
      c.fillStyle = "rgba(120, 60, 160, 0.7)";
      for (let i = 0; i < px.length; i++) {
        if (num(pf[i], NaN) !== floor) continue;
        c.beginPath();
        c.arc(X(num(px[i])), Y(num(py[i])), Math.max(3, 0.25 * scale), 0, 2 * Math.PI);
        c.fill();
      }
    }
    // The trail, the sonar rays, the robot.
    if (this.trail.length > 1) {
      c.strokeStyle = "rgba(0,0,0,0.15)";
      c.lineWidth = 1;
      c.beginPath();
      this.trail.forEach(([x, y], i) => (i ? c.lineTo(X(x), Y(y)) : c.moveTo(X(x), Y(y))));
      c.stroke();
    }
    if (robot) {
      const radius = this.map ? num(this.map["robot_radius"], 0.25) : 0.25;
      if (Array.isArray(sonar)) {
        c.strokeStyle = "rgba(255, 120, 0, 0.6)";
        c.lineWidth = 1;
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
      const pr = Math.max(4, radius * scale);
      c.arc(px, py, pr, 0, 2 * Math.PI);
      c.fill();
      c.strokeStyle = "#fff";
      c.lineWidth = 2;
      c.beginPath();
      c.moveTo(px, py);
      c.lineTo(X(robot.x + radius * Math.cos(robot.theta)), Y(robot.y + radius * Math.sin(robot.theta)));
      c.stroke();
      this.draws++;
      this.canvas.dataset["robotPx"] = px.toFixed(1);
      this.canvas.dataset["robotPy"] = py.toFixed(1);
      this.canvas.dataset["robotPr"] = pr.toFixed(1);
      this.canvas.dataset["draws"] = String(this.draws);
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
