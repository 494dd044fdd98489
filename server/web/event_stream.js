// A job's Server-Sent Events (GET /v1/jobs/{id}/events) read with fetch() and parsed here:
// EventSource cannot send the Authorization header (api.js). A dropped connection is resumed
// with Last-Event-ID after the server's `retry` delay, as EventSource would.

import { apiFetch } from "./api.js";

const TERMINAL = new Set(["done", "failed", "cancelled"]);

/// Parses one event block ("id: N\nevent: T\ndata: JSON"); null for comments and keep-alives.
function parseBlock(block) {
  let id = null;
  let type = "message";
  const data = [];
  let retry = null;
  for (const line of block.split("\n")) {
    if (line === "" || line.startsWith(":")) continue;
    const colon = line.indexOf(":");
    const field = colon < 0 ? line : line.slice(0, colon);
    let value = colon < 0 ? "" : line.slice(colon + 1);
    if (value.startsWith(" ")) value = value.slice(1);
    if (field === "id") id = Number(value);
    else if (field === "event") type = value;
    else if (field === "data") data.push(value);
    else if (field === "retry") retry = Number(value);
  }
  if (data.length === 0) return { retry };
  return { id, type, data: JSON.parse(data.join("\n")), retry };
}

/// Calls onEvent({id, type, data}) for every event of the job, history first, until the job's
/// last event (done, failed, cancelled) or until `signal` aborts. Resolves with the last type.
export async function followEvents(jobId, onEvent, signal) {
  let lastId = null;
  let retryMs = 2000;
  for (;;) {
    try {
      const headers = { Accept: "text/event-stream" };
      if (lastId !== null) headers["Last-Event-ID"] = String(lastId);
      const response = await apiFetch(`/v1/jobs/${encodeURIComponent(jobId)}/events`, { headers, signal });
      const reader = response.body.pipeThrough(new TextDecoderStream()).getReader();
      let buffer = "";
      for (;;) {
        const { value, done } = await reader.read();
        if (done) break;
        buffer += value.replaceAll("\r\n", "\n");
        // The history of a large job arrives as megabytes at once: its events are cut out by
        // position and the buffer is shortened once per chunk, not once per event.
        let start = 0;
        let end;
        while ((end = buffer.indexOf("\n\n", start)) >= 0) {
          const event = parseBlock(buffer.slice(start, end));
          start = end + 2;
          if (event.retry) retryMs = event.retry;
          if (!event.type) continue;
          if (event.id !== null) lastId = event.id;
          onEvent(event);
          if (TERMINAL.has(event.type)) {
            reader.cancel().catch(() => {});
            return event.type;
          }
        }
        buffer = buffer.slice(start);
      }
    } catch (error) {
      if (signal.aborted) return null;
      if (error.status && error.status !== 503) throw error;  // 404: no such job
    }
    if (signal.aborted) return null;
    await new Promise((resolve) => setTimeout(resolve, retryMs));
  }
}
