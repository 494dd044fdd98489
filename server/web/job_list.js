// The job list of the queue page (#/): every job, newest first, with its state and progress,
// read again every second while the page shows it (GET /v1/jobs).

import { ApiError, apiJson } from "./api.js";

const $ = (id) => document.getElementById(id);
const LIMIT = 200;

function cell(text, className) {
  const td = document.createElement("td");
  td.textContent = text;
  if (className) td.className = className;
  return td;
}

function seconds(from, to) {
  if (!from) return "";
  const end = to ? Date.parse(to) : Date.now();
  return `${((end - Date.parse(from)) / 1000).toFixed(1)} s`;
}

function jobRow(job) {
  const tr = document.createElement("tr");
  tr.dataset.id = job.id;
  const link = document.createElement("a");
  link.href = `#/jobs/${encodeURIComponent(job.id)}`;
  link.textContent = job.id;
  const id = document.createElement("td");
  id.append(link);
  const state = cell(job.state, `state ${job.state}`);
  const progress = document.createElement("td");
  const bar = document.createElement("progress");
  bar.max = job.progress.tiles_total || 1;
  bar.value = job.progress.tiles_done;
  progress.append(bar, ` ${job.progress.tiles_done}/${job.progress.tiles_total}`);
  // The time of day (UTC) in the table, the whole timestamp on hover.
  const created = cell((job.created_at || "").slice(11, 19));
  created.title = job.created_at || "";
  tr.append(id, state, progress, cell(job.pass || ""), created, cell(seconds(job.started_at, job.finished_at), "number"));
  return tr;
}

export class JobList {
  constructor() {
    this.timer = null;
  }

  open() {
    this.refresh();
  }

  close() {
    clearTimeout(this.timer);
    this.timer = null;
    this.closed = true;
  }

  async refresh() {
    this.closed = false;
    clearTimeout(this.timer);
    try {
      const { jobs } = await apiJson(`/v1/jobs?limit=${LIMIT}`);
      if (this.closed) return;
      $("job-table").tBodies[0].replaceChildren(...jobs.map(jobRow));
      $("job-table-empty").hidden = jobs.length > 0;
      $("job-table-error").hidden = true;
    } catch (error) {
      $("job-table-error").textContent =
        error instanceof ApiError ? `${error.title}: ${error.detail}` : `The daemon cannot be reached: ${error.message}`;
      $("job-table-error").hidden = false;
    }
    if (!this.closed) this.timer = setTimeout(() => this.refresh(), 1000);
  }
}
