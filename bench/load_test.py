#!/usr/bin/env python3
"""Load on a real daemon: many concurrent clients on loopback for a bounded time, then checks.

    python3 bench/load_test.py --photond build/server/photond [--clients 200] [--seconds 60]
                               [--latency-goal-ms 50] [--json FILE]

Starts `photond serve` on a free port with a fresh cache directory and runs, at once:
  submitters      POST small jobs (429 answers are waited out as Retry-After says), then fetch
                  each accepted job's image with ?wait=true
  event watchers  GET /v1/jobs/{id}/events of recent jobs, read to the end
  tile streamers  GET /v1/jobs/{id}/tiles of recent jobs, read to the end
  slow readers    open an event stream and read a few bytes a second
  slowloris       send a request head a byte at a time
and, in a separate process so that this one's threads do not delay it, a prober that times
GET /healthz on a new connection every 20 ms. After the load: every accepted job must finish
`done` with its image retrievable, no answer may be a 5xx, the daemon must still run; the
daemon's RSS is read before, at the end of the load and after it settled; --rounds N repeats the
load and its checks on the same daemon. Prints the figures;
exits 1 when a check fails (the /healthz p99 only with --latency-goal-ms). Standard library only.
"""
import argparse
import http.client
import json
import os
import random
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time

EXR_MAGIC = b"\x76\x2f\x31\x01"


def small_job(seed):
    return {"scene": {"builtin": "cornell-box"}, "integrator": "direct", "seed": seed,
            "image": {"width": 32, "height": 32, "spp": 1, "tile_size": 8}}


class Tally:
    def __init__(self):
        self.lock = threading.Lock()
        self.counts = {}
        self.errors = []
        self.accepted = []
        self.five_xx = 0

    def add(self, key, n=1):
        with self.lock:
            self.counts[key] = self.counts.get(key, 0) + n

    def status(self, role, status):
        self.add(f"{role} {status}")
        if status >= 500:
            with self.lock:
                self.five_xx += 1
            self.error(f"{role}: HTTP {status}")

    def error(self, text):
        with self.lock:
            if len(self.errors) < 50:
                self.errors.append(text)
            self.counts["errors"] = self.counts.get("errors", 0) + 1

    def recent_job(self):
        with self.lock:
            return random.choice(self.accepted[-50:]) if self.accepted else None


def request(port, method, path, body=None, timeout=60):
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    try:
        headers = {"Content-Type": "application/json"} if body is not None else {}
        connection.request(method, path, body=body, headers=headers)
        response = connection.getresponse()
        return response.status, dict(response.getheaders()), response.read()
    finally:
        connection.close()


def submitter(port, tally, stop, seeds):
    role = "submit"
    while not stop.is_set():
        seed = next(seeds)
        try:
            status, headers, body = request(port, "POST", "/v1/jobs", json.dumps(small_job(seed)))
        except OSError as e:
            tally.error(f"{role}: {e}")
            continue
        tally.status(role, status)
        if status == 429:
            stop.wait(min(float(headers.get("Retry-After", "1")), 1.0) * random.random())
            continue
        if status != 202:
            tally.error(f"{role}: HTTP {status}: {body[:200]!r}")
            continue
        job_id = json.loads(body)["id"]
        with tally.lock:
            tally.accepted.append(job_id)
        try:
            status, _, image = request(port, "GET", f"/v1/jobs/{job_id}/image.exr?wait=true", timeout=120)
        except OSError as e:
            tally.error(f"image: {e}")
            continue
        tally.status("image", status)
        if status == 200 and not image.startswith(EXR_MAGIC):
            tally.error(f"image of {job_id}: not an EXR")


def streamer(port, tally, stop, kind):
    while not stop.is_set():
        job_id = tally.recent_job()
        if job_id is None:
            stop.wait(0.05)
            continue
        connection = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        try:
            connection.request("GET", f"/v1/jobs/{job_id}/{kind}")
            response = connection.getresponse()
            tally.status(kind, response.status)
            received = 0
            while not stop.is_set():
                chunk = response.read1(65536) if hasattr(response, "read1") else response.read(65536)
                if not chunk:
                    break
                received += len(chunk)
            tally.add(f"{kind} bytes", received)
        except OSError as e:
            tally.error(f"{kind}: {e}")
        finally:
            connection.close()


