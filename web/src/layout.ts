// The page's layout: the plots shown (each its signals), the skill panels open, and the cycle the
// timeline shows when paused. Kept in the page's address (`#plots=odom.x,odom.y|sonar.range[3]&
// open=wander&cycle=1234`), so a reload keeps it and the address can be shared. A formula's own
// `,` `|` and `%` are written %2C, %7C and %25 (`min(a, b)` → `min(a%2C b)`). Not in the
// browser's storage: a second tab opened on the robot starts empty, not with another tab's plots.

export interface Layout {
  /** Each plot's expressions, in order. */
  plots: string[][];
  /** The skill panels open. */
  open: string[];
  /** The cycle shown, paused on the timeline (null: live). */
  cycle: number | null;
}

/** What a layout may hold at most (a hand-made address is bounded too). */
const MAX_PLOTS = 32;
const MAX_PER_PLOT = 24;
const MAX_OPEN = 256;

/** An expression with the separators of the address's lists escaped. */
function escape(expr: string): string {
  return expr.replace(/[%,|]/g, (c) => ({ "%": "%25", ",": "%2C", "|": "%7C" })[c] ?? c);
}

function unescape(text: string): string {
  return text.replace(/%(25|2C|7C)/gi, (_, code: string) => ({ "25": "%", "2C": ",", "7C": "|" })[code.toUpperCase()] ?? "");
}

/** The address fragment (without `#`) of a layout; empty for the empty layout. */
export function encode(layout: Layout): string {
  const q = new URLSearchParams();
  if (layout.plots.length > 0) q.set("plots", layout.plots.map((p) => p.map(escape).join(",")).join("|"));
  if (layout.open.length > 0) q.set("open", layout.open.join(","));
  if (layout.cycle !== null) q.set("cycle", String(layout.cycle));
  return q.toString();
}

/** The layout in an address fragment (with or without `#`), or null when it holds none. What is
 *  malformed is left out (a cycle that is not a whole number, empty names), never an error: the
 *  page shows what it can. */
export function decode(fragment: string | null): Layout | null {
  if (fragment === null) return null;
  const q = new URLSearchParams(fragment.replace(/^#/, ""));
  if (!q.has("plots") && !q.has("open") && !q.has("cycle")) return null;
  const names = (text: string) => text.split(",").map((s) => unescape(s).trim()).filter((s) => s !== "" && s.length <= 500);
  const plots = (q.get("plots") ?? "")
    .split("|")
    .map((p) => names(p).slice(0, MAX_PER_PLOT))
    .filter((p) => p.length > 0)
    .slice(0, MAX_PLOTS);
  const open = names(q.get("open") ?? "").slice(0, MAX_OPEN);
  const c = q.get("cycle");
  const cycle = c !== null && /^\d{1,15}$/.test(c) ? Number(c) : null;
  return { plots, open, cycle };
}

/** Keeps `layout` in the address (replacing it: no history entry per change). */
export function save(layout: Layout): void {
  const fragment = encode(layout);
  history.replaceState(null, "", fragment === "" ? `${location.pathname}${location.search}` : `#${fragment}`);
}

/** The layout to start with: the address's, or none. */
export function initial(): Layout | null {
  return decode(location.hash);
}
