// An XY plot: one line of a plot drawn against another (`odom.y` against `odom.x`) on a canvas,
// through the rows where both have a value (a gap in either breaks the path), the newest point
// marked, both axes fitted.

import { cssVar } from "./dom";

export interface Line {
  name: string;
  /** One value per buffered row; null: a gap. */
  values: (number | null)[];
}

/** Draws `y` against `x` over rows `i0`..`i1` on `canvas` (`width` × `height` CSS px); returns
 *  how many points were drawn. */
export function drawXY(canvas: HTMLCanvasElement, width: number, height: number, x: Line, y: Line, i0: number, i1: number, colors: string[]): number {
  const dpr = window.devicePixelRatio || 1;
  canvas.style.width = `${width}px`;
  canvas.style.height = `${height}px`;
  canvas.width = Math.floor(width * dpr);
  canvas.height = Math.floor(height * dpr);
  const ctx = canvas.getContext("2d");
  if (!ctx) return 0;
  ctx.scale(dpr, dpr);
  const pts: ([number, number] | null)[] = [];
  let [x0, x1, y0, y1] = [Infinity, -Infinity, Infinity, -Infinity];
  for (let i = i0; i < i1; i++) {
    const a = x.values[i];
    const b = y.values[i];
    if (typeof a !== "number" || typeof b !== "number") {
      pts.push(null);
      continue;
    }
    pts.push([a, b]);
    [x0, x1, y0, y1] = [Math.min(x0, a), Math.max(x1, a), Math.min(y0, b), Math.max(y1, b)];
  }
  const n = pts.filter((p) => p !== null).length;
  const fg = cssVar("--canvas-fg", "#333");
  const grid = cssVar("--canvas-grid", "#ccc");
  const pad = { l: 60, r: 12, t: 10, b: 30 };
  const w = width - pad.l - pad.r;
  const hgt = height - pad.t - pad.b;
  ctx.strokeStyle = grid;
  ctx.strokeRect(pad.l, pad.t, w, hgt);
  ctx.fillStyle = fg;
  ctx.font = "12px sans-serif";
  ctx.fillText(`${y.name} against ${x.name}`, pad.l + 4, pad.t + 14);
  if (n === 0) return 0;
  // A degenerate range (a constant) gets a unit's width.
  const span = (a: number, b: number) => (b - a > 1e-12 ? b - a : 1);
  const [sx, sy] = [span(x0, x1), span(y0, y1)];
  const px = (v: number) => pad.l + ((v - x0) / sx) * w;
  const py = (v: number) => pad.t + hgt - ((v - y0) / sy) * hgt;
  ctx.fillText(x0.toPrecision(4), pad.l, height - 8);
  ctx.fillText(x1.toPrecision(4), pad.l + w - 40, height - 8);
  ctx.fillText(y1.toPrecision(4), 4, pad.t + 10);
  ctx.fillText(y0.toPrecision(4), 4, pad.t + hgt);
  ctx.strokeStyle = colors[0] ?? "#1f77b4";
  ctx.lineWidth = 1.5;
  ctx.beginPath();
  let pen = false;
  let last: [number, number] | null = null;
  for (const p of pts) {
    if (p === null) {
      pen = false;
      continue;
    }
    if (pen) ctx.lineTo(px(p[0]), py(p[1]));
    else ctx.moveTo(px(p[0]), py(p[1]));
    pen = true;
    last = p;
  }
  ctx.stroke();
  if (last) {
    ctx.fillStyle = colors[1] ?? "#d62728";
    ctx.beginPath();
    ctx.arc(px(last[0]), py(last[1]), 4, 0, 2 * Math.PI);
    ctx.fill();
  }
  return n;
}
