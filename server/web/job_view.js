// The page of one job (#/jobs/{id}): its state and progress, the image assembling live
// (tile_canvas.js), the plan with each pass that runs or is skipped and why, the pass timings,
// the warnings, cancel, and the downloads (the EXR with its AOV layers, each AOV layer as an EXR
// of its own, the PNG preview).
//
// Every text from the daemon is put in with textContent, never parsed as HTML.

import { ApiError, apiFetch, apiJson, download } from "./api.js";
import { followEvents } from "./event_stream.js";
import { TileCanvas } from "./tile_canvas.js";

const $ = (id) => document.getElementById(id);

function element(tag, text, className) {
  const node = document.createElement(tag);
  if (text !== undefined) node.textContent = text;
  if (className) node.className = className;
  return node;
}

function row(cells) {
  const tr = document.createElement("tr");
  for (const cell of cells) tr.append(cell instanceof Node ? cell : element("td", String(cell)));
  return tr;
}

function sceneName(scene) {
  if (!scene) return "";
  if (scene.builtin) return `built-in ${scene.builtin}`;
  if (scene.path) return scene.path;
  return scene.id || "";
}

export class JobView {
  constructor(jobId) {
    this.jobId = jobId;
    this.abort = new AbortController();
    this.canvas = null;
    this.status = null;
  }

  base() {
    return `/v1/jobs/${encodeURIComponent(this.jobId)}`;
  }

  async open() {
    $("job-title").textContent = `Job ${this.jobId}`;
    for (const id of ["plan-table", "timing-table"]) $(id).tBodies[0].replaceChildren();
    $("warning-list").replaceChildren();
    $("job-facts").replaceChildren();
    $("downloads").replaceChildren();
    $("job-error").hidden = true;
    $("job-image-note").textContent = "";
    $("cancel-button").onclick = () => this.cancel();
    let status;
    try {
      status = await apiJson(this.base(), { signal: this.abort.signal });
    } catch (error) {
      if (this.abort.signal.aborted) return;
      this.showError(error instanceof ApiError ? `${error.title}: ${error.detail}` : error.message);
      return;
    }
    this.show(status);
    this.canvas = new TileCanvas($("job-canvas"), status);
    window.photondPage.canvas = this.canvas;
    if (status.state === "done") {
      await this.canvas.drawPreview();
      this.imageReady();
      return;
    }
    if (status.state === "failed" || status.state === "cancelled") return;
    this.poll();
    try {
      await followEvents(this.jobId, (event) => this.onEvent(event), this.abort.signal);
    } catch (error) {
      if (!this.abort.signal.aborted) this.showError(`The event stream failed: ${error.message}`);
    }
  }

  close() {
    this.abort.abort();
    cancelAnimationFrame(this.progressFrame);
    if (this.canvas) this.canvas.close();
    clearTimeout(this.pollTimer);
  }

  /// Timings and the plan are in the status only: read it every second while the job runs.
  poll() {
    this.pollTimer = setTimeout(async () => {
      if (this.abort.signal.aborted) return;
      try {
        const status = await apiJson(this.base(), { signal: this.abort.signal });
        if (!this.ended) this.show(status);
      } catch {
        // The next event or poll shows what is wrong.
      }
      if (!this.ended) this.poll();
    }, 1000);
  }

  onEvent(event) {
    const data = event.data;
    switch (event.type) {
      case "tile":
        this.canvas.add(data);
        this.showProgress(data.tiles_done, data.tiles_total, this.status.pass);
        break;
      case "progress":
        this.showProgress(data.tiles_done, data.tiles_total, data.pass);
        break;
      case "state":
        this.status.state = data.state;
        this.showState(data.state, data.reason);
        break;
      case "done":
        this.ended = true;
        this.show(data);
        this.canvas.finish().then(() => this.imageReady(), (error) => this.showError(error.message));
        break;
      case "failed":
      case "cancelled":
        this.ended = true;
        this.show(data);
        this.canvas.close();
        break;
    }
  }

  imageReady() {
    window.photondPage.imageComplete = true;
    $("job-image-note").textContent =
      this.canvas.finalSource === "preview" ? "The finished image, at its final exposure." : "";
  }

  async cancel() {
    $("cancel-button").disabled = true;
    try {
      const response = await apiFetch(this.base(), { method: "DELETE" });
      this.show(await response.json());
    } catch (error) {
      this.showError(error instanceof ApiError ? `${error.title}: ${error.detail}` : error.message);
      $("cancel-button").disabled = false;
    }
  }

