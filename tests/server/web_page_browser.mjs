// Drives the daemon's web page (server/web/) in Debian's chromium, headless, through
// puppeteer-core, against a running daemon; run by tests/server/web_page_test.cpp, which starts
// the daemon with a token and installs puppeteer-core into the build tree.
//
//   node web_page_browser.mjs '{"mode": "short"|"large", "base": "http://127.0.0.1:PORT",
//       "token": "...", "chromium": "/usr/bin/chromium", "puppeteer": "<dir with node_modules>",
//       "screenshots": "<dir>"|null, "large_size": 4096}'
//
// Prints one line "RESULT <json>" with what it saw and measured; the C++ test asserts on it.
// Steps that cannot go on throw; the error is in the result's "error".

import { createRequire } from "node:module";
import { readFileSync, readdirSync, mkdirSync, mkdtempSync, existsSync, rmSync } from "node:fs";
import os from "node:os";
import path from "node:path";

const options = JSON.parse(process.argv[2]);
const require = createRequire(path.join(options.puppeteer, "package.json"));
const puppeteer = require("puppeteer-core");

const result = { mode: options.mode, errors: [] };
const log = (...text) => console.log(new Date().toISOString().slice(11, 23), ...text);

// ------------------------------------------------------------------------- browser memory

/// Every process of the browser (the launched one and its descendants), from /proc.
function browserProcesses(root) {
  const children = new Map();
  for (const name of readdirSync("/proc")) {
    if (!/^\d+$/.test(name)) continue;
    try {
      const stat = readFileSync(`/proc/${name}/stat`, "utf8");
      const parent = Number(stat.slice(stat.lastIndexOf(")") + 2).split(" ")[1]);
      if (!children.has(parent)) children.set(parent, []);
      children.get(parent).push(Number(name));
    } catch {
      // gone meanwhile
    }
  }
  const all = [];
  const stack = [root];
  while (stack.length) {
    const pid = stack.pop();
    all.push(pid);
    stack.push(...(children.get(pid) || []));
  }
  return all;
}

/// kB of one process's field in /proc/<pid>/smaps_rollup ("Pss", "Rss"); 0 when gone.
function memoryKb(pid, field) {
  try {
    const text = readFileSync(`/proc/${pid}/smaps_rollup`, "utf8");
    const match = new RegExp(`^${field}:\\s+(\\d+) kB`, "m").exec(text);
    return match ? Number(match[1]) : 0;
  } catch {
    return 0;
  }
}

/// "browser", "renderer", "gpu-process", ... from chromium's --type= argument.
function processType(pid) {
  try {
    const match = /--type=(\S+)/.exec(readFileSync(`/proc/${pid}/cmdline`, "utf8"));
    return match ? match[1] : "browser";
  } catch {
    return "gone";
  }
}

class MemorySampler {
  constructor(browser, cdp) {
    this.root = browser.process().pid;
    this.cdp = cdp;
    this.peak = { pss_mb: 0, page_renderer_rss_mb: 0, gpu_process_rss_mb: 0, js_heap_used_mb: 0, js_heap_total_mb: 0 };
  }

  /// The page's renderer is the renderer process with the most memory (it holds the canvas);
  /// the GPU process rasterises it.
  async sample() {
    let pss = 0;
    let renderer = 0;
    let gpu = 0;
    const processes = [];
    for (const pid of browserProcesses(this.root)) {
      const own = memoryKb(pid, "Pss");
      const type = processType(pid);
      pss += own;
      if (type === "renderer") renderer = Math.max(renderer, memoryKb(pid, "Rss"));
      if (type === "gpu-process") gpu = Math.max(gpu, memoryKb(pid, "Rss"));
      processes.push(`${type} ${(own / 1024).toFixed(0)}`);
    }
    if (pss / 1024 > this.peak.pss_mb) this.peak.processes_pss_mb = processes;
    const { metrics } = await this.cdp.send("Performance.getMetrics");
    const metric = (name) => (metrics.find((m) => m.name === name) || { value: 0 }).value;
    const now = {
      pss_mb: pss / 1024,
      page_renderer_rss_mb: renderer / 1024,
      gpu_process_rss_mb: gpu / 1024,
      js_heap_used_mb: metric("JSHeapUsedSize") / 2 ** 20,
      js_heap_total_mb: metric("JSHeapTotalSize") / 2 ** 20,
    };
    for (const key of Object.keys(now)) this.peak[key] = Math.max(this.peak[key], now[key]);
    this.series = this.series || [];
    this.series.push([Math.round(performance.now()), Math.round(now.page_renderer_rss_mb), Math.round(now.gpu_process_rss_mb), Math.round(now.pss_mb)]);
    this.samples = (this.samples || 0) + 1;
    return now;
  }

