#!/usr/bin/env python3
"""Radiance caching against BSDF-sampled glossy gathering at equal error (issue 19's goal).

builtin:glossy-objects at 256 x 256, preset `final`, rendered with the radiance cache off (each
glossy point traces BSDF-sampled rays that read the photon maps) and on (glossy points the cache
holds integrate its records' incident radiance: no rays) at several spp, the runs of the two
alternating. Errors are measured against the scene's converged path reference
(bench/references/glossy-objects-256) on two sets of pixels:

  cached   a square inside the aluminium sphere (roughness 0.5), the one lobe of the scene
           sharp enough to need glossy light and broad enough for the cache's bands
  frame    the whole image (the sharper lobes keep their rays either way)

Time is the job's total and the part that differs between the two (render + radiance cache:
the photon maps and the irradiance cache are the same job's in both). The speed-up at equal
error reads the rays' time at the cache's error off the rays' log-log curve.

    python3 bench/radiance_cache_tradeoff.py --photond build/server/photond [--seeds 2]

Standard library only.
"""

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
REFERENCE = REPO / "bench/references/glossy-objects-256"
# Inside the aluminium sphere's disc (centre (214, 148), radius 25 px), clear of the green
# sphere in front of it.
CACHED_REGION = (200, 130, 228, 158)
EPSILON = 0.01


def run(command):
    return subprocess.run(command, check=True, capture_output=True, text=True).stdout


def error(photond, image, reference, region=None):
    command = [photond, "compare", str(image), str(reference), "--epsilon", str(EPSILON), "--json"]
    if region:
        command += ["--region", ",".join(map(str, region))]
    return json.loads(run(command))


def render(photond, workdir, cache, spp, seed, threads):
    name = f"{'cache' if cache else 'rays'}_{spp}_{seed}"
    out = Path(workdir) / f"{name}.exr"
    stats_file = Path(workdir) / f"{name}.json"
    run([photond, "render", "builtin:glossy-objects", "--preset", "final", "--width", "256",
         "--height", "256", "--spp", str(spp), "--seed", str(seed), "--threads", str(threads),
         "--quiet", "--set", f"photons.seed={seed}", "--set", "output.pixel_type=float",
         "--set", f"radiance_cache.enabled={'true' if cache else 'false'}",
         "--stats-json", str(stats_file), "-o", str(out)])
    stats = json.loads(stats_file.read_text())
    passes = {p["name"]: p["seconds"] for p in stats["passes"]}
    return out, {"total_s": stats["total_seconds"],
                 "differing_s": passes.get("render", 0.0) + passes.get("radiance_cache", 0.0)}


def time_at(rows, relmse, key):
    """The time the rays' curve (log-log, piecewise linear) needs for relmse; None outside it."""
    rows = sorted(rows, key=lambda r: r[key])
    for a, b in zip(rows, rows[1:]):
        lo, hi = sorted((a["relmse"], b["relmse"]))
        if lo <= relmse <= hi and a["relmse"] != b["relmse"]:
            f = (math.log(relmse) - math.log(a["relmse"])) / (math.log(b["relmse"]) - math.log(a["relmse"]))
            return math.exp(math.log(a[key]) + f * (math.log(b[key]) - math.log(a[key])))
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photond", default=str(REPO / "build/server/photond"))
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--rays-spp", default="16,32,64,128,256")
    parser.add_argument("--cache-spp", default="4,8,16,32")
    args = parser.parse_args()
    rays_spp = [int(s) for s in args.rays_spp.split(",")]
    cache_spp = [int(s) for s in args.cache_spp.split(",")]

    with tempfile.TemporaryDirectory() as workdir:
        reference = Path(workdir) / "reference.exr"
        run([args.photond, "average", "-o", str(reference), str(REFERENCE / "path_half_a.exr"),
             str(REFERENCE / "path_half_b.exr")])
        runs = {}
        order = []
        for i in range(max(len(rays_spp), len(cache_spp))):
            if i < len(rays_spp):
                order.append((False, rays_spp[i]))
            if i < len(cache_spp):
                order.append((True, cache_spp[i]))
        for seed in range(1, args.seeds + 1):
            for cache, spp in order:
                image, times = render(args.photond, workdir, cache, spp, seed, args.threads)
                times["cached_relmse"] = error(args.photond, image, reference, CACHED_REGION)["relmse"]
                times["frame_relmse"] = error(args.photond, image, reference)["relmse"]
                if not all(math.isfinite(times[k]) for k in ("cached_relmse", "frame_relmse")):
                    sys.exit(f"non-finite error against the reference: {image}")
                runs.setdefault((cache, spp), []).append(times)
                print(f"  seed {seed} {'cache' if cache else 'rays '} {spp:4d} spp: "
                      f"{times['total_s']:.2f} s total, {times['differing_s']:.2f} s render + radiance cache, "
                      f"relMSE cached {times['cached_relmse']:.5f}, frame {times['frame_relmse']:.5f}",
                      file=sys.stderr, flush=True)

    medians = {k: {f: statistics.median(r[f] for r in v) for f in v[0]} for k, v in runs.items()}
    print(f"builtin:glossy-objects 256x256 final, {args.threads} threads, medians of {args.seeds} seeds")
    print()
    print("| method | spp | total (s) | render + radiance cache (s) | relMSE cached sphere | relMSE frame |")
    print("|---|---:|---:|---:|---:|---:|")
    for (cache, spp), m in sorted(medians.items()):
        print(f"| {'radiance cache' if cache else 'glossy rays'} | {spp} | {m['total_s']:.2f} | "
              f"{m['differing_s']:.2f} | {m['cached_relmse']:.5f} | {m['frame_relmse']:.5f} |")
    print()
    for part in ("cached", "frame"):
        rays = [{"relmse": m[f"{part}_relmse"], "total_s": m["total_s"], "differing_s": m["differing_s"]}
                for (cache, _), m in medians.items() if not cache]
        for (cache, spp), m in sorted(medians.items()):
            if not cache:
                continue
            figures = []
            for key in ("total_s", "differing_s"):
                t = time_at(rays, m[f"{part}_relmse"], key)
                figures.append(f"{t / m[key]:.2f}x" if t else "outside the rays' range")
            print(f"{part}: radiance cache at {spp} spp (relMSE {m[f'{part}_relmse']:.5f}): speed-up at equal "
                  f"error {figures[0]} in total time, {figures[1]} in render + radiance cache")


if __name__ == "__main__":
    main()
