// Reads an MCAP file with the format's own reader (@mcap/core) and prints one JSON report on
// stdout, for the tests of the rig's MCAP export to compare with what the rig wrote.
//
//   node read_mcap.mjs FILE [--sample TOPIC:INDEX]...
//
// The report: header (profile, library), the channels (topic, schema name and encoding, message
// encoding, messages read), the summary's statistics, the first and last log times read, the
// metadata records, whether the data section CRC holds, whether every jsonschema schema
// compiles with Ajv (the rig's extra keywords x-unit and x-constants allowed), how many json
// messages parse and validate against their channel's schema (with the first errors), the
// decoded messages asked for (INDEX counts from 0 in log-time order on that topic; negative
// counts from the end), and the per-topic counts of a second, unindexed read of the whole file
// with McapStreamReader. Times are decimal strings of nanoseconds (exact, unlike doubles).
// Any failure to read the file exits 1 with the reason on stderr.
//
// CMake copies this script into the build's npm/ directory, where scripts/setup.sh installs
// @mcap/core, fzstd and ajv (node_modules).

import { open } from "node:fs/promises";

async function load(name) {
  try {
    return await import(name);
  } catch (e) {
    throw new Error(`cannot load ${name} (${e.code ?? e.message}): run scripts/setup.sh to install the npm packages`);
  }
}

function usage(message) {
  process.stderr.write(`read_mcap: ${message}\nusage: node read_mcap.mjs FILE [--sample TOPIC:INDEX]...\n`);
  process.exit(2);
}

function parseArgs(argv) {
  const out = { file: undefined, samples: [] };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    if (a === "--sample") {
      const v = argv[++i];
      const colon = v?.lastIndexOf(":") ?? -1;
      const index = colon > 0 ? Number(v.slice(colon + 1)) : NaN;
      if (!Number.isInteger(index)) usage(`--sample wants TOPIC:INDEX, got '${v}'`);
      out.samples.push({ key: v, topic: v.slice(0, colon), index });
    } else if (a.startsWith("--")) {
      usage(`unknown option ${a}`);
    } else if (out.file === undefined) {
      out.file = a;
    } else {
      usage(`one file only ('${a}')`);
    }
  }
  if (out.file === undefined) usage("no file");
  return out;
}