  start(intervalMs) {
    this.timer = setInterval(() => this.sample().catch(() => {}), intervalMs);
  }

  stop() {
    clearInterval(this.timer);
  }
}

// ------------------------------------------------------------------------------ the page

async function firstPaintMs(page) {
  return page.evaluate(() => {
    const paint = performance.getEntriesByType("paint").find((entry) => entry.name === "first-paint");
    const contentful = performance.getEntriesByType("paint").find((entry) => entry.name === "first-contentful-paint");
    return { first_paint: paint ? paint.startTime : null, first_contentful_paint: contentful ? contentful.startTime : null };
  });
}

/// Answers the page's `question`-th request for the token; returns the reason it gave.
async function enterToken(page, question, value) {
  await page.waitForFunction((n) => window.photondPage.tokenQuestions >= n && document.getElementById("token-dialog").open,
    { timeout: 10000 }, question);
  const reason = await page.$eval("#token-reason", (node) => node.textContent);
  await page.$eval("#token-input", (node) => { node.value = ""; });
  await page.type("#token-input", value);
  await page.keyboard.press("Enter");
  return reason;
}

async function showQueue(page) {
  await page.evaluate(() => { location.hash = "#/"; });
  await page.waitForSelector("#queue-view:not([hidden])");
  // The form's choices come from the daemon: wait for the built-in scenes.
  await page.waitForFunction(() => document.querySelector("#scene-select option[value='builtin:cornell-box']") &&
    document.querySelector("#preset-select option"), { timeout: 20000 });
}

/// Fills the form (fields: {scene, path, preset, integrator, width, height, tile, spp, exposure,
/// from, at, vfov, aovs}) and submits it.
async function submitForm(page, fields) {
  await showQueue(page);
  await page.evaluate((f) => {
    const set = (id, value) => {
      const node = document.getElementById(id);
      node.value = value === undefined ? "" : String(value);
      node.dispatchEvent(new Event("change"));
    };
    set("scene-select", f.scene);
    set("scene-path", f.path);
    set("preset-select", f.preset || "preview");
    set("integrator-select", f.integrator || "");
    set("width", f.width);
    set("height", f.height);
    set("tile-size", f.tile);
    set("spp", f.spp);
    set("exposure", f.exposure);
    set("look-from", f.from);
    set("look-at", f.at);
    set("vfov", f.vfov);
    const boxes = [...document.querySelectorAll("#aov-choices input")];
    for (const box of boxes) box.checked = (f.aovs || []).includes(box.value);
    const missing = (f.aovs || []).filter((name) => !boxes.some((box) => box.value === name));
    if (missing.length) throw new Error(`the form offers no AOV ${missing.join(", ")}`);
  }, fields);
  await page.click("#submit-button");
}

async function submitJob(page, fields) {
  const before = await page.evaluate(() => location.hash);
  await submitForm(page, fields);
  await page.waitForFunction((old) => (location.hash !== old && location.hash.startsWith("#/jobs/")) ||
    !document.getElementById("submit-error").hidden, { timeout: 20000 }, before);
  const refused = await page.evaluate(() => {
    const box = document.getElementById("submit-error");
    return box.hidden ? "" : box.textContent;
  });
  if (refused) throw new Error(`the page refused the job: ${refused}`);
  return page.evaluate(() => decodeURIComponent(location.hash.slice("#/jobs/".length)));
}

