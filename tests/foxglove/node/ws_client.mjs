// A Foxglove WebSocket client as Foxglove itself connects (@foxglove/ws-protocol's FoxgloveClient
// over the `ws` package): connects to the rig's live view, subscribes to the given topics once
// they are advertised, collects their messages for a while and writes them as JSON.
//
//   node ws_client.mjs --url ws://127.0.0.1:8765 --topics TRUTH,ESTIMATE --seconds 3 --out FILE
//        [--connect-timeout S]
//
// It retries the connection until --connect-timeout (default 10 s) passes, then collects for
// --seconds from the first message. The output: {"subprotocol", "serverInfo", "channels"
// (topic -> {id, schemaName, encoding, schemaEncoding}), "statuses", "messages": {topic:
// [{"t_ns": "...", "msg": {...}}]}, "first_receive_ms", "last_receive_ms" (wall clock of the
// client, per topic)}. Exits 0 once it wrote the file, 1 if it could not connect or a topic was
// never advertised, 2 on a usage error.
//
// Runs from <build>/npm, where the build's npm packages are installed (scripts/setup.sh).

import fs from "node:fs";
import wsProtocol from "@foxglove/ws-protocol"; // CommonJS: its exports come as one object
import WebSocket from "ws";

const { FoxgloveClient } = wsProtocol;

function usage(message) {
  console.error(
    `ws_client.mjs: ${message}\n` +
      "usage: node ws_client.mjs --url URL --topics A,B --seconds S --out FILE [--connect-timeout S]",
  );
  process.exit(2);
}

const opts = { url: null, topics: null, seconds: null, out: null, connectTimeout: 10 };
const args = process.argv.slice(2);
for (let i = 0; i < args.length; i += 2) {
  const key = args[i];
  const value = args[i + 1];
  if (value === undefined) usage(`${key} needs a value`);
  if (key === "--url") opts.url = value;
  else if (key === "--topics") opts.topics = value.split(",").filter((t) => t !== "");
  else if (key === "--seconds") opts.seconds = Number(value);
  else if (key === "--out") opts.out = value;
  else if (key === "--connect-timeout") opts.connectTimeout = Number(value);
  else usage(`unknown option ${key}`);
}
if (!opts.url || !opts.topics || opts.topics.length === 0 || !opts.out) usage("--url, --topics and --out are required");
if (!(opts.seconds > 0) || !(opts.connectTimeout > 0)) usage("--seconds and --connect-timeout must be positive");

const result = {
  subprotocol: null,
  serverInfo: null,
  channels: {},
  statuses: [],
  messages: Object.fromEntries(opts.topics.map((t) => [t, []])),
  first_receive_ms: {},
  last_receive_ms: {},
};
const decoder = new TextDecoder();
const deadline = Date.now() + opts.connectTimeout * 1000;

function finish(code, error) {
  if (error) result.error = error;
  fs.writeFileSync(opts.out, JSON.stringify(result));
  process.exit(code);
}

function connect() {
  const ws = new WebSocket(opts.url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  const client = new FoxgloveClient({ ws });
  const topicOf = new Map(); // subscription id -> topic
  let collecting = false;
  let opened = false;

  client.on("open", () => {
    opened = true;
    result.subprotocol = ws.protocol;
  });
  client.on("serverInfo", (info) => {
    result.serverInfo = info;
  });
  client.on("status", (status) => result.statuses.push(status));
  client.on("advertise", (channels) => {
    for (const c of channels) {
      result.channels[c.topic] = {
        id: c.id,
        schemaName: c.schemaName,
        encoding: c.encoding,
        schemaEncoding: c.schemaEncoding,
      };
      if (opts.topics.includes(c.topic)) topicOf.set(client.subscribe(c.id), c.topic);
    }
    const missing = opts.topics.filter((t) => !(t in result.channels));
    if (missing.length > 0) finish(1, `not advertised: ${missing.join(", ")}`);
  });
  client.on("message", ({ subscriptionId, timestamp, data }) => {
    const topic = topicOf.get(subscriptionId);
    if (topic === undefined) return;
    const now = Date.now();
    if (!collecting) {
      collecting = true;
      setTimeout(() => {
        client.close();
        finish(0);
      }, opts.seconds * 1000);
    }
    const text = decoder.decode(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
    result.messages[topic].push({ t_ns: timestamp.toString(), msg: JSON.parse(text) });
    if (!(topic in result.first_receive_ms)) result.first_receive_ms[topic] = now;
    result.last_receive_ms[topic] = now;
  });
  client.on("error", () => {});
  client.on("close", () => {
    if (collecting) {
      finish(0); // the server ended first (the run is over): what came is the result
      return;
    }
    if (!opened && Date.now() < deadline) {
      setTimeout(connect, 100);
      return;
    }
    finish(1, opened ? "the server closed the connection before any message" : `cannot connect to ${opts.url}`);
  });
}

connect();
