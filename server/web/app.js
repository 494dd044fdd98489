// The web page of `photond serve` (README.md, "The web page"): the queue (#/) with the
// submission form and the job list, and a job's page (#/jobs/{id}). This file routes between
// them and asks for the token when the daemon wants one (api.js).

import { onTokenNeeded, setToken } from "./api.js";
import { JobList } from "./job_list.js";
import { JobView } from "./job_view.js";
import { SubmitForm } from "./submit_form.js";

const $ = (id) => document.getElementById(id);

// What the browser test reads (tests/server/web_page_browser.mjs): the open job's TileCanvas,
// whether its image is complete, and how often the token was asked for.
window.photondPage = { canvas: null, imageComplete: false, tokenQuestions: 0 };

onTokenNeeded((reason) => {
  const dialog = $("token-dialog");
  window.photondPage.tokenQuestions += 1;
  $("token-reason").textContent = reason || "This daemon needs a bearer token.";
  $("token-input").value = "";
  return new Promise((resolve) => {
    dialog.addEventListener(
      "close",
      () => {
        setToken($("token-input").value.trim());
        resolve();
      },
      { once: true });
    if (!dialog.open) dialog.showModal();
  });
});
// Escape must not leave the page without a token and without a question.
$("token-dialog").addEventListener("cancel", (event) => event.preventDefault());

const jobList = new JobList();
const form = new SubmitForm((status) => {
  location.hash = `#/jobs/${encodeURIComponent(status.id)}`;
});
let jobView = null;

function route() {
  const match = /^#\/jobs\/([^/]+)$/.exec(location.hash);
  if (jobView) jobView.close();
  jobView = null;
  window.photondPage.canvas = null;
  window.photondPage.imageComplete = false;
  $("queue-view").hidden = Boolean(match);
  $("job-view").hidden = !match;
  if (match) {
    jobList.close();
    jobView = new JobView(decodeURIComponent(match[1]));
    document.title = `photond · job ${jobView.jobId}`;
    jobView.open();
  } else {
    document.title = "photond";
    jobList.open();
    form.load().catch((error) => form.showError(error));
  }
}

window.addEventListener("hashchange", route);
route();
