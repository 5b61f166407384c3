// Foxglove live: a real Foxglove WebSocket client (@foxglove/ws-protocol's FoxgloveClient) against
// the testbed's /foxglove; every value is checked over the sequencer link with the `situate` CLI.

import assert from "node:assert/strict";
import { after, before, describe, test } from "node:test";
import foxglove from "@foxglove/ws-protocol";
import { cli, cliDo, startTestbed, stopTestbed, until } from "./harness.mjs";

const { FoxgloveClient } = foxglove;

/** Node 20 has no WebSocket of its own (without a flag): then playwright-core's bundled `ws`. */
async function webSocketClass() {
  if (typeof globalThis.WebSocket === "function") return globalThis.WebSocket;
  const { createRequire } = await import("node:module");
  return createRequire(import.meta.url)("playwright-core/lib/utilsBundle").ws;
}

const decoder = new TextDecoder();

describe("Foxglove live", () => {
  let tb;
  let ws;
  let client;
  /** Everything the server sent, in order. */
  const got = { serverInfo: null, channels: [], statuses: [], params: [], messages: [], all: [] };

  before(async () => {
    tb = await startTestbed();
    const WS = await webSocketClass();
    ws = new WS(`ws://127.0.0.1:${tb.guiPort}/foxglove`, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
    client = new FoxgloveClient({ ws });
    client.on("serverInfo", (m) => (got.serverInfo = m));
    client.on("advertise", (channels) => got.channels.push(...channels));
    client.on("status", (m) => got.statuses.push(m));
    client.on("parameterValues", (m) => got.params.push(m));
    client.on("error", (e) => console.error(`foxglove client error: ${e?.message ?? e}`));
    client.on("message", (m) => {
      const msg = { sub: m.subscriptionId, timestamp: m.timestamp, body: JSON.parse(decoder.decode(m.data)) };
      got.messages.push(msg);
      got.all.push(msg);
    });
  });

  after(async () => {
    try {
      client?.close();
    } finally {
      await stopTestbed(tb);
    }
  });

  const channel = (topic) => got.channels.find((c) => c.topic === topic);
  const on = (sub) => got.messages.filter((m) => m.sub === sub);

  test("serverInfo and a channel per signal leaf, with JSON schemas", async () => {
    await until(() => got.serverInfo && channel("truth.pose.x"), "serverInfo and the channels");
    assert.equal(ws.protocol, "foxglove.websocket.v1", "the subprotocol was selected");
    const info = got.serverInfo;
    assert.equal(info.name, "situate");
    assert.ok(info.capabilities.includes("parameters"), JSON.stringify(info));
    assert.deepEqual(info.supportedEncodings, ["json"]);
    assert.match(info.sessionId, /^[0-9a-f]{12}$/, "the run id");
    for (const topic of ["truth.pose.x", "truth.pose.y", "sonar.range", "situate/events"]) {
      const c = channel(topic);
      assert.ok(c, `a channel ${topic}: ${got.channels.map((c) => c.topic).join(", ")}`);
      assert.equal(c.encoding, "json");
      assert.equal(c.schemaEncoding, "jsonschema");
      assert.deepEqual(JSON.parse(c.schema).required, ["cycle", "value"]);
    }
    assert.equal(new Set(got.channels.map((c) => c.id)).size, got.channels.length, "channel ids are unique");
  });

  test("a subscription streams every cycle, its values the robot's over the link", async () => {
    const x = client.subscribe(channel("truth.pose.x").id);
    await until(() => on(x).length >= 10, "ten messages of truth.pose.x");
    const first = on(x);
    // gui.circle is a device (it runs on its own thread, on the wall clock): under load a cycle may
    // pass without its write, so the cycles increase, mostly by one (each write is a message).
    for (let i = 1; i < first.length; i++) {
      assert.ok(first[i].body.cycle > first[i - 1].body.cycle, `in cycle order: ${JSON.stringify(first.slice(i - 1, i + 1).map((m) => m.body))}`);
      assert.ok(first[i].timestamp > first[i - 1].timestamp, "the manager's clock advances");
      assert.equal(typeof first[i].body.value, "number");
    }
    assert.ok(first.some((m, i) => i > 0 && m.body.cycle === first[i - 1].body.cycle + 1), "consecutive cycles: every write, not samples");
    assert.ok(new Set(first.map((m) => m.body.value)).size > 3, "the pose moves");
    // Stopped, the last value written is the one the link reads.
    await cliDo(tb.linkPort, "cycle", "stop");
    try {
      await until(async () => (await cli(tb.linkPort, "stats")).running === false, "the manager stopped over the link");
      const reading = await cli(tb.linkPort, "query", "truth.pose.x");
      const match = await until(() => on(x).find((m) => m.body.cycle === reading.cycle), `the message of cycle ${reading.cycle}`);
      assert.equal(match.body.value, reading.value, `cycle ${reading.cycle}: Foxglove ${match.body.value}, the link ${reading.value}`);
      assert.ok(on(x).every((m) => m.body.cycle <= reading.cycle), "nothing after the stop");
    } finally {
      await cliDo(tb.linkPort, "cycle", "run");
    }
    await until(() => on(x).length >= first.length + 10, "running again: more messages");
    // Unsubscribed: once a new subscription streams, the old one has stopped.
    client.unsubscribe(x);
    const y = client.subscribe(channel("truth.pose.y").id);
    await until(() => on(y).length >= 5, "messages of truth.pose.y");
    const firstY = got.all.findIndex((m) => m.sub === y);
    assert.equal(got.all.slice(firstY).filter((m) => m.sub === x).length, 0, "no truth.pose.x after the unsubscribe");
    client.unsubscribe(y);
  });

  test("the robot's frame, pose and sonar in Foxglove's own schemas, stamped with the run's time", async () => {
    const schemas = {
      "foxglove/tf": "foxglove.FrameTransforms",
      "foxglove/truth.pose": "foxglove.PoseInFrame",
      "foxglove/odom": "foxglove.PoseInFrame",
      "foxglove/sonar": "foxglove.LaserScan",
    };
    for (const [topic, name] of Object.entries(schemas)) {
      const c = channel(topic);
      assert.ok(c, `a channel ${topic}: ${got.channels.map((c) => c.topic).join(", ")}`);
      assert.equal(c.schemaName, name);
      assert.equal(c.encoding, "json");
      assert.equal(c.schemaEncoding, "jsonschema");
      const schema = JSON.parse(c.schema);
      assert.equal(schema.title, name);
      assert.deepEqual(schema.properties.timestamp?.properties ?? schema.properties.transforms.items.properties.timestamp.properties, {
        sec: { type: "integer", minimum: 0 },
        nsec: { type: "integer", minimum: 0, maximum: 999999999 },
      });
    }
    const tf = client.subscribe(channel("foxglove/tf").id);
    const pose = client.subscribe(channel("foxglove/truth.pose").id);
    const sonar = client.subscribe(channel("foxglove/sonar").id);
    const x = client.subscribe(channel("truth.pose.x").id);
    try {
      await until(() => on(tf).length >= 5 && on(pose).length >= 5 && on(sonar).length >= 3 && on(x).length >= 5, "messages on the Foxglove channels");
      // Times: the run's (the wall clock at its start plus the robot's clock), not 1970.
      const since2020 = BigInt(Date.UTC(2020, 0, 1)) * 1_000_000n;
      const now = BigInt(Date.now()) * 1_000_000n;
      const day = 86_400_000_000_000n;
      const stamp = (t) => BigInt(t.sec) * 1_000_000_000n + BigInt(t.nsec);
      for (const m of [...on(tf), ...on(pose), ...on(sonar), ...on(x)]) {
        assert.ok(m.timestamp > since2020 && m.timestamp < now + day, `a timestamp of the run's day: ${m.timestamp}`);
      }
      for (const m of [...on(pose), ...on(sonar)]) assert.equal(stamp(m.body.timestamp), m.timestamp, "the message's timestamp is its receive time");
      const t = on(tf).at(-1).body.transforms;
      assert.equal(t.length, 1);
      assert.equal(t[0].parent_frame_id, "world");
      assert.equal(t[0].child_frame_id, "base_link");
      assert.equal(stamp(t[0].timestamp), on(tf).at(-1).timestamp);
      const scan = on(sonar).at(-1).body;
      assert.equal(scan.frame_id, "base_link", "the ring is on the robot");
      assert.equal(scan.ranges.length, 24);
      assert.ok(scan.ranges.every((r) => typeof r === "number" && r > 0), JSON.stringify(scan.ranges));
      assert.equal(scan.start_angle, 0, "sonar 0 ahead");
      assert.ok(Math.abs(scan.end_angle - (23 * 15 * Math.PI) / 180) < 1e-9, "15° apart, counter-clockwise: sonar 23 at 345°");
      assert.equal(on(pose).at(-1).body.frame_id, "world");
      // Stopped, the pose of the cycle the link reads is truth.pose's.
      await cliDo(tb.linkPort, "cycle", "stop");
      try {
        await until(async () => (await cli(tb.linkPort, "stats")).running === false, "the manager stopped over the link");
        const reading = await cli(tb.linkPort, "query", "truth.pose");
        const leaf = await until(() => on(x).find((m) => m.body.cycle === reading.cycle), `truth.pose.x of cycle ${reading.cycle}`);
        const p = await until(() => on(pose).find((m) => m.timestamp === leaf.timestamp), `the pose of cycle ${reading.cycle}`);
        const f = await until(() => on(tf).find((m) => m.timestamp === leaf.timestamp), `the transform of cycle ${reading.cycle}`);
        const { x: px, y: py } = p.body.pose.position;
        assert.ok(Math.abs(px - reading.value.x) < 1e-9 && Math.abs(py - reading.value.y) < 1e-9, `pose (${px}, ${py}), truth.pose ${JSON.stringify(reading.value)}`);
        const q = p.body.pose.orientation;
        const yaw = 2 * Math.atan2(q.z, q.w);
        const diff = Math.atan2(Math.sin(yaw - reading.value.theta), Math.cos(yaw - reading.value.theta));
        assert.ok(Math.abs(diff) < 1e-9 && q.x === 0 && q.y === 0, `orientation ${JSON.stringify(q)}, theta ${reading.value.theta}`);
        assert.deepEqual(f.body.transforms[0].translation, p.body.pose.position, "the frame is where the pose is");
        assert.deepEqual(f.body.transforms[0].rotation, q);
      } finally {
        await cliDo(tb.linkPort, "cycle", "run");
      }
    } finally {
      client.unsubscribe(tf);
      client.unsubscribe(pose);
      client.unsubscribe(sonar);
      client.unsubscribe(x);
    }
  });

  test("events: an activation over the link is a message on situate/events", async () => {
    const ev = client.subscribe(channel("situate/events").id);
    const skills = await cli(tb.linkPort, "skills");
    const wander = skills.find((s) => s.name === "wander");
    assert.ok(wander, "the testbed has wander");
    await cli(tb.linkPort, wander.active ? "deactivate" : "activate", "wander");
    const mark = await until(() => on(ev).find((m) => m.body.value.kind === "activation" && m.body.value.text.includes("wander")), "the activation's event");
    assert.ok(Number.isInteger(mark.body.cycle), JSON.stringify(mark.body));
    await cli(tb.linkPort, wander.active ? "activate" : "deactivate", "wander");
    client.unsubscribe(ev);
  });

  test("parameters: get, set, and a refused value reported as an error naming it", async () => {
    client.getParameters([], "all");
    const all = await until(() => got.params.find((p) => p.id === "all"), "parameterValues for all");
    const radius = all.parameters.find((p) => p.name === "circle.radius");
    assert.ok(radius, `circle.radius among ${all.parameters.map((p) => p.name).join(", ")}`);
    assert.equal(radius.value, await cli(tb.linkPort, "param", "get", "circle", "radius"));
    assert.ok(all.parameters.some((p) => p.name === "runaway.safe_distance"));

    client.setParameters([{ name: "circle.radius", value: 3.5 }], "set1");
    const set1 = await until(() => got.params.find((p) => p.id === "set1"), "parameterValues for the set");
    assert.deepEqual(set1.parameters.map((p) => [p.name, p.value]), [["circle.radius", 3.5]]);
    assert.equal(await cli(tb.linkPort, "param", "get", "circle", "radius"), 3.5, "set over the link");

    const before = got.statuses.length;
    client.setParameters([{ name: "circle.radius", value: 1000 }], "set2");
    const refused = await until(() => got.statuses.slice(before).find((s) => s.level === 2), "a status error");
    assert.match(refused.message, /circle\.radius/, refused.message);
    await until(() => got.params.find((p) => p.id === "set2"), "the values after the refused set");
    assert.equal(await cli(tb.linkPort, "param", "get", "circle", "radius"), 3.5, "the refused value changed nothing");
    client.setParameters([{ name: "circle.radius", value: 2.0 }], "set3");
    await until(async () => (await cli(tb.linkPort, "param", "get", "circle", "radius")) === 2, "radius back to 2");
  });

  test("parametersSubscribe: a change made over the link is pushed to a client following it", async () => {
    assert.ok(got.serverInfo.capabilities.includes("parametersSubscribe"), JSON.stringify(got.serverInfo));
    client.subscribeParameterUpdates(["circle.floor"]);
    // The subscription is in once a later request is answered (the server reads in order).
    client.getParameters(["circle.floor"], "floor0");
    const floor0 = await until(() => got.params.find((p) => p.id === "floor0"), "circle.floor");
    assert.equal(floor0.parameters[0].value, 0);
    const pushed = () => got.params.filter((p) => p.id === undefined).flatMap((p) => p.parameters);
    try {
      await cliDo(tb.linkPort, "param", "set", "circle", "floor", "1");
      await until(() => pushed().some((p) => p.name === "circle.floor" && p.value === 1), "the update to 1");
      await cliDo(tb.linkPort, "param", "set", "circle", "period_s", "30");
      await cliDo(tb.linkPort, "param", "set", "circle", "floor", "0");
      await until(() => pushed().some((p) => p.name === "circle.floor" && p.value === 0), "the update to 0");
      assert.ok(!pushed().some((p) => p.name === "circle.period_s"), "only what the client follows");
    } finally {
      client.unsubscribeParameterUpdates([]);
      await cliDo(tb.linkPort, "param", "set", "circle", "floor", "0");
      await cliDo(tb.linkPort, "param", "set", "circle", "period_s", "20");
    }
  });

  test("a bad client message is answered by a status error, and the session goes on", async () => {
    const before = got.statuses.length;
    ws.send("this is not JSON");
    ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 99, channelId: 999999 }] }));
    ws.send(JSON.stringify({ op: "fly" }));
    await until(() => got.statuses.slice(before).filter((s) => s.level === 2).length >= 3, "three status errors");
    const texts = got.statuses.slice(before).map((s) => s.message).join("\n");
    assert.match(texts, /not JSON/);
    assert.match(texts, /no channel 999999/);
    assert.match(texts, /unsupported op `fly`/);
    client.getParameters(["circle.radius"], "after");
    const p = await until(() => got.params.find((m) => m.id === "after"), "an answer after the bad messages");
    assert.deepEqual(p.parameters.map((q) => q.name), ["circle.radius"]);
  });

  test("at most 8 clients: a ninth is told so and closed, and a place frees when one leaves", async () => {
    const WS = await webSocketClass();
    const url = `ws://127.0.0.1:${tb.guiPort}/foxglove`;
    const connect = () => {
      const c = { ws: new WS(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]), msgs: [], closed: false };
      c.ws.onmessage = (e) => typeof e.data === "string" && c.msgs.push(JSON.parse(e.data));
      c.ws.onclose = () => (c.closed = true);
      return c;
    };
    const others = Array.from({ length: 7 }, connect);
    try {
      await until(() => others.every((o) => o.msgs.some((m) => m.op === "serverInfo")), "seven more clients admitted");
      const ninth = connect();
      await until(() => ninth.closed, "the ninth closed by the server");
      assert.ok(!ninth.msgs.some((m) => m.op === "serverInfo"), "the ninth was not served");
      assert.ok(ninth.msgs.some((m) => m.op === "status" && m.level === 2 && /too many Foxglove clients \(at most 8\)/.test(m.message)), JSON.stringify(ninth.msgs));
      others.pop().ws.close();
      await until(async () => {
        const c = connect();
        await until(() => c.closed || c.msgs.length > 0, "an answer");
        const served = c.msgs.some((m) => m.op === "serverInfo");
        c.ws.close();
        return served;
      }, "a client admitted once one left");
    } finally {
      for (const o of others) o.ws.close();
    }
  });
});
