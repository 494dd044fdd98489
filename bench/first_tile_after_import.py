#!/usr/bin/env python3
"""How soon a render node that imported a view's photon maps and irradiance cache shows a tile.

    python3 bench/first_tile_after_import.py --photond build/server/photond [--size 512]
                                             [--scenes cornell-box,cornell-box-diffuse,...]

For each built-in scene: a first daemon renders the view (preset final, 1 sample per pixel: the
photon maps and the irradiance cache do not depend on the sample count) and exports both; a second
daemon with an empty cache directory imports them over HTTP (PUT /v1/photon-maps/KEY,
PUT /v1/render-caches/KEY), then the job (preset final, --size x --size) is submitted to it and its
event stream read until the first tile. Prints, per scene, the time from the submission to the
first tile event, the job's passes and whether both artifacts were cache hits. Standard library
only.
"""
import argparse
import http.client
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time


def start(photond, cache_dir):
    daemon = subprocess.Popen([photond, "serve", "--listen", "127.0.0.1:0", "--cache-dir", cache_dir],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    line = daemon.stdout.readline()
    if "listening on http://" not in line:
        sys.exit(f"the daemon did not start: {line!r}")
    return daemon, int(line.strip().rsplit(":", 1)[1])


def request(port, method, path, body=None):
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=600)
    connection.request(method, path, body=body)
    response = connection.getresponse()
    data = response.read()
    connection.close()
    return response.status, data


def render(port, job):
    status, body = request(port, "POST", "/v1/jobs", json.dumps(job))
    job_id = json.loads(body)["id"]
    request(port, "GET", f"/v1/jobs/{job_id}/image.exr?wait=true")
    return json.loads(request(port, "GET", f"/v1/jobs/{job_id}")[1])


def first_tile_seconds(port, job):
    """Submits the job and reads its event stream until the first tile; returns (seconds, id)."""
    started = time.monotonic()
    status, body = request(port, "POST", "/v1/jobs", json.dumps(job))
    job_id = json.loads(body)["id"]
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=600)
    connection.request("GET", f"/v1/jobs/{job_id}/events")
    response = connection.getresponse()
    while True:
        line = response.readline()
        if not line:
            sys.exit("the event stream ended without a tile")
        if line.strip() == b"event: tile":
            seconds = time.monotonic() - started
            break
    connection.close()
    return seconds, job_id


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photond", default="build/server/photond")
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--scenes", default="cornell-box,cornell-box-diffuse,caustic-area,spheres-room,sunlit-room")
    args = parser.parse_args()
    work = tempfile.mkdtemp(prefix="photond_first_tile_")
    try:
        for scene in args.scenes.split(","):
            job = {"scene": {"builtin": scene}, "preset": "final", "image": {"width": args.size, "height": args.size}}
            source, source_port = start(args.photond, os.path.join(work, scene, "source"))
            built = render(source_port, dict(job, image=dict(job["image"], spp=1)))
            photon_key = built["photons"]["key"]
            cache_key = built["statistics"]["irradiance_cache"]["key"]
            maps = request(source_port, "GET", f"/v1/photon-maps/{photon_key}")[1]
            cache = request(source_port, "GET", f"/v1/render-caches/{cache_key}")[1]
            source.terminate()
            source.wait()
            node, port = start(args.photond, os.path.join(work, scene, "node"))
            imported_at = time.monotonic()
            request(port, "PUT", f"/v1/photon-maps/{photon_key}", maps)
            request(port, "PUT", f"/v1/render-caches/{cache_key}", cache)
            import_seconds = time.monotonic() - imported_at
            seconds, job_id = first_tile_seconds(port, job)
            request(port, "GET", f"/v1/jobs/{job_id}/image.exr?wait=true")
            status = json.loads(request(port, "GET", f"/v1/jobs/{job_id}")[1])
            node.terminate()
            node.wait()
            passes = ", ".join(f"{name} {value * 1000:.1f} ms" for name, value in status["timings"].items())
            print(f"{scene} {args.size}x{args.size}: import {import_seconds * 1000:.0f} ms "
                  f"({len(maps) / 1e6:.1f} + {len(cache) / 1e6:.2f} MB); first tile {seconds * 1000:.0f} ms after "
                  f"the submission; photons {status['photons']['cache']}, irradiance cache "
                  f"{status['statistics']['irradiance_cache']['cache']}; {passes}", flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