async function waitForImage(page, timeoutMs) {
  await page.waitForFunction(() => window.photondPage.imageComplete === true, { timeout: timeoutMs, polling: 100 });
}

/// The canvas against the server's preview.png, decoded by the same browser: differing pixels.
async function compareWithPreview(page, jobId) {
  return page.evaluate(async (id) => {
    const canvas = document.getElementById("job-canvas");
    const frame = window.photondPage.canvas.framePixels();
    const shown = frame.data;
    const token = sessionStorage.getItem("photond.token");
    const response = await fetch(`/v1/jobs/${id}/preview.png`, { headers: { Authorization: `Bearer ${token}` } });
    const bitmap = await createImageBitmap(await response.blob(), { colorSpaceConversion: "none", premultiplyAlpha: "none" });
    const scratch = new OffscreenCanvas(bitmap.width, bitmap.height);
    const context = scratch.getContext("2d");
    context.drawImage(bitmap, 0, 0);
    const served = context.getImageData(0, 0, bitmap.width, bitmap.height).data;
    let differing = 0;
    let black = 0;
    for (let i = 0; i < shown.length; i += 4) {
      if (shown[i] !== served[i] || shown[i + 1] !== served[i + 1] || shown[i + 2] !== served[i + 2]) differing += 1;
      if (shown[i] === 0 && shown[i + 1] === 0 && shown[i + 2] === 0) black += 1;
    }
    const pageState = window.photondPage.canvas;
    // The canvas on the page (the frame itself, or shown smaller): not black.
    const onPage = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
    let shownBlack = 0;
    for (let i = 0; i < onPage.length; i += 4) shownBlack += onPage[i] === 0 && onPage[i + 1] === 0 && onPage[i + 2] === 0;
    return {
      canvas: [frame.width, frame.height],
      shown: [canvas.width, canvas.height],
      shown_black_fraction: shownBlack / (canvas.width * canvas.height),
      preview: [bitmap.width, bitmap.height],
      differing_pixels: differing,
      black_pixels: black,
      tiles_drawn: pageState.tilesDrawn,
      final_source: pageState.finalSource,
      exposure: pageState.exposure,
      tile_errors: pageState.errors,
      latencies_ms: pageState.latencies,
      phases_ms: pageState.phases,
    };
  }, jobId);
}

function summary(values) {
  if (!values.length) return null;
  const sorted = [...values].sort((a, b) => a - b);
  const at = (q) => sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))];
  return { count: sorted.length, median: at(0.5), p95: at(0.95), max: sorted[sorted.length - 1] };
}

async function serverStatus(page, jobId) {
  return page.evaluate(async (id) => {
    const token = sessionStorage.getItem("photond.token");
    return (await fetch(`/v1/jobs/${id}`, { headers: { Authorization: `Bearer ${token}` } })).json();
  }, jobId);
}

async function pageTexts(page) {
  return page.evaluate(() => ({
    state: document.getElementById("job-state").textContent,
    plan_rows: [...document.querySelectorAll("#plan-table tbody tr")].map((tr) => tr.textContent),
    timing_rows: [...document.querySelectorAll("#timing-table tbody tr")].map((tr) => tr.textContent),
    downloads: [...document.querySelectorAll("#downloads button")].map((b) => b.textContent),
    error: document.getElementById("job-error").hidden ? "" : document.getElementById("job-error").textContent,
  }));
}

async function screenshot(page, name) {
  if (!options.screenshots) return;
  mkdirSync(options.screenshots, { recursive: true });
  const file = path.join(options.screenshots, name);
  await page.screenshot({ path: file });
  result.screenshots = [...(result.screenshots || []), file];
}

// ------------------------------------------------------------------------------ the runs

