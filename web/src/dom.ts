// Tiny DOM helpers (no UI framework).

import type { Json } from "./conn";

type Attrs = Record<string, string | number | boolean | undefined>;
type Child = Node | string | null | undefined | false;

/** Creates an element with attributes (`on*` values are not supported: use addEventListener). */
export function h<K extends keyof HTMLElementTagNameMap>(
  tag: K,
  attrs: Attrs = {},
  ...children: Child[]
): HTMLElementTagNameMap[K] {
  const el = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === false) continue;
    if (k === "class") el.className = String(v);
    else el.setAttribute(k, v === true ? "" : String(v));
  }
  for (const c of children) {
    if (c === null || c === undefined || c === false) continue;
    el.append(typeof c === "string" ? document.createTextNode(c) : c);
  }
  return el;
}

/** Sets an element's text only when it changed (keeps selections and avoids layout churn). */
export function setText(el: Element, text: string): void {
  if (el.textContent !== text) el.textContent = text;
}

/** A value in the JSON form of the link, shortened for display. */
export function show(v: Json | undefined, max = 400): string {
  if (v === undefined) return "—";
  const s = typeof v === "string" ? JSON.stringify(v) : JSON.stringify(v, (_k, x: unknown) => roundNumbers(x));
  return s.length > max ? s.slice(0, max) + "…" : s;
}

function roundNumbers(x: unknown): unknown {
  if (typeof x === "number" && !Number.isInteger(x)) return Number(x.toPrecision(6));
  return x;
}

/** Flattens the numeric leaves of a value: `{x: 1, r: [2, 3]}` → `[[".x", 1], [".r[0]", 2], [".r[1]", 3]]`. */
export function numericLeaves(v: Json | undefined, prefix = "", out: [string, number][] = []): [string, number][] {
  if (typeof v === "number") out.push([prefix, v]);
  else if (typeof v === "boolean") out.push([prefix, v ? 1 : 0]);
  else if (typeof v === "string" && (v === "inf" || v === "-inf" || v === "nan")) out.push([prefix, Number(v === "nan" ? NaN : v === "inf" ? Infinity : -Infinity)]);
  else if (Array.isArray(v)) v.forEach((x, i) => numericLeaves(x, `${prefix}[${i}]`, out));
  else if (v !== null && typeof v === "object") for (const [k, x] of Object.entries(v)) numericLeaves(x, `${prefix}.${k}`, out);
  return out;
}

/** Reads `path` (like `.x`, `[3]`, `.pose.theta`) inside a value. */
export function pick(v: Json | undefined, path: string): Json | undefined {
  const re = /\.([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]/gy;
  let cur: Json | undefined = v;
  let m: RegExpExecArray | null;
  let consumed = 0;
  while ((m = re.exec(path)) !== null) {
    consumed = re.lastIndex;
    if (m[1] !== undefined) {
      cur = cur !== null && typeof cur === "object" && !Array.isArray(cur) ? cur[m[1]] : undefined;
    } else if (m[2] !== undefined) {
      cur = Array.isArray(cur) ? cur[Number(m[2])] : undefined;
    }
  }
  return consumed === path.length ? cur : undefined;
}

export function num(v: Json | undefined, fallback = 0): number {
  if (typeof v === "number") return v;
  if (v === "inf") return Infinity;
  if (v === "-inf") return -Infinity;
  return fallback;
}

export function str(v: Json | undefined, fallback = ""): string {
  return typeof v === "string" ? v : fallback;
}

export function errorText(e: unknown): string {
  return e instanceof Error ? e.message : String(e);
}

// ----- the link's state: controls that need it, values that go stale without it ---------------

let linkUp = false;
/** The recording replayed, when the robot is a replay (its hello's `replay`): nothing on it can
 *  be changed. */
let replayOf: string | null = null;

type Control = HTMLButtonElement | HTMLInputElement | HTMLSelectElement;

function enable(el: Control): void {
  const changes = el.dataset["robot"] !== undefined;
  el.disabled = !linkUp || (changes && replayOf !== null);
  if (changes) {
    if (replayOf !== null) {
      el.dataset["title"] ??= el.title;
      el.title = `a replay of ${replayOf}: its robot ran the recording to the end, nothing on it can be changed (replay it again with --set or --robot)`;
    } else if (el.dataset["title"] !== undefined) {
      el.title = el.dataset["title"];
      delete el.dataset["title"];
    }
  }
}

/** Marks a control that sends requests: disabled while the robot is not connected. */
export function linkControl<T extends Control>(el: T): T {
  el.dataset["link"] = "";
  enable(el);
  return el;
}

/** Marks a control that changes the robot (activation, parameters, the cycle): disabled while the
 *  robot is not connected, and in a replay. */
export function robotControl<T extends Control>(el: T): T {
  el.dataset["robot"] = "";
  return linkControl(el);
}

/** Enables or disables every control that needs the robot. */
export function setLinkUp(up: boolean): void {
  linkUp = up;
  for (const el of document.querySelectorAll<Control>("[data-link]")) enable(el);
}

/** The robot is a replay of `file` (null: a live robot): the controls that change it are off. */
export function setReplay(file: string | null): void {
  replayOf = file;
  for (const el of document.querySelectorAll<Control>("[data-link]")) enable(el);
}

/** The recording replayed, or null for a live robot. */
export function replayFile(): string | null {
  return replayOf;
}

/** A panel title's note, filled while the panel's values are stale ("last seen at cycle N, t s ago"). */
export function staleNote(): HTMLElement {
  return h("span", { class: "stale-note", "data-testid": "stale-note" });
}

/** A CSS custom property of the page (the colour scheme's), for canvas drawing. */
export function cssVar(name: string, fallback: string): string {
  const v = getComputedStyle(document.documentElement).getPropertyValue(name).trim();
  return v === "" ? fallback : v;
}
