// A job's image assembling on a canvas the size of the frame, tile by tile as the event stream
// announces them: each tile is fetched as a PNG (GET /v1/jobs/{id}/tiles/{tx}/{ty}.png, made as
// preview.png is, server/tile_png.h) and drawn where its rectangle says.
//
// Exposure: with the job's own output.exposure_ev every tile uses it. Otherwise the first tile
// is fetched without one and the server picks the preview's automatic exposure at that moment
// (X-Exposure-EV); the page pins it for every later tile, so that the live image is of one
// piece. When the job is done its automatic exposure is asked for again; if it differs, the
// finished image is drawn from preview.png, so that the canvas ends as the preview.
//
// At most MAX_IN_FLIGHT tile requests run at once; a PNG's decoded bitmap is closed as soon as
// it is drawn, so that a 4096x4096 job's 16,384 tiles cost the canvas and little else.

import { apiFetch } from "./api.js";

const MAX_IN_FLIGHT = 6;

/// A PNG response as an ImageBitmap (close() it after), without colour conversion: the PNG and the
/// canvas are sRGB.
async function decodePng(response) {
  return createImageBitmap(await response.blob(), { colorSpaceConversion: "none", premultiplyAlpha: "none" });
}

export class TileCanvas {
  /// `status`: the job's status document (its job description gives the frame and exposure).
  constructor(canvas, status) {
    this.canvas = canvas;
    this.jobId = status.id;
    const image = status.job.image;
    canvas.width = image.width;
    canvas.height = image.height;
    this.context = canvas.getContext("2d", { alpha: false });
    this.context.fillStyle = "#000";
    this.context.fillRect(0, 0, image.width, image.height);
    const own = status.job.output && status.job.output.exposure_ev;
    this.fixedExposure = own !== undefined && own !== null;
    this.exposure = null;  // the pinned X-Exposure-EV, as the server wrote it
    this.pending = [];     // tile events not fetched yet, in arrival order, from pendingHead on
    this.pendingHead = 0;
    this.inFlight = 0;
    this.pinning = false;
    this.idleWaiters = [];
    this.closed = false;
    // Figures the browser test reads (tests/server/web_page_browser.mjs).
    this.tilesDrawn = 0;
    this.latencies = [];   // ms from the tile's event to its pixels on the canvas
    this.phases = [];      // per tile: [queued, request, read and decode, draw] in ms
    this.finalSource = "tiles";
    this.errors = [];
  }

  base() {
    return `/v1/jobs/${encodeURIComponent(this.jobId)}`;
  }

  /// A `tile` event: {tx, ty, rect: [x0, y0, x1, y1]}.
  add(event) {
    if (this.closed) return;
    this.pending.push({ tx: event.tx, ty: event.ty, rect: event.rect, at: performance.now() });
    this.pump();
  }

  waiting() {
    return this.pending.length - this.pendingHead;
  }

  /// The next tile to fetch; the queue is compacted now and then rather than shifted per tile.
  next() {
    const tile = this.pending[this.pendingHead++];
    if (this.pendingHead > 1024 && this.pendingHead * 2 > this.pending.length) {
      this.pending = this.pending.slice(this.pendingHead);
      this.pendingHead = 0;
    }
    return tile;
  }

  pump() {
    while (!this.closed && this.waiting() > 0 && this.inFlight < MAX_IN_FLIGHT) {
      // Without an exposure yet, the first request picks it and the others wait for it.
      const unpinned = !this.fixedExposure && this.exposure === null;
      if (unpinned && this.pinning) return;
      const tile = this.next();
      this.inFlight += 1;
      if (unpinned) this.pinning = true;
      this.draw(tile)
        .catch((error) => this.errors.push(`tile (${tile.tx}, ${tile.ty}): ${error.message}`))
        .finally(() => {
          this.inFlight -= 1;
          if (unpinned) this.pinning = false;
          this.pump();
          if (this.inFlight === 0 && this.waiting() === 0) {
            for (const resolve of this.idleWaiters.splice(0)) resolve();
          }
        });
    }
  }

  async draw(tile) {
    const started = performance.now();
    let path = `${this.base()}/tiles/${tile.tx}/${tile.ty}.png`;
    if (!this.fixedExposure && this.exposure !== null) path += `?exposure_ev=${encodeURIComponent(this.exposure)}`;
    const response = await apiFetch(path);
    if (!this.fixedExposure && this.exposure === null) this.exposure = response.headers.get("X-Exposure-EV");
    const answered = performance.now();
    const image = await decodePng(response);
    const decoded = performance.now();
    if (!this.closed) this.context.drawImage(image, tile.rect[0], tile.rect[1]);
    image.close();
    this.tilesDrawn += 1;
    const drawn = performance.now();
    this.latencies.push(drawn - tile.at);
    // Where the time went: waiting for a free request, the request, reading and decoding the
    // PNG, drawing.
    this.phases.push([started - tile.at, answered - started, decoded - answered, drawn - decoded]);
  }

  /// Resolves when every tile announced so far is drawn.
  idle() {
    if (this.inFlight === 0 && this.waiting() === 0) return Promise.resolve();
    return new Promise((resolve) => this.idleWaiters.push(resolve));
  }

  /// Draws a whole image (preview.png) over the canvas.
  async drawPreview() {
    const response = await apiFetch(`${this.base()}/preview.png`);
    const image = await decodePng(response);
    if (!this.closed) this.context.drawImage(image, 0, 0);
    image.close();
    this.finalSource = "preview";
  }

  /// The job is done: the last tiles drawn, then the final exposure checked (see above).
  async finish() {
    await this.idle();
    if (this.fixedExposure) return;
    if (this.exposure !== null) {
      const probe = await apiFetch(`${this.base()}/tiles/0/0.png`);
      const finalExposure = probe.headers.get("X-Exposure-EV");
      await probe.body.cancel();
      if (finalExposure === this.exposure) return;
    }
    this.exposure = null;
    await this.drawPreview();
  }

  close() {
    this.closed = true;
    this.pending = [];
    this.pendingHead = 0;
    for (const resolve of this.idleWaiters.splice(0)) resolve();
  }
}
