// A job's image assembling tile by tile as the event stream announces them: each tile is fetched
// as a PNG (GET /v1/jobs/{id}/tiles/{tx}/{ty}.png, made as preview.png is, server/tile_png.h)
// and drawn where its rectangle says into the frame, a canvas of the image's size.
//
// The frame is shown as it is when it is at most MAX_SHOWN pixels wide and high. A larger one is
// kept off the page (an OffscreenCanvas, in the page's own memory) and shown through a canvas
// smaller by a whole factor, each tile drawn into both: a 4096x4096 frame costs its 64 MB once,
// instead of again in the compositor's and the GPU process's copies of a canvas that size.
//
// Exposure: with the job's own output.exposure_ev every tile uses it. Otherwise the first tile
// is fetched without one and the server picks the preview's automatic exposure at that moment
// (X-Exposure-EV); the page pins it for every later tile, so that the live image is of one
// piece. When the job is done its automatic exposure is asked for again; if it differs, the
// finished image is drawn from preview.png, so that the frame ends as the preview.
//
// Progressive jobs (README.md, "Progressive previews") first announce a preview of the whole
// frame as tile events with `preview: true`; each is fetched with ?preview=true and drawn until
// its final tile replaces it. A preview tile whose final tile was announced before it was
// fetched is dropped, and one that arrives after its final tile was drawn is not drawn (the
// answer's X-Tile-Kind says which pixels came), so the frame only ever improves.
//
// At most MAX_IN_FLIGHT tile requests run at once; a PNG's decoded bitmap is closed as soon as
// it is drawn.

import { apiFetch } from "./api.js";

