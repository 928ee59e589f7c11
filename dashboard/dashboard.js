// The rig's live dashboard: roll angle, roll rate and lateral velocity (truth and estimate), the
// faults and the run's verdict, from a Foxglove WebSocket server (subprotocol
// foxglove.websocket.v1, JSON-encoded channels).
//
// Query string: ws=<server URL> (default ws://127.0.0.1:8765), window=<seconds shown> (default 10).
// uPlot comes as the global `uPlot` from uPlot.iife.min.js, served next to this file.

const params = new URLSearchParams(window.location.search);
const WS_URL = params.get("ws") || "ws://127.0.0.1:8765";
const WINDOW_S = numberParam("window", 10, 1, 120);

const SUBPROTOCOL = "foxglove.websocket.v1";
const REDRAW_MS = 100;        // at most 10 redraws a second
const MAX_SAMPLES = 20000;    // per source, whatever the window holds
const MAX_FAULTS = 200;       // list items kept; older ones are dropped from the list
const RECONNECT_MS = [1000, 4000];  // first retry, longest wait between retries
const RESTART_S = 1.0;        // rig time running back more than this starts a new picture
const RAD2DEG = 180 / Math.PI;
const PLOT_HEIGHT = 190;      // px, each plot with its axes

// Topic -> what the page does with it.
const TOPICS = new Map([
  ["TRUTH", "truth"],
  ["ESTIMATE", "estimate"],
  ["FAULT", "fault"],
  ["rig/verdict", "verdict"],
]);
const SEVERITY = ["INFO", "WARNING", "ERROR", "FATAL"];

// The plots: which vector field and component, its scale to the shown unit, the smallest span
// of the y axis (so that a quiet signal is not magnified into noise).
const PLOTS = [
  { id: "phi", field: "euler_rad", index: 0, scale: RAD2DEG, minSpan: 2, digits: 2 },
  { id: "p", field: "omega_body_radps", index: 0, scale: RAD2DEG, minSpan: 10, digits: 1 },
  { id: "v", field: "velocity_body_mps", index: 1, scale: 1, minSpan: 0.1, digits: 3 },
];

function numberParam(name, fallback, lo, hi) {
  const v = Number(params.get(name));
  return params.has(name) && Number.isFinite(v) ? Math.min(hi, Math.max(lo, v)) : fallback;
}

// ---- samples -----------------------------------------------------------------------------

// The samples of one source (truth or estimate) in rig-time order: time [s] and one column per
// plot, in the plot's unit (null where the source had NaN). Old samples leave from the front.
class Trace {
  constructor() { this.clear(); }
  clear() {
    this.t = [];
    this.cols = PLOTS.map(() => []);
    this.head = 0;
  }
  get size() { return this.t.length - this.head; }
  get last() { return this.t.length > this.head ? this.t[this.t.length - 1] : -Infinity; }
  push(t, values) {
    this.t.push(t);
    for (let k = 0; k < PLOTS.length; k++) this.cols[k].push(values[k]);
  }
  // Drops samples older than tMin and any beyond MAX_SAMPLES; compacts now and then.
  trim(tMin) {
    while (this.head < this.t.length && (this.t[this.head] < tMin || this.size > MAX_SAMPLES)) this.head++;
    if (this.head > 4096 && this.head * 2 > this.t.length) {
      this.t = this.t.slice(this.head);
      this.cols = this.cols.map((c) => c.slice(this.head));
      this.head = 0;
    }
  }
}

const truth = new Trace();
const estimate = new Trace();
let tNewest = -Infinity;  // newest rig time seen on TRUTH or ESTIMATE [s]
let tFirst = Infinity;    // first rig time seen since the start or a restart [s]
let dirty = true;

function component(msg, field, index, scale) {
  const arr = msg[field];
  const v = Array.isArray(arr) ? arr[index] : null;
  return typeof v === "number" && Number.isFinite(v) ? v * scale : null;
}

// Rig time of a message [s]: its own field if it has one, else the frame's timestamp.
function rigTime(msg, field, stampNs) {
  const us = msg[field];
  return typeof us === "number" && Number.isFinite(us) ? us / 1e6 : stampNs / 1e9;
}

