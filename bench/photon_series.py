#!/usr/bin/env python3
"""The photon pass from 200k to 10M global photons, and every pass of each render summed.

Renders builtin:cornell-box-diffuse (256x256, `final` otherwise, no caustic map) with 200k, 1M,
3M and 10M global photons through `photond render`, one process each, and prints for each count:
the photon pass in its parts (tracing, kd-tree, precomputed irradiance), its cost per stored
photon, the photon map's bytes, the process's peak RSS against the map (whole, and less the peak
of the same render with a thousand photons: the maps' own share), and the sum of all passes
against the total (the statistics' `passes` must add up to `total_seconds`).

    python3 bench/photon_series.py --photond build/server/photond [--counts 200000,1000000]

Standard library only. Needs about 1.5 GB of memory for 10M photons.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

PHOTON_PASSES = ("photon_tracing", "photon_kdtree", "photon_irradiance")


def render(photond, count, threads, directory):
    """Runs one render; returns its statistics and the process's peak RSS in bytes."""
    stats_file = os.path.join(directory, f"stats-{count}.json")
    command = [photond, "render", "builtin:cornell-box-diffuse", "--width", "256", "--height", "256",
               "--set", "photons.caustic=0", "--set", f"photons.global={count}", "--quiet",
               "--stats-json", stats_file, "-o", os.path.join(directory, "image.exr")]
    if threads:
        command += ["--threads", str(threads)]
    process = subprocess.Popen(command)
    _, status, usage = os.wait4(process.pid, 0)
    process.returncode = os.waitstatus_to_exitcode(status)
    if process.returncode != 0:
        sys.exit(f"photon_series: {' '.join(command)} exited with {process.returncode}")
    with open(stats_file) as f:
        return json.load(f), usage.ru_maxrss * 1024  # ru_maxrss is in kB on Linux


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photond", default="build/server/photond")
    parser.add_argument("--counts", default="200000,1000000,3000000,10000000")
    parser.add_argument("--threads", type=int, default=0, help="render threads (default: every core)")
    args = parser.parse_args()
    counts = [int(c) for c in args.counts.split(",")]

    with tempfile.TemporaryDirectory() as directory:
        # The same render with a thousand photons: the process without photon maps (program,
        # scene, acceleration structure, image, cache), to tell the maps' share of the peak.
        _, baseline_rss = render(args.photond, 1000, args.threads, directory)
        print(f"Process without photon maps (1,000 photons): peak RSS {baseline_rss / 1e6:.0f} MB.")
        print()
        print("global photons | tracing s | kd-tree s | irradiance s | photon pass s | us per photon | "
              "map MB | peak RSS MB | RSS / map | (RSS - without) / map | passes s | total s | passes / total")
        print("---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:")
        for count in counts:
            stats, peak_rss = render(args.photond, count, args.threads, directory)
            seconds = {p["name"]: p["seconds"] for p in stats["passes"]}
            photon_pass = sum(seconds.get(name, 0.0) for name in PHOTON_PASSES)
            stored = stats["photons"]["stored_global"]
            map_bytes = stats["photons"]["map_bytes"]
            passes = sum(p["seconds"] for p in stats["passes"])
            total = stats["total_seconds"]
            print(f"{count:,} | {seconds.get('photon_tracing', 0):.2f} | {seconds.get('photon_kdtree', 0):.2f} | "
                  f"{seconds.get('photon_irradiance', 0):.2f} | {photon_pass:.2f} | {1e6 * photon_pass / stored:.2f} | "
                  f"{map_bytes / 1e6:.0f} | {peak_rss / 1e6:.0f} | {peak_rss / map_bytes:.2f} | "
                  f"{(peak_rss - baseline_rss) / map_bytes:.2f} | {passes:.2f} | "
                  f"{total:.2f} | {passes / total:.3f}")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
