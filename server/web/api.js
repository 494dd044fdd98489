// The daemon's HTTP API as the page calls it (README.md, "The web page").
//
// The bearer token: a daemon started with --token-file answers 401 to every API request without
// it, and so to this page. The page then asks for the token once, keeps it in sessionStorage
// (this tab only, gone when the tab closes) and sends it as "Authorization: Bearer" with every
// request, the event stream and downloads included: they are all read with fetch(), never
// through a URL that carries the token (URLs end up in logs, history and Referer headers). A
// token that is refused is forgotten and asked for again.

const TOKEN_KEY = "photond.token";

/// A refused request: `status`, and the RFC 9457 problem's `title`, `detail` and `field`.
export class ApiError extends Error {
  constructor(status, problem) {
    super(problem.detail || problem.title || `HTTP ${status}`);
    this.status = status;
    this.title = problem.title || `HTTP ${status}`;
    this.detail = problem.detail || "";
    this.field = problem.field || "";
  }
}

export function token() {
  return sessionStorage.getItem(TOKEN_KEY) || "";
}

export function setToken(value) {
  sessionStorage.setItem(TOKEN_KEY, value);
}

function forgetToken() {
  sessionStorage.removeItem(TOKEN_KEY);
}

// Asks the user for a token (installed by app.js); one question at a time for all requests.
let askForToken = null;
let pendingQuestion = null;

export function onTokenNeeded(ask) {
  askForToken = ask;
}

function tokenQuestion(reason) {
  if (!pendingQuestion) {
    pendingQuestion = askForToken(reason).finally(() => {
      pendingQuestion = null;
    });
  }
  return pendingQuestion;
}

async function readProblem(response) {
  const type = response.headers.get("Content-Type") || "";
  try {
    if (type.includes("json")) return await response.json();
    const text = await response.text();
    return { title: `HTTP ${response.status}`, detail: text.trim() };
  } catch {
    return { title: `HTTP ${response.status}` };
  }
}

/// fetch() with the token; a 401 asks for the token and tries again; other refusals throw
/// ApiError. `options` as fetch's (signal, method, body, headers).
export async function apiFetch(path, options = {}) {
  for (;;) {
    const headers = new Headers(options.headers || {});
    const sent = token();
    if (sent) headers.set("Authorization", `Bearer ${sent}`);
    const response = await fetch(path, { ...options, headers, cache: "no-store", credentials: "omit" });
    if (response.status === 401 && askForToken) {
      const problem = await readProblem(response);
      if (sent && token() === sent) forgetToken();
      // Another request may have been answered meanwhile: ask only if the token is still missing.
      if (!token()) await tokenQuestion(sent ? `The token was refused: ${problem.detail}` : problem.detail);
      continue;
    }
    if (!response.ok) throw new ApiError(response.status, await readProblem(response));
    return response;
  }
}

export async function apiJson(path, options = {}) {
  return (await apiFetch(path, options)).json();
}

/// Downloads `path` as `filename`: fetched with the token, handed to the browser as a blob.
export async function download(path, filename) {
  const blob = await (await apiFetch(path)).blob();
  const url = URL.createObjectURL(blob);
  const link = document.createElement("a");
  link.href = url;
  link.download = filename;
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 60000);
}