function addSample(trace, t, msg) {
  if (t <= trace.last) {
    if (trace.last - t > RESTART_S) restart();  // a new run or a replay from its start
    else return;                                 // late or repeated: the plot keeps time order
  }
  trace.push(t, PLOTS.map((p) => component(msg, p.field, p.index, p.scale)));
  if (t > tNewest) tNewest = t;
  if (t < tFirst) tFirst = t;
  // Redraws trim the traces; a hidden page's timers may run only once a minute.
  if (trace.size > 2 * MAX_SAMPLES) trace.trim(tNewest - WINDOW_S);
  dirty = true;
}

// A new run: the plots, the fault list and the verdict start afresh.
function restart() {
  truth.clear();
  estimate.clear();
  tNewest = -Infinity;
  tFirst = Infinity;
  clearFaults();
  showVerdict(null);
}

// ---- plots -------------------------------------------------------------------------------

const plotsEl = document.getElementById("plots");
let xRange = [0, WINDOW_S];

function makePlot(spec) {
  const fig = document.getElementById("plot-" + spec.id);
  const fmt = (u, v) => (v == null ? "\u2013" : v.toFixed(spec.digits));
  const opts = {
    width: plotWidth(),
    height: PLOT_HEIGHT,
    cursor: { drag: { x: false, y: false } },
    legend: { show: false },
    scales: {
      x: { time: false, range: () => xRange },
      y: {
        // The data's range, at least minSpan wide, padded out to round numbers.
        range: (u, lo, hi) => {
          if (lo == null || hi == null) return [-spec.minSpan / 2, spec.minSpan / 2];
          const mid = (lo + hi) / 2;
          const half = Math.max(hi - lo, spec.minSpan) / 2;
          return uPlot.rangeNum(mid - half, mid + half, 0.05, true);
        },
      },
    },
    axes: [
      { label: "rig time [s]", labelSize: 18, size: 36 },
      { size: 56, space: 24 },
    ],
    series: [
      { label: "t", value: (u, v) => (v == null ? "\u2013" : v.toFixed(3)) },
      { label: "truth", stroke: "#1f5fa8", width: 1.5, value: fmt, points: { show: false } },
      { label: "estimate", stroke: "#d9480f", width: 1.5, dash: [7, 4], value: fmt, points: { show: false } },
    ],
  };
  return { spec, fig, u: new uPlot(opts, [[], [], []], fig.querySelector(".canvas")) };
}

function plotWidth() {
  return Math.max(300, Math.floor(plotsEl.clientWidth) - 4);
}

const plots = PLOTS.map(makePlot);
new ResizeObserver(() => {
  const w = plotWidth();
  for (const p of plots) if (p.u.width !== w) p.u.setSize({ width: w, height: PLOT_HEIGHT });
}).observe(plotsEl);

// Joins the two traces on their times (both sorted): one x array, and per plot one array per
// trace, `undefined` where only the other trace has a sample (uPlot draws across those) and
// null where the source had NaN (uPlot leaves a gap there).
function joined() {
  const xs = [];
  const ys = PLOTS.map(() => [[], []]);
  let i = truth.head;
  let j = estimate.head;
  const ni = truth.t.length;
  const nj = estimate.t.length;
  while (i < ni || j < nj) {
    const ti = i < ni ? truth.t[i] : Infinity;
    const tj = j < nj ? estimate.t[j] : Infinity;
    const takeI = ti <= tj;
    const takeJ = tj <= ti;
    xs.push(takeI ? ti : tj);
    for (let k = 0; k < PLOTS.length; k++) {
      ys[k][0].push(takeI ? truth.cols[k][i] : undefined);
      ys[k][1].push(takeJ ? estimate.cols[k][j] : undefined);
    }
    if (takeI) i++;
    if (takeJ) j++;
  }
  return { xs, ys };
}

