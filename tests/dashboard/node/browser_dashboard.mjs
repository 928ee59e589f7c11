// The dashboard in a real browser: opens the page in headless Chromium and checks that it shows a
// live run.
//
//   node browser_dashboard.mjs --url 'http://127.0.0.1:8080/?ws=ws://127.0.0.1:8765'
//        [--expect-fault TEXT] [--expect-verdict TEXT] [--expect-span S] [--still] [--timeout S]
//        [--interval-ms MS] [--screenshots DIR] [--chromium PATH] [--min-diff-pixels N]
//
// Checks, in order (each wait bounded by --timeout, default 30 s):
//  1. the page loads and connects: the message counter (#count) rises above zero, then rises again
//     (not with --still: a page opened after the stream ended gets the last seconds only);
//  2. the roll-angle plot holds truth and estimate samples; with --expect-span S, both come to
//     span at least S s of rig time (a late page gets the server's history);
//  3. the plots move (not with --still): the plots as drawn, captured twice --interval-ms apart
//     (default 1000), show different rig times and differ in at least --min-diff-pixels pixels
//     (default 100). What is compared is each plot's canvas (uPlot draws a plot with its axes on
//     one), so the layout around the plots (a fault list growing beside them stretches their
//     section) cannot change what is compared; a plot resized between the captures (a change of
//     width) is captured again. With --screenshots DIR the canvases are saved there as
//     plots-1-<plot>.png and plots-2-<plot>.png, and the whole page at the end as page.png;
//  4. with --expect-fault, a fault whose text contains TEXT appears in the fault list (#faults li);
//  5. with --expect-verdict, the run line (#verdict) comes to contain TEXT;
//  6. the page logged no console error and threw nothing, every request of the page succeeded,
//     and it asked nothing of any host but this machine.
// Prints one JSON report on stdout; exits 0 if every check passed, 1 if one failed (the report's
// "error" says which), 2 on a usage error.
//
// Runs from <build>/npm, where the build's npm packages (puppeteer-core) are installed.

import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import zlib from "node:zlib";
import puppeteer from "puppeteer-core";

const USAGE = `usage: node browser_dashboard.mjs --url URL [--expect-fault TEXT] [--expect-verdict TEXT]
       [--expect-span S] [--still] [--timeout S] [--interval-ms MS] [--screenshots DIR] [--chromium PATH]
       [--min-diff-pixels N]`;

function parseArgs(argv) {
  const opts = {
    url: null,
    expectFault: null,
    expectVerdict: null,
    expectSpan: 0,
    still: false,
    timeoutS: 30,
    intervalMs: 1000,
    screenshots: null,
    chromium: "/usr/bin/chromium-headless-shell",
    minDiffPixels: 100,
  };
  const valued = {
    "--url": "url",
    "--expect-fault": "expectFault",
    "--expect-verdict": "expectVerdict",
    "--expect-span": "expectSpan",
    "--timeout": "timeoutS",
    "--interval-ms": "intervalMs",
    "--screenshots": "screenshots",
    "--chromium": "chromium",
    "--min-diff-pixels": "minDiffPixels",
  };
  for (let i = 0; i < argv.length; i++) {
    let a = argv[i];
    let v;
    const eq = a.indexOf("=");
    if (a.startsWith("--") && eq > 0) {
      v = a.slice(eq + 1);
      a = a.slice(0, eq);
    }
    if (a === "--help" || a === "-h") {
      console.log(USAGE);
      process.exit(0);
    }
    if (a === "--still" && v === undefined) {
      opts.still = true;
      continue;
    }
    const key = valued[a];
    if (!key) usageError(`unknown argument ${a}`);
    if (v === undefined) {
      if (i + 1 >= argv.length) usageError(`${a} needs a value`);
      v = argv[++i];
    }
    opts[key] = v;
  }
  if (!opts.url) usageError("--url is required");
  for (const k of ["timeoutS", "intervalMs", "minDiffPixels", "expectSpan"]) {
    const n = Number(opts[k]);
    if (!Number.isFinite(n) || n < 0) usageError(`bad number for ${k}: ${opts[k]}`);
    opts[k] = n;
  }
  return opts;
}