async function shortRun(page, sampler) {
  // The token: a wrong one is refused and asked for again, the right one opens the page.
  result.token_question = await enterToken(page, 1, "not-the-token");
  result.token_refused_question = await enterToken(page, 2, options.token);
  await showQueue(page);
  result.token_in_session_storage = await page.evaluate(() => sessionStorage.getItem("photond.token"));

  // A job with its own exposure: the canvas is the tiles alone. Its tiles come at a steady pace
  // (16 spp), so that their latency is the page's and not that of a queue of tiles that arrive
  // faster than any page fetches them.
  log("job with its own exposure");
  const fixed = await submitJob(page, {
    scene: "builtin:cornell-box", preset: "final", width: 320, height: 240, tile: 32, spp: 16, exposure: 0.5,
    aovs: ["albedo", "normal"],
  });
  await waitForImage(page, 180000);
  result.fixed_exposure = { id: fixed, ...(await compareWithPreview(page, fixed)), texts: await pageTexts(page) };
  result.fixed_exposure.status = await serverStatus(page, fixed);
  await screenshot(page, "web-job.png");

  // Downloads, fetched with the token: the EXR and one AOV layer, as files.
  const downloads = mkdtempSync(path.join(os.tmpdir(), "photond_web_downloads_"));
  const session = await page.browser().target().createCDPSession();
  await session.send("Browser.setDownloadBehavior", { behavior: "allow", downloadPath: downloads });
  result.downloads = {};
  for (const [label, file] of [["image.exr", `${fixed}.exr`], ["albedo.exr", `${fixed}.albedo.exr`]]) {
    await page.evaluate((text) => [...document.querySelectorAll("#downloads button")].find((b) => b.textContent.startsWith(text)).click(), label);
    const target = path.join(downloads, file);
    const deadline = Date.now() + 20000;
    while (!existsSync(target) && Date.now() < deadline) await new Promise((resolve) => setTimeout(resolve, 100));
    const bytes = existsSync(target) ? readFileSync(target) : Buffer.alloc(0);
    result.downloads[label] = { bytes: bytes.length, exr_magic: bytes.length >= 4 && bytes.readUInt32LE(0) === 20000630 };
  }
  rmSync(downloads, { recursive: true, force: true });

  // Automatic exposure: live tiles at the first tile's exposure, the end as preview.png.
  log("job with automatic exposure");
  const automatic = await submitJob(page, {
    scene: "builtin:spheres-room", preset: "preview", width: 256, height: 192, tile: 32,
  });
  await waitForImage(page, 180000);
  result.automatic_exposure = { id: automatic, ...(await compareWithPreview(page, automatic)), texts: await pageTexts(page) };

  // Cancel: a long job, cancelled from its page once its first tile is drawn.
  log("cancel");
  const long = await submitJob(page, {
    scene: "builtin:cornell-box", preset: "reference", width: 512, height: 512, tile: 16,
  });
  await page.waitForFunction(() => window.photondPage.canvas && window.photondPage.canvas.tilesDrawn > 0,
    { timeout: 120000, polling: 50 });
  // The queue while it runs.
  await showQueue(page);
  await page.waitForFunction(() => document.querySelectorAll("#job-table tbody tr").length >= 3 &&
    document.querySelector("#job-table td.state.running"), { timeout: 10000 });
  result.queue_rows = await page.evaluate(() =>
    [...document.querySelectorAll("#job-table tbody tr")].map((tr) => tr.textContent));
  await screenshot(page, "web-queue.png");
  await page.evaluate((id) => { location.hash = `#/jobs/${encodeURIComponent(id)}`; }, long);
  await page.waitForSelector("#cancel-button:not([hidden])", { timeout: 10000 });
  await page.click("#cancel-button");
  await page.waitForFunction(() => document.getElementById("job-state").textContent === "cancelled", { timeout: 30000 });
  result.cancel = { id: long, texts: await pageTexts(page), status: (await serverStatus(page, long)).state };

  // A scene that does not exist: the form says so, naming the field.
  log("bad scene");
  await submitForm(page, { scene: "path:", path: "no/such/scene.gltf", preset: "preview" });
  await page.waitForSelector("#submit-error:not([hidden])", { timeout: 20000 });
  result.bad_scene = await page.evaluate(() => ({
    error: document.getElementById("submit-error").textContent,
    marked: document.getElementById("scene-path").classList.contains("invalid"),
    hash: location.hash,
  }));

  result.memory = await sampler.sample();
}

