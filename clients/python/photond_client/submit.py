"""photond-submit: submits a job to a photond daemon, follows it and saves its image.

    photond-submit job.json -o out.exr [--preview out.png] [--set image.spp=16 ...]
    photond-submit - -o out.exr < job.json

Options are named as photonctl's (`photonctl submit JOB.json --wait -o out.exr`): the server is
--server URL, else $PHOTOND_URL, else http://127.0.0.1:8080; a bearer token is read from
--token-file FILE, else from the file named by $PHOTOND_TOKEN_FILE. The job's id goes to stdout,
its progress and any error to stderr. Exit status: 0 when the job is done and its files are
written, 1 for any failure (an error answer of the daemon, an unreachable daemon, a failed or
cancelled job, a timeout, a file that cannot be read or written), 2 for a usage error, 130 when
interrupted (the job keeps running on the daemon).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from typing import Any, Dict, List, Optional, Sequence, TextIO

from . import PhotondClient, PhotondError, ServerEvent, __version__

PROGRAM = "photond-submit"
DEFAULT_SERVER_URL = "http://127.0.0.1:8080"

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130

_PROGRESS_BAR_WIDTH = 30


class _Failure(Exception):
    """A failure the command reports on one line and exits 1 for."""


def apply_override(document: Dict[str, Any], assignment: str) -> None:
    """--set FIELD=VALUE as photonctl applies it (protocol::apply_override): FIELD is a dotted
    path whose missing objects are created; VALUE is JSON when it parses as JSON, else a
    string. Raises ValueError naming the assignment."""
    quoted = f'override "{assignment}"'
    path, equals, value_text = assignment.partition("=")
    if not equals:
        raise ValueError(f"{quoted}: expected FIELD=VALUE, e.g. image.spp=16")
    path, value_text = path.strip(), value_text.strip()
    keys = path.split(".")
    if any(not key for key in keys):
        raise ValueError(f'{quoted}: empty field name in "{path}"')
    node = document
    for depth, key in enumerate(keys[:-1]):
        child = node.get(key)
        if child is None:
            child = node[key] = {}
        if not isinstance(child, dict):
            raise ValueError(f'{quoted}: "{".".join(keys[:depth + 1])}" is not an object')
        node = child
    try:
        value: Any = json.loads(value_text, parse_constant=_refuse_constant)
    except ValueError:
        value = value_text
    node[keys[-1]] = value


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not JSON")


def read_token(token_file: str) -> str:
    """The bearer token in `token_file`, surrounding white space removed."""
    try:
        with open(token_file, encoding="utf-8") as source:
            token = source.read().strip()
    except (OSError, UnicodeDecodeError) as error:
        raise _Failure(f"token file {token_file}: {_reason(error)}") from None
    if not token:
        raise _Failure(f"token file {token_file} is empty")
    return token


def read_job(path: str, overrides: Sequence[str], stdin: TextIO) -> Dict[str, Any]:
    """The job document in `path` ("-": stdin) with the --set overrides applied."""
    name = "stdin" if path == "-" else path
    try:
        if path == "-":
            text = stdin.read()
        else:
            with open(path, encoding="utf-8") as source:
                text = source.read()
    except (OSError, UnicodeDecodeError) as error:
        raise _Failure(f"{name}: cannot read: {_reason(error)}") from None
    try:
        document = json.loads(text, parse_constant=_refuse_constant)
    except json.JSONDecodeError as error:
        raise _Failure(f"{name}: malformed JSON at line {error.lineno}, column {error.colno}: "
                       f"{error.msg}") from None
    except ValueError as error:
        raise _Failure(f"{name}: malformed JSON: {error}") from None
    if not isinstance(document, dict):
        raise _Failure(f"{name}: a job is a JSON object, not {type(document).__name__}")
    for assignment in overrides:
        try:
            apply_override(document, assignment)
        except ValueError as error:
            raise _Failure(f"--set {assignment}: {error}") from None
    return document


def _reason(error: BaseException) -> str:
    if isinstance(error, OSError) and error.strerror:
        return error.strerror
    return str(error)


def _check_writable(path: str, option: str) -> None:
    """Fails before anything is submitted when `path` cannot be written."""
    directory = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise _Failure(f"{option} {path}: is a directory")
    if not os.path.isdir(directory):
        raise _Failure(f"{option} {path}: the directory {directory} does not exist")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise _Failure(f"{option} {path}: the directory {directory} is not writable")


def describe_job_error(error: Any) -> str:
    """A failed job's `error` member as one line (a string, or a problem-like object)."""
    if isinstance(error, str):
        return error
    if not isinstance(error, dict):
        return json.dumps(error)
    parts = [str(error[name]) for name in ("title", "detail") if error.get(name)]
    text = ": ".join(parts) or str(error.get("message") or "") or json.dumps(error)
    if error.get("field"):
        text += f" (field: {error['field']})"
    return text


