// The WebSocket to the GUI server: requests with replies (the link's verbs and JSON), and a
// stream of telemetry and events. Reconnects by itself.

export type Json = null | boolean | number | string | Json[] | { [key: string]: Json };
export type JsonObject = { [key: string]: Json };

export interface WireError {
  kind: string;
  message: string;
  /** For a bad monitor condition: the condition with a caret under the error. */
  pointer?: string;
}

/** A request the manager (or the server) refused: its message is the link's. */
export class RefusedError extends Error {
  readonly kind: string;
  readonly pointer: string;
  constructor(e: WireError) {
    super(e.message);
    this.kind = e.kind;
    this.pointer = e.pointer ?? "";
  }
}

export interface Handlers {
  hello(msg: JsonObject): void;
  telemetry(msg: JsonObject): void;
  event(event: JsonObject): void;
  /** How the program's run ended (`{ok, summary}`), when it says. */
  outcome(outcome: JsonObject): void;
  status(connected: boolean, text: string): void;
}

interface Pending {
  resolve(value: Json): void;
  reject(error: Error): void;
}

export function isObject(j: Json | undefined): j is JsonObject {
  return typeof j === "object" && j !== null && !Array.isArray(j);
}

export class Connection {
  private ws: WebSocket | null = null;
  private nextId = 1;
  private readonly pending = new Map<number, Pending>();
  private readonly handlers: Handlers;
  private readonly url: string;
  private closed = false;
  /** Called after every (re)connection, to restore this tab's watch list. */
  onOpen: () => void = () => {};

  constructor(url: string, handlers: Handlers) {
    this.url = url;
    this.handlers = handlers;
    this.open();
  }

  private open(): void {
    if (this.closed) return;
    const ws = new WebSocket(this.url);
    this.ws = ws;
    ws.onopen = () => {
      this.handlers.status(true, "connected");
      this.onOpen();
    };
    ws.onclose = () => {
      this.ws = null;
      for (const p of this.pending.values()) p.reject(new Error("the connection to the robot closed"));
      this.pending.clear();
      this.handlers.status(false, "disconnected — reconnecting…");
      window.setTimeout(() => this.open(), 1000);
    };
    ws.onmessage = (ev: MessageEvent) => {
      if (typeof ev.data !== "string") return;
      let msg: Json;
      try {
        msg = JSON.parse(ev.data) as Json;
      } catch {
        return;
      }
      if (!isObject(msg)) return;
      this.dispatch(msg);
    };
  }

  private dispatch(msg: JsonObject): void {
    switch (msg["type"]) {
      case "hello":
        this.handlers.hello(msg);
        break;
      case "telemetry":
        this.handlers.telemetry(msg);
        break;
      case "event": {
        const e = msg["event"];
        if (isObject(e)) this.handlers.event(e);
        break;
      }
      case "outcome":
        this.handlers.outcome(msg);
        break;
      case "reply": {
        const id = msg["id"];
        if (typeof id !== "number") return;
        const p = this.pending.get(id);
        if (!p) return;
        this.pending.delete(id);
        const err = msg["error"];
        if (isObject(err)) {
          const pointer = err["pointer"];
          p.reject(
            new RefusedError({
              kind: String(err["kind"] ?? "error"),
              message: String(err["message"] ?? ""),
              ...(typeof pointer === "string" ? { pointer } : {}),
            }),
          );
        } else {
          p.resolve(msg["ok"] ?? null);
        }
        break;
      }
      default:
        break;
    }
  }

  /** Sends one request (a verb of the link's protocol, or `watch`); resolves with its `ok` value. */
  request(verb: string, args: JsonObject = {}): Promise<Json> {
    const ws = this.ws;
    if (!ws || ws.readyState !== WebSocket.OPEN) {
      return Promise.reject(new Error("not connected to the robot"));
    }
    const id = this.nextId++;
    return new Promise<Json>((resolve, reject) => {
      this.pending.set(id, { resolve, reject });
      ws.send(JSON.stringify({ id, verb, args }));
    });
  }

  close(): void {
    this.closed = true;
    this.ws?.close();
  }
}
