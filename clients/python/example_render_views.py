#!/usr/bin/env python3
"""Renders several camera views of one scene through a running photond daemon.

Photon maps do not depend on the camera, so the daemon traces them for the first view only:
every later view of the same scene with the same photon settings finds them in its photon-map
cache ("cache: hit", photon pass 0 s). Standard library only:

    photond serve --listen 127.0.0.1:8080 --cache-dir /tmp/photond &
    python3 clients/python/example_render_views.py --server http://127.0.0.1:8080 --out-dir views
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from photond_client import PhotondClient, PhotondError  # noqa: E402

# Jensen's Cornell box (builtin:cornell-box) is 5.5 units wide, deep and high, centred on x = 0
# and z = 0 with its floor at y = 0 and its open side facing +z.
VIEWS = [
    ("front", [0.0, 2.75, 10.75]),
    ("left", [-2.0, 3.5, 10.0]),
    ("right", [2.0, 2.0, 10.0]),
    ("high", [0.0, 5.0, 9.5]),
]
LOOK_AT = [0.0, 2.75, 0.0]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--server", default=os.environ.get("PHOTOND_URL", "http://127.0.0.1:8080"),
                        help="the daemon's URL (default: $PHOTOND_URL or http://127.0.0.1:8080)")
    parser.add_argument("--token-file", help="a file holding the daemon's bearer token")
    parser.add_argument("--scene", default="cornell-box", help="a builtin scene name")
    parser.add_argument("--views", type=int, default=len(VIEWS), choices=range(1, len(VIEWS) + 1),
                        metavar=f"1..{len(VIEWS)}", help="how many views to render")
    parser.add_argument("--width", type=int, default=160)
    parser.add_argument("--height", type=int, default=120)
    parser.add_argument("--spp", type=int, default=1)
    parser.add_argument("--preset", default="preview")
    parser.add_argument("--out-dir", default="views", help="where the EXRs go")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds per view")
    args = parser.parse_args()

    token = None
    if args.token_file:
        with open(args.token_file, encoding="utf-8") as token_file:
            token = token_file.read().strip()
    client = PhotondClient(args.server, token=token)
    os.makedirs(args.out_dir, exist_ok=True)

    print(f"{'view':<6} {'job':<36} {'photon cache':<12} {'photon pass':>11} {'render':>8}  file")
    for name, look_from in VIEWS[:args.views]:
        job = {
            "scene": {"builtin": args.scene},
            "preset": args.preset,
            "camera": {"look_from": look_from, "look_at": LOOK_AT, "up": [0, 1, 0],
                       "vfov_deg": 40},
            "image": {"width": args.width, "height": args.height, "spp": args.spp},
        }
        try:
            job_id = client.submit(job)
            status = client.wait(job_id, timeout=args.timeout)
            if status.get("state") != "done":
                print(f"photond: view {name}: job {job_id} {status.get('state')}: "
                      f"{status.get('error', '')}", file=sys.stderr)
                return 1
            path = client.fetch_image(job_id, os.path.join(args.out_dir, f"{name}.exr"))
        except PhotondError as error:
            print(f"photond: view {name}: {error}", file=sys.stderr)
            return 1
        except TimeoutError as error:
            print(f"photond: view {name}: {error}", file=sys.stderr)
            return 1
        timings = status.get("timings") or {}
        if isinstance(timings, list):
            timings = {entry.get("name"): entry.get("seconds", 0.0) for entry in timings}
        cache = status.get("photons", {}).get("cache", "-")
        photon_pass = timings.get("photon_tracing", 0.0) + timings.get("photon_kdtree", 0.0)
        render = timings.get("render", 0.0)
        print(f"{name:<6} {job_id:<36} {cache:<12} {photon_pass:>9.3f} s {render:>6.3f} s  {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