class Progress:
    """The job's progress on stderr: a bar redrawn in place on a terminal, else a line each
    time the state or the pass changes (as photonctl shows it)."""

    def __init__(self, job_id: str, stream: TextIO, quiet: bool) -> None:
        self.job_id = job_id
        self.stream = stream
        self.quiet = quiet
        self.terminal = stream.isatty()
        self.state = ""
        self.label = ""
        self.fraction = 0.0
        self.tiles_done = 0
        self.tiles_total = 0
        self.drawn = False

    def on_event(self, event: ServerEvent) -> None:
        data = event.data if isinstance(event.data, dict) else {}
        if event.type in ("progress", "tile"):
            self._read_progress(data)
            if event.type == "progress":
                self.state = "running"
                self._show(_state_label("running", data))
            elif self.terminal:
                self._show(self.label)
        elif event.type == "state":
            state = data.get("state") if data else event.data
            if isinstance(state, str):
                self.state = state
                self._show(state)

    def show_status(self, status: Dict[str, Any]) -> None:
        progress = status.get("progress")
        if isinstance(progress, dict):
            self._read_progress(progress)
        state = status.get("state")
        if isinstance(state, str):
            self.state = state
            self._show(_state_label(state, status))

    def finish(self) -> None:
        if self.drawn:
            self.stream.write("\n")
            self.stream.flush()
        self.drawn = False

    def note(self, text: str) -> None:
        if not self.quiet:
            self.finish()
            self.stream.write(text + "\n")
            self.stream.flush()

    def _read_progress(self, data: Dict[str, Any]) -> None:
        done, total = data.get("tiles_done"), data.get("tiles_total")
        if isinstance(done, int) and isinstance(total, int):
            self.tiles_done, self.tiles_total = done, total
        fraction = data.get("fraction")
        if isinstance(fraction, (int, float)) and math.isfinite(fraction):
            self.fraction = float(fraction)
        elif self.tiles_total > 0:
            self.fraction = self.tiles_done / self.tiles_total

    def _show(self, label: str) -> None:
        if self.quiet or not label:
            return
        if self.terminal:
            self.label = label
            self.stream.write(f"\r{self._bar()}  {label}\033[K")
            self.drawn = True
        elif label != self.label:
            self.label = label
            self.stream.write(f"job {self.job_id}: {label}\n")
        self.stream.flush()

    def _bar(self) -> str:
        fraction = min(max(self.fraction, 0.0), 1.0)
        filled = min(max(int(math.floor(fraction * _PROGRESS_BAR_WIDTH)), 0), _PROGRESS_BAR_WIDTH)
        bar = "[" + "#" * filled + "-" * (_PROGRESS_BAR_WIDTH - filled) + "] "
        bar += f"{int(math.floor(fraction * 100)):3d}%"
        if self.tiles_total > 0:
            bar += f"  {self.tiles_done}/{self.tiles_total} tiles"
        return bar