function redrawPlots() {
  if (Number.isFinite(tNewest)) {
    const tMin = tNewest - WINDOW_S;
    truth.trim(tMin);
    estimate.trim(tMin);
    // The window fills from the first sample, then slides with the newest.
    const lo = Math.max(tMin, tFirst);
    xRange = [lo, lo + WINDOW_S];
  } else {
    xRange = [0, WINDOW_S];
  }
  const { xs, ys } = joined();
  // What is plotted, for a test to read: samples per source and the rig time they span [s].
  const span = (tr) => (tr.size ? [tr.t[tr.head], tr.last] : ["", ""]);
  const [truthFrom, truthTo] = span(truth);
  const [estimateFrom, estimateTo] = span(estimate);
  for (let k = 0; k < plots.length; k++) {
    const p = plots[k];
    p.u.setData([xs, ys[k][0], ys[k][1]]);
    const d = p.fig.dataset;
    d.truthPoints = String(truth.size);
    d.estimatePoints = String(estimate.size);
    d.truthFrom = String(truthFrom);
    d.truthTo = String(truthTo);
    d.estimateFrom = String(estimateFrom);
    d.estimateTo = String(estimateTo);
  }
  const rt = document.getElementById("rigtime");
  rt.textContent = Number.isFinite(tNewest) ? tNewest.toFixed(2) + " s" : "\u2013";
  rt.dataset.tS = Number.isFinite(tNewest) ? String(tNewest) : "";
}

// ---- faults, verdict, counters -----------------------------------------------------------

const faultsEl = document.getElementById("faults");
const pendingFaults = [];
let faultTotal = 0;

function addFault(msg) {
  pendingFaults.push(msg);
  faultTotal++;
  if (pendingFaults.length > MAX_FAULTS) pendingFaults.shift();
}

function faultItem(msg) {
  const li = document.createElement("li");
  const sev = Number.isInteger(msg.severity) ? msg.severity : -1;
  const sevName = SEVERITY[sev] || "severity " + String(msg.severity);
  li.dataset.severity = sevName.toLowerCase();
  li.dataset.code = String(msg.code);
  const span = (cls, text) => {
    const s = document.createElement("span");
    s.className = cls;
    s.textContent = text;
    li.appendChild(s);
  };
  const us = msg.rig_utime;
  span("t", typeof us === "number" && us >= 0 ? (us / 1e6).toFixed(3) + " s" : "\u2013");
  span("process", String(msg.process ?? ""));
  span("severity", sevName);
  span("message", String(msg.message ?? ""));
  if (msg.channel) span("channel", String(msg.channel));
  return li;
}

function clearFaults() {
  pendingFaults.length = 0;
  faultTotal = 0;
  faultsEl.replaceChildren();
  showFaultCount();
}

function showFaultCount() {
  const fc = document.getElementById("fault-count");
  fc.textContent = String(faultTotal);
  fc.dataset.count = String(faultTotal);
}

function flushFaults() {
  if (pendingFaults.length === 0) return;
  const frag = document.createDocumentFragment();
  for (let k = pendingFaults.length - 1; k >= 0; k--) frag.appendChild(faultItem(pendingFaults[k]));
  pendingFaults.length = 0;
  faultsEl.insertBefore(frag, faultsEl.firstChild);
  while (faultsEl.childElementCount > MAX_FAULTS) faultsEl.lastElementChild.remove();
  showFaultCount();
}

function showVerdict(msg) {
  const el = document.getElementById("verdict");
  if (msg === null) {
    el.dataset.state = "none";
    el.dataset.verdict = "";
    el.textContent = "no verdict yet";
    return;
  }
  const state = typeof msg.state === "string" ? msg.state : "unknown";
  const verdict = typeof msg.verdict === "string" ? msg.verdict : "";
  const t = typeof msg.t_s === "number" && Number.isFinite(msg.t_s) ? msg.t_s.toFixed(1) + " s" : "";
  // Messages the server left out for a value beyond the vehicle's physical bounds: named, never plotted.
  const beyond = typeof msg.beyond_bounds === "string" ? "left out: " + msg.beyond_bounds : "";
  el.dataset.state = state;
  el.dataset.verdict = verdict;
  el.dataset.beyondBounds = beyond;
  el.textContent = [state, t, verdict, beyond].filter((s) => s !== "").join(" \u00b7 ");
}

let messageCount = 0;
let undecodable = 0;

function showCount() {
  const el = document.getElementById("count");
  if (el.dataset.count === String(messageCount)) return;
  el.textContent = undecodable ? `${messageCount} (${undecodable} undecodable)` : String(messageCount);
  el.dataset.count = String(messageCount);
}