async function largeRun(page, sampler) {
  await enterToken(page, 1, options.token);
  await showQueue(page);
  const size = options.large_size || 4096;
  // The browser with the page open and no job: what chromium takes whatever the page does.
  result.memory_before_job = await sampler.sample();
  log(`${size}x${size} job`);
  sampler.start(250);
  const started = Date.now();
  const id = await submitJob(page, {
    scene: "builtin:cornell-box", preset: "preview", integrator: "direct", width: size, height: size, tile: 32, spp: 1,
  });
  await waitForImage(page, 3600000);
  const seconds = (Date.now() - started) / 1000;
  sampler.stop();
  await sampler.sample();
  // The comparison's own copies of the pixels are the test's, not the page's: measured before.
  result.memory_peak = { ...sampler.peak };
  result.memory_series = sampler.series.filter((_, i) => i % 8 === 0);
  result.large = { id, size, seconds, ...(await compareWithPreview(page, id)) };
  result.large.progress = (await serverStatus(page, id)).progress;
}

async function main() {
  const browser = await puppeteer.launch({
    executablePath: options.chromium,
    headless: true,
    // As root (CI) chromium needs --no-sandbox; /dev/shm of containers is small.
    args: ["--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu", "--window-size=1400,900"],
    defaultViewport: { width: 1400, height: 900 },
    protocolTimeout: 900000,
  });
  try {
    // The tab the browser opened with: a new one would leave a second renderer process behind.
    const [page] = await browser.pages();
    page.on("pageerror", (error) => result.errors.push(`page error: ${error.message}`));
    page.on("console", (message) => {
      // Refused requests (401, 422) are logged by the browser itself; the page handles them.
      if (message.type() === "error" && !message.text().startsWith("Failed to load resource"))
        result.errors.push(`console: ${message.text()}`);
    });
    const cdp = await page.createCDPSession();
    await cdp.send("Performance.enable");
    const sampler = new MemorySampler(browser, cdp);

    // First paint: the first load (a cold renderer) and four more.
    const paints = [];
    for (let i = 0; i < 5; ++i) {
      await page.goto(`${options.base}/`, { waitUntil: "load" });
      await page.waitForFunction(() => performance.getEntriesByType("paint").length > 0, { timeout: 10000 });
      paints.push(await firstPaintMs(page));
      if (i < 4) await page.evaluate(() => sessionStorage.clear());
    }
    result.first_paint_ms = paints.map((p) => p.first_paint);
    result.first_contentful_paint_ms = paints.map((p) => p.first_contentful_paint);

    if (options.mode === "large") await largeRun(page, sampler);
    else await shortRun(page, sampler);
    if (!result.memory_peak) result.memory_peak = sampler.peak;
    for (const key of ["fixed_exposure", "automatic_exposure", "large"]) {
      if (result[key] && result[key].latencies_ms) {
        result[key].latency_ms = summary(result[key].latencies_ms);
        delete result[key].latencies_ms;
        // Medians of where the time went.
        const phases = result[key].phases_ms;
        result[key].latency_phases_median_ms = Object.fromEntries(
          ["queued", "request", "read_and_decode", "draw"].map((name, i) => [name, summary(phases.map((p) => p[i])).median]));
        delete result[key].phases_ms;
      }
    }
  } catch (error) {
    result.error = error.stack || String(error);
  } finally {
    await browser.close();
  }
  console.log(`RESULT ${JSON.stringify(result)}`);
}

await main();