const MAX_IN_FLIGHT = 6;
const MAX_SHOWN = 1280;

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
    // The frame's pixels stay on the CPU (willReadFrequently), where the test reads them back.
    const options = { alpha: false, willReadFrequently: true };
    this.shrink = Math.ceil(Math.max(image.width, image.height) / MAX_SHOWN);
    canvas.width = Math.ceil(image.width / this.shrink);
    canvas.height = Math.ceil(image.height / this.shrink);
    if (this.shrink === 1) {
      this.shown = canvas.getContext("2d", options);
      this.frame = this.shown;
    } else {
      this.shown = canvas.getContext("2d", { alpha: false });
      this.shown.imageSmoothingQuality = "high";
      this.frame = new OffscreenCanvas(image.width, image.height).getContext("2d", options);
    }
    for (const context of [this.shown, this.frame]) {
      context.fillStyle = "#000";
      context.fillRect(0, 0, context.canvas.width, context.canvas.height);
    }
    const own = status.job.output && status.job.output.exposure_ev;
    this.fixedExposure = own !== undefined && own !== null;
    this.exposure = null;  // the pinned X-Exposure-EV, as the server wrote it
    this.pending = [];     // tile events not fetched yet, in arrival order, from pendingHead on
    this.pendingHead = 0;
    this.inFlight = 0;
    this.pinning = false;
    this.idleWaiters = [];
    this.closed = false;
    this.finalSeen = new Set();   // "tx,ty" of final tiles announced
    this.finalDrawn = new Set();  // "tx,ty" of tiles whose final pixels are drawn
    // Figures the browser test reads (tests/server/web_page_browser.mjs).
    this.tilesDrawn = 0;          // final tiles
    this.previewTilesDrawn = 0;
    this.covered = new Set();     // "tx,ty" of tiles drawn, preview or final
    this.tilesTotal = 0;
    this.frameCoveredAt = null;   // performance.now() when every tile was drawn, preview or final
    this.latencies = [];   // ms from the tile's event to its pixels on the canvas
    this.phases = [];      // per tile: [queued, request, read and decode, draw] in ms
    this.finalSource = "tiles";
    this.errors = [];
  }

  base() {
    return `/v1/jobs/${encodeURIComponent(this.jobId)}`;
  }

  /// A `tile` event: {tx, ty, rect: [x0, y0, x1, y1], preview?, preview_tiles_done?, tiles_total}.
  add(event) {
    if (this.closed) return;
    const preview = event.preview === true;
    if (!preview) this.finalSeen.add(`${event.tx},${event.ty}`);
    this.tilesTotal = event.tiles_total;
    this.pending.push({ tx: event.tx, ty: event.ty, rect: event.rect, at: performance.now(), preview });
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
      // A preview tile whose final tile is already announced: not worth a request.
      if (tile.preview && this.finalSeen.has(`${tile.tx},${tile.ty}`)) {
        if (this.inFlight === 0 && this.waiting() === 0) {
          for (const resolve of this.idleWaiters.splice(0)) resolve();
        }
        continue;
      }
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
    const query = [];
    if (!this.fixedExposure && this.exposure !== null) query.push(`exposure_ev=${encodeURIComponent(this.exposure)}`);
    if (tile.preview) query.push("preview=true");
    const path = `${this.base()}/tiles/${tile.tx}/${tile.ty}.png` + (query.length ? `?${query.join("&")}` : "");
    const response = await apiFetch(path);
    if (!this.fixedExposure && this.exposure === null) this.exposure = response.headers.get("X-Exposure-EV");
    const answered = performance.now();
    const image = await decodePng(response);
    const decoded = performance.now();
    const key = `${tile.tx},${tile.ty}`;
    const gotFinal = response.headers.get("X-Tile-Kind") !== "preview";
    // Preview pixels never cover final ones drawn before them.
    if (!this.closed && (gotFinal || !this.finalDrawn.has(key))) this.place(image, tile.rect);
    image.close();
    if (gotFinal) this.finalDrawn.add(key);
    this.covered.add(key);
    if (this.frameCoveredAt === null && this.covered.size === this.tilesTotal) this.frameCoveredAt = performance.now();
    if (tile.preview) {
      this.previewTilesDrawn += 1;
      return;
    }
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
    if (!this.closed) {
      this.frame.drawImage(image, 0, 0);
      if (this.frame !== this.shown) this.shown.drawImage(this.frame.canvas, 0, 0, this.canvas.width, this.canvas.height);
    }
    image.close();
    this.finalSource = "preview";
  }

  /// Draws a decoded tile into the frame at rect [x0, y0, x1, y1] and, when the frame is shown
  /// smaller, into the shown canvas too (rounded so that neighbours share their edges).
  place(image, rect) {
    this.frame.drawImage(image, rect[0], rect[1]);
    if (this.frame === this.shown) return;
    const k = this.shrink;
    const x0 = Math.floor(rect[0] / k);
    const y0 = Math.floor(rect[1] / k);
    this.shown.drawImage(image, x0, y0, Math.floor(rect[2] / k) - x0, Math.floor(rect[3] / k) - y0);
  }

  /// The frame's pixels (what the browser test compares with preview.png).
  framePixels() {
    return this.frame.getImageData(0, 0, this.frame.canvas.width, this.frame.canvas.height);
  }

  /// When the job is done: the shown canvas drawn again from the whole frame in one go.
  refreshShown() {
    if (this.frame !== this.shown && !this.closed) {
      this.shown.drawImage(this.frame.canvas, 0, 0, this.canvas.width, this.canvas.height);
    }
  }

  /// The job is done: the last tiles drawn, then the final exposure checked (see above).
  async finish() {
    await this.idle();
    if (!this.fixedExposure) {
      let finalExposure = null;
      if (this.exposure !== null) {
        const probe = await apiFetch(`${this.base()}/tiles/0/0.png`);
        finalExposure = probe.headers.get("X-Exposure-EV");
        await probe.body.cancel();
      }
      if (finalExposure !== this.exposure || finalExposure === null) {
        this.exposure = null;
        await this.drawPreview();
        return;
      }
    }
    this.refreshShown();
  }

  close() {
    this.closed = true;
    this.pending = [];
    this.pendingHead = 0;
    for (const resolve of this.idleWaiters.splice(0)) resolve();
  }
}