// CRC-32 (the polynomial of zlib and of the MCAP specification), for the data section CRC that
// the indexed reader reads but does not check.
const crcTable = (() => {
  const t = new Uint32Array(256);
  for (let n = 0; n < 256; ++n) {
    let c = n;
    for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    t[n] = c >>> 0;
  }
  return t;
})();
function crc32Update(crc, bytes) {
  let c = crc;
  for (let i = 0; i < bytes.length; ++i) c = crcTable[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return c;
}

const decoder = new TextDecoder("utf-8", { fatal: true });

async function main() {
  const args = parseArgs(process.argv.slice(2));
  const { McapIndexedReader, McapStreamReader } = await load("@mcap/core");
  const fzstd = await load("fzstd");
  const Ajv = (await load("ajv")).default;
  const Ajv2020 = (await load("ajv/dist/2020.js")).default;

  const decompressHandlers = {
    zstd: (buffer, decompressedSize) => fzstd.decompress(buffer, new Uint8Array(Number(decompressedSize))),
  };
  const fh = await open(args.file, "r");
  const fileSize = (await fh.stat()).size;
  const readable = {
    size: async () => BigInt(fileSize),
    read: async (offset, size) => {
      const n = Number(size);
      const buf = new Uint8Array(n);
      const { bytesRead } = await fh.read(buf, 0, n, Number(offset));
      if (bytesRead !== n) throw new Error(`short read at ${offset}: ${bytesRead} of ${n} bytes`);
      return buf;
    },
  };

  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  const report = {
    file: args.file,
    profile: reader.header.profile,
    library: reader.header.library,
    channels: [],
    statistics: null,
    startTime: null,
    endTime: null,
    messages: 0,
    metadata: [],
    dataSectionCrcOk: null,
    schemas: { jsonschema: 0, compiled: 0, failures: [] },
    validation: { json: 0, parsed: 0, valid: 0, errors: [] },
    samples: {},
    stream: { messages: 0, counts: {} },
  };

  // The data section CRC: everything before the DataEnd record.
  if (reader.dataSectionCrc !== undefined) {
    let crc = 0xffffffff;
    const piece = 1 << 20;
    for (let at = 0n; at < reader.dataEndOffset; at += BigInt(piece)) {
      const n = reader.dataEndOffset - at < BigInt(piece) ? reader.dataEndOffset - at : BigInt(piece);
      crc = crc32Update(crc, await readable.read(at, n));
    }
    report.dataSectionCrcOk = ((crc ^ 0xffffffff) >>> 0) === reader.dataSectionCrc;
  }

  // Schemas: every jsonschema one must compile, by the draft its $schema names (draft-07 by
  // default, as Ajv's).
  const makeAjv = (Class) => {
    const a = new Class({ allErrors: false, allowUnionTypes: true });
    a.addKeyword("x-unit");
    a.addKeyword("x-constants");
    return a;
  };
  const ajv07 = makeAjv(Ajv);
  const ajv2020 = makeAjv(Ajv2020);
  const validators = new Map();  // schema id -> validate function
  for (const [id, schema] of reader.schemasById) {
    if (schema.encoding !== "jsonschema") continue;
    ++report.schemas.jsonschema;
    try {
      const json = JSON.parse(decoder.decode(schema.data));
      const ajv = String(json.$schema ?? "").includes("2020-12") ? ajv2020 : ajv07;
      validators.set(id, ajv.compile(json));
      ++report.schemas.compiled;
    } catch (e) {
      report.schemas.failures.push({ name: schema.name, error: String(e.message ?? e) });
    }
  }

  if (reader.statistics) {
    const s = reader.statistics;
    const perTopic = {};
    for (const [id, count] of s.channelMessageCounts) {
      perTopic[reader.channelsById.get(id)?.topic ?? `#${id}`] = Number(count);
    }
    report.statistics = {
      messageCount: Number(s.messageCount),
      schemaCount: s.schemaCount,
      channelCount: s.channelCount,
      chunkCount: s.chunkCount,
      metadataCount: s.metadataCount,
      attachmentCount: s.attachmentCount,
      messageStartTime: String(s.messageStartTime),
      messageEndTime: String(s.messageEndTime),
      channelMessageCounts: perTopic,
    };
  }
  for await (const m of reader.readMetadata()) {
    report.metadata.push({ name: m.name, metadata: Object.fromEntries(m.metadata) });
  }

  // Every message in log-time order, CRCs checked.
  const counts = new Map();
  const lastTime = new Map();
  let start = null;
  let end = null;
  for await (const msg of reader.readMessages({ validateCrcs: true })) {
    ++report.messages;
    counts.set(msg.channelId, (counts.get(msg.channelId) ?? 0) + 1);
    const previous = lastTime.get(msg.channelId);
    if (previous !== undefined && msg.logTime < previous) throw new Error(`messages out of log-time order on channel ${msg.channelId}`);
    lastTime.set(msg.channelId, msg.logTime);
    if (start === null || msg.logTime < start) start = msg.logTime;
    if (end === null || msg.logTime > end) end = msg.logTime;
    const channel = reader.channelsById.get(msg.channelId);
    if (channel.messageEncoding !== "json") continue;
    ++report.validation.json;
    let value;
    try {
      value = JSON.parse(decoder.decode(msg.data));
      ++report.validation.parsed;
    } catch (e) {
      if (report.validation.errors.length < 5) report.validation.errors.push({ topic: channel.topic, error: `not JSON: ${e.message}` });
      continue;
    }
    const validate = validators.get(channel.schemaId);
    if (validate === undefined) continue;
    if (validate(value)) {
      ++report.validation.valid;
    } else if (report.validation.errors.length < 5) {
      report.validation.errors.push({ topic: channel.topic, sequence: msg.sequence, errors: validate.errors });
    }
  }
  report.startTime = start === null ? null : String(start);
  report.endTime = end === null ? null : String(end);
  for (const [id, channel] of reader.channelsById) {
    const schema = reader.schemasById.get(channel.schemaId);
    report.channels.push({
      id,
      topic: channel.topic,
      schemaName: schema?.name ?? "",
      schemaEncoding: schema?.encoding ?? "",
      messageEncoding: channel.messageEncoding,
      count: counts.get(id) ?? 0,
    });
  }

  // Samples: the INDEX-th message of TOPIC in log-time order.
  for (const s of args.samples) {
    const entry = report.channels.find((c) => c.topic === s.topic);
    if (!entry) throw new Error(`--sample ${s.key}: no channel ${s.topic}`);
    const index = s.index < 0 ? entry.count + s.index : s.index;
    if (index < 0 || index >= entry.count) throw new Error(`--sample ${s.key}: the channel has ${entry.count} messages`);
    let i = 0;
    for await (const msg of reader.readMessages({ topics: [s.topic] })) {
      if (i++ !== index) continue;
      const text = entry.messageEncoding === "json" ? decoder.decode(msg.data) : null;
      report.samples[s.key] = {
        index,
        logTime: String(msg.logTime),
        publishTime: String(msg.publishTime),
        sequence: msg.sequence,
        size: msg.data.length,
        message: text === null ? null : JSON.parse(text),
      };
      break;
    }
  }

  // The whole file again, unindexed, as a streaming reader sees it.
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  const topics = new Map();
  const piece = 1 << 20;
  for (let at = 0; at < fileSize; at += piece) {
    stream.append(await readable.read(BigInt(at), BigInt(Math.min(piece, fileSize - at))));
    for (let record; (record = stream.nextRecord()); ) {
      if (record.type === "Channel") topics.set(record.id, record.topic);
      if (record.type !== "Message") continue;
      ++report.stream.messages;
      const topic = topics.get(record.channelId);
      if (topic === undefined) throw new Error(`stream: message on channel ${record.channelId} before its Channel record`);
      report.stream.counts[topic] = (report.stream.counts[topic] ?? 0) + 1;
    }
  }
  if (!stream.done()) throw new Error("stream: the file ended before its footer and closing magic");
  await fh.close();
  process.stdout.write(JSON.stringify(report, null, 1) + "\n");
}

main().catch((e) => {
  process.stderr.write(`read_mcap: ${e.message ?? e}\n`);
  process.exit(1);
});