  showError(text) {
    $("job-error").textContent = text;
    $("job-error").hidden = false;
  }

  showState(state, reason) {
    const badge = $("job-state");
    badge.textContent = state;
    badge.className = `state ${state}`;
    const cancellable = state === "queued" || state === "running";
    $("cancel-button").hidden = !cancellable;
    if (!cancellable) $("cancel-button").disabled = false;
    if (reason && state !== "running") this.showError(reason);
  }

  /// Drawn once per frame at most: a large job's events come by the thousand.
  showProgress(done, total, pass) {
    this.progress = { done, total, pass };
    if (this.progressFrame) return;
    this.progressFrame = requestAnimationFrame(() => {
      this.progressFrame = 0;
      const p = this.progress;
      const fraction = p.total > 0 ? p.done / p.total : 0;
      $("job-progress-bar").style.width = `${(100 * fraction).toFixed(1)}%`;
      $("job-progress-text").textContent = `${p.done} of ${p.total} tiles` + (p.pass ? ` · ${p.pass}` : "");
    });
  }

  show(status) {
    this.status = status;
    this.showState(status.state);
    const progress = status.progress || {};
    this.showProgress(progress.tiles_done || 0, progress.tiles_total || 0, status.pass);
    if (status.state === "failed") this.showError(`Failed: ${status.error}`);
    if (status.state === "cancelled") this.showError(status.error ? `Cancelled: ${status.error}` : "Cancelled.");

    const plan = status.plan || [];
    $("plan-table").tBodies[0].replaceChildren(
      ...plan.map((entry) =>
        row([entry.pass, element("td", entry.enabled ? "runs" : "skipped", entry.enabled ? "runs" : "skipped"), entry.reason])));
    $("plan-empty").hidden = plan.length > 0;

    // In the order the passes ran (statistics.passes, once the render ended); `timings` is keyed
    // by name.
    const timings = (status.statistics && status.statistics.passes) ||
      Object.entries(status.timings || {}).map(([name, seconds]) => ({ name, seconds }));
    const total = timings.reduce((sum, t) => sum + t.seconds, 0);
    $("timing-table").tBodies[0].replaceChildren(
      ...timings.map((t) => row([t.name, element("td", t.seconds.toFixed(3), "number")])),
      ...(timings.length ? [row([element("th", "total"), element("th", total.toFixed(3), "number")])] : []));

    const warnings = status.warnings || [];
    $("warning-list").replaceChildren(...warnings.map((w) => element("li", w)));
    $("warning-empty").hidden = warnings.length > 0;

    const job = status.job || {};
    const image = job.image || {};
    const facts = [
      ["Scene", sceneName(job.scene)],
      ["Preset", job.preset],
      ["Integrator", job.integrator],
      ["Size", image.width ? `${image.width} × ${image.height}, ${image.spp} spp, tiles of ${image.tile_size}` : ""],
      ["Photon maps", status.photons ? `${status.photons.cache || ""} ${status.photons.key || ""}` : ""],
      ["Created", status.created_at],
      ["Started", status.started_at],
      ["Finished", status.finished_at],
    ];
    $("job-facts").replaceChildren(
      ...facts.filter(([, value]) => value).flatMap(([name, value]) => [element("dt", name), element("dd", String(value))]));

    this.showDownloads(status);
  }

  showDownloads(status) {
    const links = $("downloads");
    if (status.state !== "done" || links.childElementCount > 0) return;
    const aovs = (status.job && status.job.output && status.job.output.aovs) || [];
    const exr = element("button", aovs.length ? `image.exr (beauty, ${aovs.join(", ")})` : "image.exr");
    exr.type = "button";
    exr.id = "download-exr";
    exr.onclick = () => download(`${this.base()}/image.exr`, `${this.jobId}.exr`).catch((e) => this.showError(e.message));
    const layers = aovs.map((name) => {
      const button = element("button", `${name}.exr`);
      button.type = "button";
      button.onclick = () =>
        download(`${this.base()}/layers/${name}.exr`, `${this.jobId}.${name}.exr`).catch((e) => this.showError(e.message));
      return button;
    });
    const png = element("button", "preview.png");
    png.type = "button";
    png.id = "download-png";
    png.onclick = () => download(`${this.base()}/preview.png`, `${this.jobId}.png`).catch((e) => this.showError(e.message));
    links.append(element("span", "Download ", "hint"), exr, ...layers, png);
  }
}
