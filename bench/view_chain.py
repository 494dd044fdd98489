#!/usr/bin/env python3
"""A second view of a scene whose irradiance cache starts from the first view's, against the same
view rendered alone: time and error against a path-traced reference.

    python3 bench/view_chain.py --photond build/server/photond [--size 256] [--reference-spp 1024]

Renders, with `photond render` (preset final, 2 threads by default):
  alone    the second view with an empty cache directory (photon maps and its irradiance cache built)
  first    the first view with a cache directory C
  chained  the second view in C with irradiance_cache.start_from = the first view's render-cache
           key: photon maps from C, its cache starting from the first view's records
and a `path` reference of the second view, then prints each render's passes, total time and
relMSE against the reference. Standard library only.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

SECOND_VIEW = ["--set", "camera.look_from=[1.8,2.2,-7.0]", "--set", "camera.look_at=[3.2,2.5,2.8]",
               "--set", "camera.vfov_deg=38"]


def render(photond, work, tag, extra):
    stats = os.path.join(work, tag + ".json")
    exr = os.path.join(work, tag + ".exr")
    subprocess.run([photond, "render", "--quiet", "-o", exr, "--stats-json", stats] + extra, check=True)
    with open(stats) as f:
        return exr, json.load(f)


def relmse(photond, image, reference):
    out = subprocess.run([photond, "compare", "--json", image, reference], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)["relmse"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photond", default="build/server/photond")
    parser.add_argument("--scene", default="builtin:cornell-box-diffuse")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--reference-spp", type=int, default=1024)
    args = parser.parse_args()
    common = [args.scene, "--width", str(args.size), "--height", str(args.size), "--threads", str(args.threads)]
    work = tempfile.mkdtemp(prefix="photond_view_chain_")
    try:
        shared = ["--cache-dir", os.path.join(work, "shared")]
        alone = render(args.photond, work, "alone", common + SECOND_VIEW + ["--cache-dir", os.path.join(work, "own")])
        first = render(args.photond, work, "first", common + shared)
        start = ["--set", "irradiance_cache.start_from=" + first[1]["irradiance_cache"]["key"]]
        chained = render(args.photond, work, "chained", common + SECOND_VIEW + shared + start)
        reference, _ = render(args.photond, work, "reference",
                              common + SECOND_VIEW + ["--integrator", "path", "--spp", str(args.reference_spp),
                                                      "--seed", "7"])
        for tag, (exr, stats) in (("second view alone", alone), ("first view", first), ("second view chained", chained)):
            passes = ", ".join(f"{p['name']} {p['seconds']:.2f}" for p in stats["passes"])
            cache = stats["irradiance_cache"]
            error = "" if tag == "first view" else (
                f"; relMSE against path {args.reference_spp} spp {relmse(args.photond, exr, reference):.5f}")
            print(f"{tag}: {stats['total_seconds']:.2f} s ({passes}); {cache['records']} records"
                  f"{', ' + str(cache['records_reused']) + ' reused' if 'records_reused' in cache else ''}{error}")
        print(f"second view: {alone[1]['total_seconds'] / chained[1]['total_seconds']:.2f}x faster chained than alone")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