def _state_label(state: str, document: Dict[str, Any]) -> str:
    """"running: photon_tracing" while a pass is known, else the bare state."""
    current_pass = document.get("pass")
    if state == "running" and isinstance(current_pass, str) and current_pass:
        return f"{state}: {current_pass}"
    return state


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROGRAM,
        description="Submit a render job to a photond daemon, follow its progress and save its "
                    "OpenEXR image (and optionally its PNG preview). The job id goes to stdout, "
                    "progress and errors to stderr.",
        epilog="The server is --server URL, else $PHOTOND_URL, else "
               f"{DEFAULT_SERVER_URL}. A bearer token is read from --token-file FILE, else from "
               "the file named by $PHOTOND_TOKEN_FILE. Exit status: 0 done and written, "
               "1 failure, 2 usage error, 130 interrupted (the job keeps running).")
    parser.add_argument("job", metavar="JOB.json", help="the job document (- for stdin)")
    parser.add_argument("-o", "--output", required=True, metavar="OUT.exr",
                        help="where the job's OpenEXR image goes (written to OUT.exr.part "
                             "first, then renamed)")
    parser.add_argument("--preview", metavar="OUT.png",
                        help="also save the job's tone-mapped PNG preview there")
    parser.add_argument("--server", metavar="URL",
                        help=f"the daemon (default: $PHOTOND_URL or {DEFAULT_SERVER_URL})")
    parser.add_argument("--token-file", metavar="FILE",
                        help="a file holding the daemon's bearer token (default: "
                             "$PHOTOND_TOKEN_FILE)")
    parser.add_argument("--set", action="append", default=[], dest="overrides",
                        metavar="FIELD=VALUE",
                        help="override a field of the job, e.g. --set image.spp=16 (VALUE is "
                             "JSON, else a string); repeatable")
    parser.add_argument("--idempotency-key", metavar="KEY",
                        help="submitting again with the same key follows the same job")
    parser.add_argument("--timeout", type=float, metavar="SECONDS",
                        help="give up (exit 1) when the job has not ended by then; the job "
                             "keeps running on the daemon")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress on stderr (errors only)")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    return parser


def run(argv: Optional[List[str]] = None, stdin: Optional[TextIO] = None,
        stdout: Optional[TextIO] = None, stderr: Optional[TextIO] = None) -> int:
    """The command with `argv` (default: sys.argv[1:]); returns the exit status."""
    stdin = stdin or sys.stdin
    stdout = stdout or sys.stdout
    stderr = stderr or sys.stderr
    parser = _parser()
    options = parser.parse_args(argv)
    if options.timeout is not None and not options.timeout > 0:
        parser.error("--timeout must be a positive number of seconds")
    server = options.server or os.environ.get("PHOTOND_URL") or DEFAULT_SERVER_URL
    token_file = options.token_file or os.environ.get("PHOTOND_TOKEN_FILE") or ""

    job_id = ""
    try:
        token = read_token(token_file) if token_file else None
        job = read_job(options.job, options.overrides, stdin)
        _check_writable(options.output, "-o")
        if options.preview:
            _check_writable(options.preview, "--preview")
        client = PhotondClient(server, token=token)
        job_id = client.submit(job, idempotency_key=options.idempotency_key)
        stdout.write(job_id + "\n")
        stdout.flush()

        progress = Progress(job_id, stderr, options.quiet)
        try:
            status = client.wait(job_id, timeout=options.timeout, on_event=progress.on_event)
        except BaseException:
            progress.finish()
            raise
        progress.show_status(status)
        progress.finish()
        state = status.get("state")
        if state != "done":
            message = f"job {job_id} {state or 'ended'}"
            if status.get("error"):
                message += f": {describe_job_error(status['error'])}"
            raise _Failure(message)
        client.fetch_image(job_id, options.output, wait=False)
        written = [options.output]
        if options.preview:
            client.fetch_preview(job_id, options.preview)
            written.append(options.preview)
        progress.note(f"job {job_id}: wrote {' and '.join(written)}")
        return EXIT_OK
    except (_Failure, PhotondError) as error:
        stderr.write(f"{PROGRAM}: {error}\n")
        return EXIT_FAILURE
    except TimeoutError as error:
        stderr.write(f"{PROGRAM}: {error}; it keeps running on the daemon "
                     f"(photonctl cancel {job_id})\n")
        return EXIT_FAILURE
    except KeyboardInterrupt:
        if job_id:
            stderr.write(f"\n{PROGRAM}: interrupted; job {job_id} keeps running on the daemon "
                         f"(photonctl cancel {job_id})\n")
        else:
            stderr.write(f"\n{PROGRAM}: interrupted\n")
        return EXIT_INTERRUPTED


def main() -> None:
    """The console entry point."""
    sys.exit(run())


if __name__ == "__main__":
    main()
