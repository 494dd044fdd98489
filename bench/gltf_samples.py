#!/usr/bin/env python3
"""Real glTF content: every Khronos sample model of tests/data/gltf-samples rendered at 256 x 256
with preset `final` (time per pass, warnings) and its image mean against a `path` render of the
same job (the mean of a path render converges long before its pixels do).

    python3 bench/gltf_samples.py --photond build/server/photond [--path-spp 256] [--seeds 1] [--out DIR]

Writes DIR/gltf_samples.md and .csv (default bench/results) and prints the table. Standard
library only.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SAMPLES = os.path.join(ROOT, "tests", "data", "gltf-samples")


def render(photond, scene, out_dir, tag, extra):
    exr = os.path.join(out_dir, tag + ".exr")
    stats = os.path.join(out_dir, tag + ".json")
    command = [photond, "render", scene, "--width", "256", "--height", "256", "--quiet",
               "--set", "output.pixel_type=float", "-o", exr, "--stats-json", stats] + extra
    start = time.monotonic()
    result = subprocess.run(command, capture_output=True, text=True)
    wall = time.monotonic() - start
    if result.returncode != 0:
        sys.exit(f"{' '.join(command)} failed:\n{result.stdout}{result.stderr}")
    with open(stats) as f:
        return exr, json.load(f), wall


def mean_of(photond, exr, reference):
    result = subprocess.run([photond, "compare", "--json", exr, reference], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"compare failed: {result.stdout}{result.stderr}")
    return json.loads(result.stdout)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photond", default=os.path.join(ROOT, "build", "server", "photond"))
    parser.add_argument("--path-spp", type=int, default=256, help="samples per pixel of the path render")
    parser.add_argument("--out", default=os.path.join(ROOT, "bench", "results"))
    parser.add_argument("--models", default="", help="comma-separated model names (default: all)")
    parser.add_argument("--seeds", type=int, default=1,
                        help="render `final` with this many seeds (render and photons) and report the "
                             "mean of their means and their spread: a mostly black frame lit by a few "
                             "bright paths has a mean that moves by percents from seed to seed")
    args = parser.parse_args()

    names = sorted(d for d in os.listdir(SAMPLES) if os.path.isdir(os.path.join(SAMPLES, d)))
    if args.models:
        names = [n for n in names if n in args.models.split(",")]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            scene = os.path.join(SAMPLES, name, "glTF", name + ".gltf")
            ref, ref_stats, ref_wall = render(args.photond, scene, tmp, name + "_path",
                                              ["--integrator", "path", "--spp", str(args.path_spp)])
            seed_differences = []
            for seed in range(1, args.seeds + 1):
                seeded = ["--set", f"seed={seed}", "--set", f"photons.seed={seed}"]
                seed_exr, seed_stats, _ = render(args.photond, scene, tmp, f"{name}_final_{seed}", seeded)
                seed_c = mean_of(args.photond, seed_exr, ref)
                if seed == 1:
                    stats, c = seed_stats, seed_c  # times, passes and warnings: seed 1's
                if seed_c["reference_mean"] > 0:
                    seed_differences.append(100.0 * (seed_c["mean"] / seed_c["reference_mean"] - 1.0))
            passes = {p["name"]: p["seconds"] for p in stats["passes"]}
            environment = stats["plan"][0]
            rows.append({
                "model": name,
                "final_s": round(stats["total_seconds"], 2),
                "photon_tracing_s": round(passes.get("photon_tracing", 0.0), 2),
                "irradiance_cache_s": round(passes.get("irradiance_cache", 0.0), 2),
                "render_s": round(passes.get("render", 0.0), 2),
                "mean": round(c["mean"], 5),
                "path_mean": round(c["reference_mean"], 5),
                "mean_difference_pct": round(100.0 * (c["mean"] / c["reference_mean"] - 1.0), 2)
                if c["reference_mean"] > 0 else 0.0,
                "seeds_mean_difference_pct": round(sum(seed_differences) / len(seed_differences), 2)
                if seed_differences else 0.0,
                "seeds_min_pct": round(min(seed_differences), 2) if seed_differences else 0.0,
                "seeds_max_pct": round(max(seed_differences), 2) if seed_differences else 0.0,
                "path_s": round(ref_stats["total_seconds"], 2),
                "lit_by": "default sky" if environment["enabled"] else "own lights",
                "warnings": len(stats.get("warnings", [])),
            })
            print(f"{name}: final {rows[-1]['final_s']} s, mean {rows[-1]['mean_difference_pct']:+.2f} % "
                  f"against path {args.path_spp} spp", flush=True)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "gltf_samples.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)
    seeds = args.seeds > 1
    lines = [f"Khronos sample models, 256 x 256, preset final against path at {args.path_spp} spp "
             f"(`python3 bench/gltf_samples.py`), {os.cpu_count()} cores"
             + (f", final with seeds 1 to {args.seeds}" if seeds else "") + ".", "",
             "| model | lit by | final s | photons s | cache s | render s | mean vs path | "
             + (f"mean of {args.seeds} seeds (min, max) | " if seeds else "") + "path s | warnings |",
             "|---|---|---|---|---|---|---|" + ("---|" if seeds else "") + "---|---|"]
    for r in rows:
        spread = (f"{r['seeds_mean_difference_pct']:+.2f} % ({r['seeds_min_pct']:+.2f}, "
                  f"{r['seeds_max_pct']:+.2f}) | ") if seeds else ""
        lines.append(f"| {r['model']} | {r['lit_by']} | {r['final_s']} | {r['photon_tracing_s']} | "
                     f"{r['irradiance_cache_s']} | {r['render_s']} | {r['mean_difference_pct']:+.2f} % | "
                     f"{spread}{r['path_s']} | {r['warnings']} |")
    table = "\n".join(lines) + "\n"
    with open(os.path.join(args.out, "gltf_samples.md"), "w") as f:
        f.write(table)
    print(table)


if __name__ == "__main__":
    main()