function usageError(msg) {
  console.error(`browser_dashboard: ${msg}\n${USAGE}`);
  process.exit(2);
}

// ---- PNG decoding (8-bit RGB or RGBA, not interlaced: what Chromium writes) -------------------

function decodePng(buf) {
  const sig = [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a];
  if (buf.length < 8 || sig.some((b, i) => buf[i] !== b)) throw new Error("not a PNG");
  let off = 8;
  let width = 0, height = 0, depth = 0, colorType = 0, interlace = 0;
  const idat = [];
  while (off + 8 <= buf.length) {
    const len = buf.readUInt32BE(off);
    const type = buf.toString("latin1", off + 4, off + 8);
    const data = buf.subarray(off + 8, off + 8 + len);
    if (type === "IHDR") {
      width = data.readUInt32BE(0);
      height = data.readUInt32BE(4);
      depth = data[8];
      colorType = data[9];
      interlace = data[12];
    } else if (type === "IDAT") {
      idat.push(data);
    } else if (type === "IEND") {
      break;
    }
    off += 12 + len;
  }
  const bpp = colorType === 6 ? 4 : colorType === 2 ? 3 : 0;
  if (depth !== 8 || bpp === 0 || interlace !== 0) {
    throw new Error(`PNG of depth ${depth}, colour type ${colorType}, interlace ${interlace} not handled`);
  }
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = width * bpp;
  if (raw.length < height * (stride + 1)) throw new Error("PNG data shorter than its size");
  const px = Buffer.alloc(height * stride);
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    const src = y * (stride + 1) + 1;
    const dst = y * stride;
    for (let x = 0; x < stride; x++) {
      const a = x >= bpp ? px[dst + x - bpp] : 0;
      const b = y > 0 ? px[dst - stride + x] : 0;
      const c = x >= bpp && y > 0 ? px[dst - stride + x - bpp] : 0;
      let pred = 0;
      switch (filter) {
        case 0: pred = 0; break;
        case 1: pred = a; break;
        case 2: pred = b; break;
        case 3: pred = (a + b) >> 1; break;
        case 4: {
          const p = a + b - c;
          const pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
          pred = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
          break;
        }
        default: throw new Error(`PNG row filter ${filter} unknown`);
      }
      px[dst + x] = (raw[src + x] + pred) & 0xff;
    }
  }
  return { width, height, bpp, px };
}

// Pixels that differ between two images of the same size (sizes_differ if they are not).
function comparePngs(a, b) {
  const ia = decodePng(a);
  const ib = decodePng(b);
  const total = ia.width * ia.height;
  if (ia.width !== ib.width || ia.height !== ib.height || ia.bpp !== ib.bpp) {
    return { width: ia.width, height: ia.height, total, differing: 0, sizes_differ: true };
  }
  let differing = 0;
  for (let i = 0; i < total; i++) {
    const o = i * ia.bpp;
    for (let k = 0; k < ia.bpp; k++) {
      if (ia.px[o + k] !== ib.px[o + k]) {
        differing++;
        break;
      }
    }
  }
  return { width: ia.width, height: ia.height, total, differing, sizes_differ: false };
}

// ---- the run ---------------------------------------------------------------------------------

const LOCAL_HOSTS = new Set(["127.0.0.1", "localhost", "[::1]", "::1"]);