def slow_reader(port, tally, stop):
    while not stop.is_set():
        job_id = tally.recent_job()
        if job_id is None:
            stop.wait(0.05)
            continue
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=60)
            s.sendall(f"GET /v1/jobs/{job_id}/events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode())
            s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            for _ in range(10):  # a few bytes a second, then hang up
                if stop.wait(0.5):
                    break
                if not s.recv(16):
                    break
            s.close()
            tally.add("slow reader rounds")
        except OSError as e:
            tally.error(f"slow reader: {e}")


def slowloris(port, tally, stop):
    head = b"GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + b"a" * 64
    while not stop.is_set():
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=60)
            for byte in head:
                if stop.wait(1.0):
                    break
                s.send(bytes([byte]))
            s.close()
            tally.add("slowloris rounds")
        except OSError:
            tally.add("slowloris dropped by the daemon")  # it may close a trickling connection


def probe(port, seconds, out_path):
    latencies, failures = [], 0
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        start = time.monotonic()
        try:
            status, _, _ = request(port, "GET", "/healthz", timeout=10)
            if status != 200:
                failures += 1
        except OSError:
            failures += 1
        latencies.append((time.monotonic() - start) * 1000.0)
        time.sleep(0.02)
    with open(out_path, "w") as f:
        json.dump({"latencies_ms": latencies, "failures": failures}, f)


def resident_kb(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def percentile(values, p):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(p / 100.0 * (len(ordered) - 1))))]


