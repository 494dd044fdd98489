// The submission form of the queue page: the scene (a built-in one, an uploaded one, or a file
// under --scene-root), the preset, the size, the camera, the exposure and the AOV layers. Its
// choices come from the daemon: the built-in scenes, presets and AOVs from the job schema of
// GET /v1/openapi.json, the uploaded scenes from GET /v1/scenes. The daemon validates the job;
// a refusal is shown as its problem's detail, with the field it names marked.

import { ApiError, apiFetch, apiJson } from "./api.js";

const $ = (id) => document.getElementById(id);

// The problem's field (protocol/job.h's names) -> the input to mark.
const FIELD_INPUTS = [
  ["scene.path", "scene-path"],
  ["scene", "scene-select"],
  ["preset", "preset-select"],
  ["image.width", "width"],
  ["image.height", "height"],
  ["image.tile_size", "tile-size"],
  ["image.spp", "spp"],
  ["integrator", "integrator-select"],
  ["camera.look_from", "look-from"],
  ["camera.look_at", "look-at"],
  ["camera.vfov_deg", "vfov"],
  ["camera", "look-from"],
  ["output.exposure_ev", "exposure"],
];

function option(value, text, group) {
  const node = document.createElement("option");
  node.value = value;
  node.textContent = text;
  if (group) group.append(node);
  return node;
}

function optgroup(label) {
  const group = document.createElement("optgroup");
  group.label = label;
  return group;
}

/// "1 2 3" or "1, 2, 3" -> [1, 2, 3]; anything else is sent as written, for the daemon to refuse.
function vector(text) {
  const parts = text.trim().split(/[\s,]+/).filter(Boolean);
  const numbers = parts.map(Number);
  return numbers.length === 3 && numbers.every(Number.isFinite) ? numbers : text;
}

function number(text) {
  const value = Number(text);
  return text.trim() !== "" && Number.isFinite(value) ? value : text;
}

export class SubmitForm {
  constructor(onSubmitted) {
    this.onSubmitted = onSubmitted;
    $("submit-form").addEventListener("submit", (event) => {
      event.preventDefault();
      this.submit();
    });
    $("scene-select").addEventListener("change", () => {
      $("scene-path-label").hidden = $("scene-select").value !== "path:";
    });
  }

  async loadSchema() {
    const openapi = await apiJson("/v1/openapi.json");
    this.schema = openapi.components.schemas.Job;
    const presets = this.schema.properties.preset;
    $("preset-select").replaceChildren(...presets.enum.map((name) => option(name, name)));
    $("preset-select").value = presets.default;
    $("integrator-select").append(...this.schema.properties.integrator.enum.map((name) => option(name, name)));
    const aovs = this.schema.properties.output.properties.aovs.items.enum;
    $("aov-choices").replaceChildren(
      ...aovs.map((name) => {
        const label = document.createElement("label");
        const box = document.createElement("input");
        box.type = "checkbox";
        box.value = name;
        box.name = "aov";
        label.append(box, ` ${name}`);
        return label;
      }));
  }

  /// Fills the choices (once per page load; the uploaded scenes on every visit). Visits may
  /// overlap: the schema's choices are built by one load alone, so a choice made meanwhile stays.
  async load() {
    this.schemaLoaded ??= this.loadSchema();
    try {
      await this.schemaLoaded;
    } catch (error) {
      this.schemaLoaded = undefined;  // the next visit asks again
      throw error;
    }
    const builtin = this.schema.properties.scene.oneOf
      .map((form) => form.properties.builtin)
      .find(Boolean);
    const { scenes } = await apiJson("/v1/scenes");
    const select = $("scene-select");
    const builtins = optgroup("Built-in");
    for (const name of builtin.examples || []) option(`builtin:${name}`, name, builtins);
    const uploaded = optgroup("Uploaded");
    for (const scene of scenes) option(`id:${scene.id}`, `${scene.name || "scene"} (${scene.id.slice(0, 19)}…)`, uploaded);
    const other = optgroup("Other");
    option("path:", "a file under --scene-root…", other);
    const kept = select.value;  // read after the fetch: a choice made while it ran stays
    select.replaceChildren(builtins, ...(scenes.length ? [uploaded] : []), other);
    if ([...select.options].some((o) => o.value === kept)) select.value = kept;
    $("scene-path-label").hidden = select.value !== "path:";
  }

  job() {
    const job = {};
    const scene = $("scene-select").value;
    if (scene.startsWith("builtin:")) job.scene = { builtin: scene.slice(8) };
    else if (scene.startsWith("id:")) job.scene = { id: scene.slice(3) };
    else job.scene = { path: $("scene-path").value.trim() };
    job.preset = $("preset-select").value;
    if ($("integrator-select").value) job.integrator = $("integrator-select").value;
    const image = {};
    for (const [field, id] of [["width", "width"], ["height", "height"], ["tile_size", "tile-size"], ["spp", "spp"]]) {
      if ($(id).value.trim() !== "") image[field] = number($(id).value);
    }
    if (Object.keys(image).length) job.image = image;
    const from = $("look-from").value.trim();
    const at = $("look-at").value.trim();
    const vfov = $("vfov").value.trim();
    if (from || at || vfov) {
      job.camera = {};
      if (from) job.camera.look_from = vector(from);
      if (at) job.camera.look_at = vector(at);
      if (vfov) job.camera.vfov_deg = number(vfov);
    }
    const output = {};
    if ($("exposure").value.trim() !== "") output.exposure_ev = number($("exposure").value);
    const aovs = [...document.querySelectorAll("#aov-choices input:checked")].map((box) => box.value);
    if (aovs.length) output.aovs = aovs;
    if (Object.keys(output).length) job.output = output;
    return job;
  }

  showError(error) {
    for (const node of document.querySelectorAll("#submit-form .invalid")) node.classList.remove("invalid");
    const box = $("submit-error");
    if (!error) {
      box.hidden = true;
      return;
    }
    if (error instanceof ApiError) {
      box.textContent = `${error.title}: ${error.detail}`;
      const match = FIELD_INPUTS.find(([field]) => error.field === field || error.field.startsWith(`${field}.`));
      if (match) $(match[1]).classList.add("invalid");
    } else {
      box.textContent = `The daemon cannot be reached: ${error.message}`;
    }
    box.hidden = false;
  }

  async submit() {
    const button = $("submit-button");
    button.disabled = true;
    try {
      const response = await apiFetch("/v1/jobs", {
        method: "POST",
        headers: { "Content-Type": "application/json" },
        body: JSON.stringify(this.job()),
      });
      const status = await response.json();
      this.showError(null);
      this.onSubmitted(status);
    } catch (error) {
      this.showError(error);
    } finally {
      button.disabled = false;
    }
  }
}