function setStatus(state, text) {
  const el = document.getElementById("status");
  el.dataset.state = state;
  el.textContent = text;
}

// ---- the connection ------------------------------------------------------------------------

const decoder = new TextDecoder();
let subscriptions = new Map();  // subscription id -> { kind, topic }
let subscribedChannels = new Map();  // channel id -> subscription id
let nextSubscription = 1;
let retryMs = RECONNECT_MS[0];

function onText(ws, text) {
  let m;
  try { m = JSON.parse(text); } catch (e) { return; }
  if (m.op === "serverInfo") {
    setStatus("connected", "connected" + (m.name ? " to " + m.name : ""));
  } else if (m.op === "advertise" && Array.isArray(m.channels)) {
    const subs = [];
    for (const ch of m.channels) {
      const kind = TOPICS.get(ch.topic);
      if (!kind || ch.encoding !== "json" || subscribedChannels.has(ch.id)) continue;
      const id = nextSubscription++;
      subscriptions.set(id, { kind, topic: ch.topic });
      subscribedChannels.set(ch.id, id);
      subs.push({ id, channelId: ch.id });
    }
    if (subs.length) ws.send(JSON.stringify({ op: "subscribe", subscriptions: subs }));
  } else if (m.op === "unadvertise" && Array.isArray(m.channelIds)) {
    // The server ends the subscriptions of a channel it removes.
    for (const cid of m.channelIds) {
      const sid = subscribedChannels.get(cid);
      subscribedChannels.delete(cid);
      if (sid !== undefined) subscriptions.delete(sid);
    }
  } else if (m.op === "status") {
    const el = document.getElementById("server-status");
    el.textContent = typeof m.message === "string" ? m.message : "";
    el.dataset.level = String(m.level);
  }
}

function onBinary(buf) {
  if (buf.byteLength < 13) return;
  const dv = new DataView(buf);
  if (dv.getUint8(0) !== 0x01) return;  // only Message Data; Time (0x02) is not needed
  const sub = subscriptions.get(dv.getUint32(1, true));
  if (!sub) return;
  const stampNs = dv.getUint32(5, true) + dv.getUint32(9, true) * 4294967296;
  let msg;
  try {
    msg = JSON.parse(decoder.decode(new Uint8Array(buf, 13)));
  } catch (e) {
    undecodable++;
    return;
  }
  messageCount++;
  if (msg === null || typeof msg !== "object") return;
  switch (sub.kind) {
    case "truth":
      addSample(truth, rigTime(msg, "utime", stampNs), msg);
      break;
    case "estimate":
      // The estimate refers to its newest IMU sample, imu_utime; utime is when it was published.
      addSample(estimate, rigTime(msg, Number.isFinite(msg.imu_utime) ? "imu_utime" : "utime", stampNs), msg);
      break;
    case "fault":
      addFault(msg);
      break;
    case "verdict":
      showVerdict(msg);
      break;
  }
}

function connect() {
  subscriptions = new Map();
  subscribedChannels = new Map();
  setStatus("connecting", "connecting");
  let ws;
  try {
    ws = new WebSocket(WS_URL, [SUBPROTOCOL]);
  } catch (e) {
    setStatus("error", "bad server URL: " + WS_URL);
    return;
  }
  ws.binaryType = "arraybuffer";
  ws.onopen = () => {
    retryMs = RECONNECT_MS[0];
    setStatus("connected", "connected");
  };
  ws.onmessage = (ev) => (typeof ev.data === "string" ? onText(ws, ev.data) : onBinary(ev.data));
  // Each failed attempt costs a line in the browser's console: the waits grow to RECONNECT_MS[1].
  ws.onclose = () => {
    setStatus("disconnected", `disconnected, retrying in ${Math.round(retryMs / 1000)} s`);
    setTimeout(connect, retryMs);
    retryMs = Math.min(retryMs * 2, RECONNECT_MS[1]);
  };
}

// ---- start ----------------------------------------------------------------------------------

document.getElementById("ws-url").textContent = WS_URL;
document.getElementById("window").textContent = `last ${WINDOW_S} s of rig time`;
setInterval(() => {
  showCount();
  flushFaults();
  if (dirty) {
    dirty = false;
    redrawPlots();
  }
}, REDRAW_MS);
redrawPlots();
connect();
