#!/usr/bin/env python3
"""What the daemon keeps per finished job: its heap in use and RSS at quiet points.

    python3 bench/job_memory.py --photond build/server/photond [--jobs 200] [--rounds 3]

Starts `photond serve` with a fresh cache directory, runs a warm-up of 100 small jobs, then
--rounds rounds of --jobs jobs one after another (32x32, 8-pixel tiles; each job's image, events
and tiles fetched), and after each reads the daemon's RSS and the allocator's bytes in use
(glibc's malloc_stats(), called through gdb, which must be installed). Prints one line per point
and the heap's growth per job. Standard library only.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.request


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photond", default="build/server/photond")
    parser.add_argument("--jobs", type=int, default=200)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    if not shutil.which("gdb"):
        sys.exit("gdb is needed to read the allocator's statistics (apt-get install gdb)")
    work = tempfile.mkdtemp(prefix="photond_job_memory_")
    err_path = os.path.join(work, "daemon.err")
    err = open(err_path, "w")
    daemon = subprocess.Popen([args.photond, "serve", "--listen", "127.0.0.1:0", "--cache-dir",
                               os.path.join(work, "cache"), "--max-queued", "100000", "--threads", "2"],
                              stdout=subprocess.PIPE, stderr=err, text=True)
    try:
        url = daemon.stdout.readline().split()[-1]
        seed = [0]

        def get(path):
            with urllib.request.urlopen(url + path) as r:
                return r.read()

        def run(count):
            for _ in range(count):
                seed[0] += 1
                job = {"scene": {"builtin": "cornell-box"}, "integrator": "direct", "seed": seed[0],
                       "image": {"width": 32, "height": 32, "spp": 1, "tile_size": 8}}
                request = urllib.request.Request(url + "/v1/jobs", data=json.dumps(job).encode(), method="POST")
                with urllib.request.urlopen(request) as r:
                    job_id = json.loads(r.read())["id"]
                for suffix in ("image.exr?wait=true", "events", "tiles"):
                    get(f"/v1/jobs/{job_id}/{suffix}")

        def measure():
            subprocess.run(["gdb", "-p", str(daemon.pid), "-batch", "-ex", "call (void)malloc_stats()"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
            time.sleep(0.5)
            with open(err_path) as f:
                in_use = [line for line in f if line.startswith("in use bytes")][-1].split()[-1]
            with open(f"/proc/{daemon.pid}/status") as f:
                rss = next(line for line in f if line.startswith("VmRSS")).split()[1]
            return int(in_use) / 1024.0, int(rss)

        run(100)
        points = [(seed[0],) + measure()]
        print(f"after {points[-1][0]} jobs: heap in use {points[-1][1]:.0f} kB, RSS {points[-1][2]} kB", flush=True)
        for _ in range(args.rounds):
            run(args.jobs)
            points.append((seed[0],) + measure())
            print(f"after {points[-1][0]} jobs: heap in use {points[-1][1]:.0f} kB, RSS {points[-1][2]} kB",
                  flush=True)
        growth = (points[-1][1] - points[0][1]) / (points[-1][0] - points[0][0])
        print(f"heap growth: {growth:.2f} kB per finished job")
    finally:
        daemon.terminate()
        daemon.wait(timeout=30)
        err.close()
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