function isLocal(url) {
  if (url.startsWith("data:") || url.startsWith("blob:") || url === "about:blank") return true;
  try {
    return LOCAL_HOSTS.has(new URL(url).hostname);
  } catch (e) {
    return false;
  }
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  const started = Date.now();
  const timeout = opts.timeoutS * 1000;
  const report = {
    ok: false,
    url: opts.url,
    browser: null,
    messages: null,
    plots: null,
    screenshots: null,
    fault: null,
    verdict: null,
    status: null,
    console_errors: [],
    page_errors: [],
    failed_requests: [],
    external_requests: [],
    elapsed_s: 0,
  };
  const step = (what) => console.error(`browser_dashboard: ${what}`);
  const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), "browser_dashboard-"));
  const args = [
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
  ];
  if (typeof process.getuid === "function" && process.getuid() === 0) args.push("--no-sandbox");

  let browser = null;
  try {
    if (!fs.existsSync(opts.chromium)) {
      throw new Error(`no browser at ${opts.chromium} (scripts/setup.sh installs chromium-headless-shell)`);
    }
    step(`starting ${opts.chromium}`);
    browser = await puppeteer.launch({
      executablePath: opts.chromium,
      headless: "shell",
      pipe: true,
      userDataDir,
      args,
      defaultViewport: { width: 1280, height: 900 },
    });
    report.browser = await browser.version();
    const page = await browser.newPage();
    page.on("console", (m) => {
      if (m.type() === "error") {
        const loc = m.location();
        report.console_errors.push(m.text() + (loc && loc.url ? ` (${loc.url}:${loc.lineNumber ?? "?"})` : ""));
      }
    });
    page.on("pageerror", (e) => report.page_errors.push(String(e && e.message ? e.message : e)));
    page.on("request", (r) => {
      if (!isLocal(r.url())) report.external_requests.push(r.url());
    });
    page.on("requestfailed", (r) => {
      report.failed_requests.push(`${r.url()}: ${r.failure() ? r.failure().errorText : "failed"}`);
    });
    page.on("response", (r) => {
      if (r.status() >= 400) report.failed_requests.push(`${r.url()}: HTTP ${r.status()}`);
    });

    step(`opening ${opts.url}`);
    let resp;
    try {
      resp = await page.goto(opts.url, { waitUntil: "load", timeout });
    } catch (e) {
      throw new Error(`the page did not load: ${e.message}`);
    }
    if (!resp || !resp.ok()) throw new Error(`the page did not load: HTTP ${resp ? resp.status() : "no response"}`);

    const readState = () => page.evaluate(() => {
      const ds = (sel) => document.querySelector(sel)?.dataset ?? {};
      const txt = (sel) => document.querySelector(sel)?.textContent ?? null;
      return {
        count: Number(ds("#count").count ?? NaN),
        status: ds("#status").state ?? null,
        statusText: txt("#status"),
        verdictState: ds("#verdict").state ?? null,
        verdictText: txt("#verdict"),
        rigTime: Number(ds("#rigtime").tS || NaN),
        truthPoints: Number(ds("#plot-phi").truthPoints ?? NaN),
        estimatePoints: Number(ds("#plot-phi").estimatePoints ?? NaN),
        truthSpan: Number(ds("#plot-phi").truthTo || NaN) - Number(ds("#plot-phi").truthFrom || NaN),
        estimateSpan: Number(ds("#plot-phi").estimateTo || NaN) - Number(ds("#plot-phi").estimateFrom || NaN),
        faults: document.querySelectorAll("#faults li").length,
      };
    });
    const missing = await page.evaluate(() =>
      ["#status", "#count", "#verdict", "#plots", "#plot-phi", "#plot-p", "#plot-v", "#faults"]
        .filter((s) => !document.querySelector(s)));
    if (missing.length) throw new Error(`the page lacks ${missing.join(", ")}`);

    // 1. live data: the counter leaves zero, then rises again.
    step("waiting for messages");
    const waitCount = async (above, what) => {
      try {
        await page.waitForFunction((n) => Number(document.querySelector("#count").dataset.count) > n,
          { timeout, polling: 100 }, above);
      } catch (e) {
        const s = await readState();
        throw new Error(`${what} within ${opts.timeoutS} s (count ${s.count}, link "${s.statusText}")`);
      }
      return (await readState()).count;
    };
    const first = await waitCount(0, "no message arrived");
    const tFirst = Date.now();
    if (opts.still) {
      report.messages = { first };
    } else {
      await waitCount(first, "the message count did not rise");
      await sleep(Math.max(0, 500 - (Date.now() - tFirst)));  // a rate over at least half a second
      const later = (await readState()).count;
      report.messages = {
        first,
        later,
        per_s: Math.round(((later - first) / Math.max(0.001, (Date.now() - tFirst) / 1000)) * 10) / 10,
      };
    }

    // 2. both sources in the plots.
    step("waiting for truth and estimate in the plots");
    try {
      await page.waitForFunction(() => {
        const d = document.querySelector("#plot-phi").dataset;
        return Number(d.truthPoints) > 0 && Number(d.estimatePoints) > 0;
      }, { timeout, polling: 100 });
    } catch (e) {
      const s = await readState();
      throw new Error(`the plots did not get both truth and estimate within ${opts.timeoutS} s ` +
        `(truth ${s.truthPoints} samples, estimate ${s.estimatePoints})`);
    }
    if (opts.expectSpan > 0) {
      step(`waiting for truth and estimate over ${opts.expectSpan} s of rig time`);
      try {
        await page.waitForFunction((span) => {
          const d = document.querySelector("#plot-phi").dataset;
          return Number(d.truthTo) - Number(d.truthFrom) >= span && Number(d.estimateTo) - Number(d.estimateFrom) >= span;
        }, { timeout, polling: 100 }, opts.expectSpan);
      } catch (e) {
        const s = await readState();
        throw new Error(`the plots did not come to span ${opts.expectSpan} s of rig time within ${opts.timeoutS} s ` +
          `(truth ${s.truthSpan} s, estimate ${s.estimateSpan} s)`);
      }
    }
    const plotted = await readState();
    report.plots = {
      truth_points: plotted.truthPoints,
      estimate_points: plotted.estimatePoints,
      truth_span_s: plotted.truthSpan,
      estimate_span_s: plotted.estimateSpan,
    };

    // 3. the plots move: each plot as drawn on its canvas, with the rig time drawn up to, read in
    // one go after two animation frames (a pending layout and redraw done).
    report.screenshots = { interval_ms: opts.intervalMs, files: [] };
    if (opts.screenshots) fs.mkdirSync(opts.screenshots, { recursive: true });
    const capture = () => page.evaluate(() => new Promise((resolve) => {
      requestAnimationFrame(() => requestAnimationFrame(() => {
        resolve({
          rigTime: Number(document.querySelector("#rigtime").dataset.tS || NaN),
          plots: Array.from(document.querySelectorAll("#plots figure.plot"), (fig) => {
            const c = fig.querySelector("canvas");
            return { plot: fig.dataset.plot, png: c ? c.toDataURL("image/png") : null };
          }),
        });
      }));
    }));
    const pngOf = (p) => Buffer.from(p.png.slice(p.png.indexOf(",") + 1), "base64");
    if (!opts.still) {
      step("comparing the plots as drawn twice");
      await sleep(300);  // a redraw after the first samples
      let a = null, b = null, cmps = null, resized = 0;
      const deadline = Date.now() + timeout;
      for (;;) {
        a = await capture();
        await sleep(opts.intervalMs);
        b = await capture();
        if (a.plots.length !== 3 || a.plots.some((p) => !p.png) || b.plots.length !== a.plots.length) {
          throw new Error(`the plots have no canvas to compare (${a.plots.length} plots)`);
        }
        cmps = a.plots.map((p, i) => comparePngs(pngOf(p), pngOf(b.plots[i])));
        if (!cmps.some((c) => c.sizes_differ)) break;
        resized++;  // a plot changed its size between the captures: the layout was not settled
        if (Date.now() > deadline) {
          throw new Error(`the plots kept changing their size for ${opts.timeoutS} s (${resized} pairs of captures)`);
        }
      }
      const differing = cmps.reduce((n, c) => n + c.differing, 0);
      const total = cmps.reduce((n, c) => n + c.total, 0);
      report.plots.rig_time_s = [a.rigTime, b.rigTime];
      Object.assign(report.screenshots, {
        canvases: cmps.map((c, i) => ({ plot: a.plots[i].plot, width: c.width, height: c.height, differing: c.differing })),
        resized_pairs: resized,
        differing_pixels: differing,
        total_pixels: total,
        differing_fraction: Math.round((differing / Math.max(1, total)) * 1e4) / 1e4,
      });
      if (opts.screenshots) {
        for (const [k, shot] of [[1, a], [2, b]]) {
          for (const p of shot.plots) {
            const f = path.join(opts.screenshots, `plots-${k}-${p.plot}.png`);
            fs.writeFileSync(f, pngOf(p));
            report.screenshots.files.push(f);
          }
        }
      }
      if (!Number.isFinite(a.rigTime) || !Number.isFinite(b.rigTime) || a.rigTime === b.rigTime) {
        throw new Error(`the plots did not move: both captures ${opts.intervalMs} ms apart show rig time ${a.rigTime} s`);
      }
      if (differing < opts.minDiffPixels) {
        throw new Error(`the plots did not move: ${differing} pixels differ between two captures ` +
          `${opts.intervalMs} ms apart (at least ${opts.minDiffPixels} wanted)`);
      }
    }

    // 4. the expected fault.
    if (opts.expectFault !== null) {
      step(`waiting for a fault containing "${opts.expectFault}"`);
      const t0 = Date.now();
      let found = null;
      try {
        const h = await page.waitForFunction((text) => {
          for (const li of document.querySelectorAll("#faults li")) {
            if (li.textContent.includes(text)) return Array.from(li.children, (c) => c.textContent).join(" | ");
          }
          return false;
        }, { timeout, polling: 100 }, opts.expectFault);
        found = await h.jsonValue();
      } catch (e) {
        const listed = await page.$$eval("#faults li",
          (lis) => lis.slice(0, 10).map((li) => Array.from(li.children, (c) => c.textContent).join(" | ")));
        report.fault = { expected: opts.expectFault, found: null, listed };
        throw new Error(`no fault containing "${opts.expectFault}" within ${opts.timeoutS} s ` +
          `(${listed.length ? "listed: " + listed.join("; ") : "the list is empty"})`);
      }
      report.fault = { expected: opts.expectFault, found, after_s: (Date.now() - t0) / 1000 };
    }

    // 5. the expected verdict.
    if (opts.expectVerdict !== null) {
      step(`waiting for a verdict containing "${opts.expectVerdict}"`);
      try {
        await page.waitForFunction((text) => document.querySelector("#verdict").textContent.includes(text),
          { timeout, polling: 100 }, opts.expectVerdict);
      } catch (e) {
        const s = await readState();
        throw new Error(`the run line did not come to contain "${opts.expectVerdict}" within ` +
          `${opts.timeoutS} s (it reads "${s.verdictText}")`);
      }
    }

    if (opts.screenshots) {
      fs.mkdirSync(opts.screenshots, { recursive: true });
      const f = path.join(opts.screenshots, "page.png");
      await page.screenshot({ path: f, fullPage: true });
      report.screenshots.files.push(f);
    }

    const last = await readState();
    report.status = last.statusText;
    report.verdict = { state: last.verdictState, text: last.verdictText };
    report.faults_listed = last.faults;

    // 6. a clean page.
    const problems = [];
    if (report.console_errors.length) problems.push(`${report.console_errors.length} console error(s): ${report.console_errors[0]}`);
    if (report.page_errors.length) problems.push(`${report.page_errors.length} uncaught error(s): ${report.page_errors[0]}`);
    if (report.failed_requests.length) problems.push(`${report.failed_requests.length} failed request(s): ${report.failed_requests[0]}`);
    if (report.external_requests.length) problems.push(`requests beyond this machine: ${report.external_requests[0]}`);
    if (problems.length) throw new Error(problems.join("; "));
    report.ok = true;
  } catch (e) {
    report.error = e && e.message ? e.message : String(e);
    const first = report.page_errors[0] ?? report.console_errors[0];
    if (first && !report.error.includes(first)) report.error += ` (the page's first error: ${first})`;
  } finally {
    if (browser) await browser.close().catch(() => {});
    fs.rmSync(userDataDir, { recursive: true, force: true });
  }
  report.elapsed_s = Math.round((Date.now() - started) / 100) / 10;
  console.log(JSON.stringify(report, null, 2));
  if (!report.ok) {
    console.error(`browser_dashboard: FAILED: ${report.error}`);
    process.exit(1);
  }
  console.error("browser_dashboard: passed");
}

main().catch((e) => {
  console.error(`browser_dashboard: FAILED: ${e && e.stack ? e.stack : e}`);
  process.exit(1);
});