def load_round(args, port, daemon, work):
    """One round of load on the running daemon, then its checks; returns (figures, failures)."""
    tally, stop = Tally(), threading.Event()
    seeds_lock, counter = threading.Lock(), [0]

    def seeds():
        while True:
            with seeds_lock:
                counter[0] += 1
                yield counter[0]

    seed_source = seeds()
    n = args.clients
    roles = ([("submit", lambda: submitter(port, tally, stop, seed_source))] * int(n * 0.3) +
             [("events", lambda: streamer(port, tally, stop, "events"))] * int(n * 0.25) +
             [("tiles", lambda: streamer(port, tally, stop, "tiles"))] * int(n * 0.2) +
             [("slow", lambda: slow_reader(port, tally, stop))] * int(n * 0.15))
    roles += [("slowloris", lambda: slowloris(port, tally, stop))] * (n - len(roles))
    probe_out = os.path.join(work, "probe.json")
    prober = subprocess.Popen([sys.executable, __file__, "--probe", str(port), str(args.seconds), probe_out])
    threads = [threading.Thread(target=target, daemon=True) for _, target in roles]
    started = time.monotonic()
    for t in threads:
        t.start()
    time.sleep(args.seconds)
    rss_load = resident_kb(daemon.pid)
    stop.set()
    prober.wait()
    for t in threads:
        t.join(timeout=130)
    load_seconds = time.monotonic() - started

    # Every accepted job ends done, with its image.
    deadline = time.monotonic() + 300
    not_done = []
    for job_id in tally.accepted:
        while True:
            status, _, body = request(port, "GET", f"/v1/jobs/{job_id}")
            state = json.loads(body).get("state") if status == 200 else f"HTTP {status}"
            if state not in ("queued", "running") or time.monotonic() > deadline:
                break
            time.sleep(0.05)
        if state != "done":
            not_done.append(f"{job_id}: {state}")
            continue
        status, _, image = request(port, "GET", f"/v1/jobs/{job_id}/image.exr")
        if status != 200 or not image.startswith(EXR_MAGIC):
            not_done.append(f"{job_id}: image HTTP {status}")
    time.sleep(5)
    rss_after = resident_kb(daemon.pid)
    with open(probe_out) as f:
        probed = json.load(f)
    latencies = probed["latencies_ms"]
    five_xx = tally.five_xx

    figures = {
        "clients": n,
        "roles": {r: sum(1 for x, _ in roles if x == r) for r, _ in roles},
        "load_seconds": round(load_seconds, 1),
        "jobs_accepted": len(tally.accepted),
        "jobs_not_done": len(not_done),
        "answers": dict(sorted(tally.counts.items())),
        "answers_5xx": five_xx,
        "healthz_probes": len(latencies),
        "healthz_failures": probed["failures"],
        "healthz_ms": {"p50": round(statistics.median(latencies), 2),
                       "p99": round(percentile(latencies, 99), 2),
                       "max": round(max(latencies), 2)},
        "rss_kb": {"end_of_load": rss_load, "settled": rss_after},
    }
    failures = []
    if five_xx:
        failures.append(f"{five_xx} answers were 5xx")
    failures += [f"error: {e}" for e in tally.errors[:10]]
    if not_done:
        failures.append(f"{len(not_done)} accepted job(s) not done: {not_done[:5]}")
    if probed["failures"]:
        failures.append(f"{probed['failures']} /healthz probes failed")
    if not tally.accepted:
        failures.append("no job was accepted")
    if args.latency_goal_ms > 0 and figures["healthz_ms"]["p99"] > args.latency_goal_ms:
        failures.append(f"/healthz p99 {figures['healthz_ms']['p99']} ms > {args.latency_goal_ms} ms")
    return figures, failures


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photond", default="build/server/photond")
    parser.add_argument("--clients", type=int, default=200)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--threads", type=int, default=2, help="render threads of the daemon")
    parser.add_argument("--latency-goal-ms", type=float, default=0.0,
                        help="fail when the /healthz p99 exceeds this (0: report only)")
    parser.add_argument("--rounds", type=int, default=1,
                        help="rounds of load on the same daemon (its RSS settled after each shows "
                             "whether what stays grows)")
    parser.add_argument("--json", help="write the figures to this file")
    parser.add_argument("--probe", nargs=3, metavar=("PORT", "SECONDS", "OUT"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.probe:
        probe(int(args.probe[0]), float(args.probe[1]), args.probe[2])
        return 0

    work = tempfile.mkdtemp(prefix="photond_load_")
    log = open(os.path.join(work, "daemon.log"), "w")
    daemon = subprocess.Popen([args.photond, "serve", "--listen", "127.0.0.1:0", "--cache-dir",
                               os.path.join(work, "cache"), "--threads", str(args.threads)],
                              stdout=subprocess.PIPE, stderr=log, text=True)
    failures = []
    try:
        line = daemon.stdout.readline()
        if not line.startswith("listening on http://127.0.0.1:"):
            sys.exit(f"the daemon did not start: {line!r}")
        port = int(line.strip().rsplit(":", 1)[1])
        # Warm-up: a few jobs, so that the RSS before the load includes what one job leaves.
        for seed in range(3):
            status, _, body = request(port, "POST", "/v1/jobs", json.dumps(small_job(10**6 + seed)))
            request(port, "GET", f"/v1/jobs/{json.loads(body)['id']}/image.exr?wait=true")
        rss_before = resident_kb(daemon.pid)

        rounds = []
        for _ in range(args.rounds):
            figures, round_failures = load_round(args, port, daemon, work)
            rounds.append(figures)
            failures += round_failures
        figures = dict(rounds[0]) if len(rounds) == 1 else {"rounds": rounds}
        figures["rss_kb_before"] = rss_before
        figures["daemon_running"] = daemon.poll() is None
        print(json.dumps(figures, indent=2))
        if args.json:
            with open(args.json, "w") as f:
                json.dump(figures, f, indent=2)
        if daemon.poll() is not None:
            failures.append("the daemon died")
    finally:
        if daemon.poll() is None:
            daemon.terminate()
            try:
                daemon.wait(timeout=30)
            except subprocess.TimeoutExpired:
                daemon.kill()
        log.close()
        if failures:
            with open(os.path.join(work, "daemon.log")) as f:
                tail = f.read()[-3000:]
            print("daemon log (tail):\n" + tail, file=sys.stderr)
        shutil.rmtree(work, ignore_errors=True)
    for f in failures:
        print("FAIL: " + f, file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
