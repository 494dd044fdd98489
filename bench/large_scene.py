#!/usr/bin/env python3
"""The large scene of many lights (builtin:large-city, about 2M triangles and 674 lights).

Prints, in one run on this machine:
  1. build time, memory and the photon tracing rate against bare Embree on its rays
     (build/bench/large_scene_bench);
  2. render time of the `final` preset (photon map, final gathering, irradiance cache), with the
     light tree and with power selection;
  3. the light tree against power selection at equal time: `path` renders compared with the
     stored converged reference (bench/references/large-city-320, the mean of two halves): the
     tree at --spp, power at the samples that take the tree's render time (measured from a
     render of power at --spp), relMSE of each, medians over --repeats seeds;
  4. the same pair on cornell-box (one light of two triangles) at equal samples, against its
     reference: what the tree costs where there is nothing to choose.

    python3 bench/large_scene.py [--photond build/server/photond] [--quick]
    python3 bench/large_scene.py --make-reference      # renders the reference (about 10 min on 2 cores)
    python3 bench/large_scene.py --quick --check       # ctest's short version: fails unless the tree wins

Standard library only. Figures are medians; ratios come from renders interleaved in one run.
"""
import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
EPSILON = 0.01  # relMSE's epsilon, as bench/run_benchmark.py
WIDTH, HEIGHT = 320, 180
REFERENCE_DIR = REPO / "bench/references/large-city-320"
REFERENCE_SPP = 1024  # per half
CORNELL_REFERENCE_DIR = REPO / "bench/references/cornell-box-256"


def run(command):
    result = subprocess.run([str(c) for c in command], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"failed ({result.returncode}): {' '.join(map(str, command))}\n{result.stderr}")
    return result.stdout


def render(photond, workdir, scene, integrator, spp, seed, selection, width, height, preset=None):
    """One render: its statistics (passes, total) and the EXR's path."""
    out = Path(workdir) / f"{scene}_{integrator}_{selection}_{spp}_{seed}.exr"
    stats = out.with_suffix(".json")
    command = [photond, "render", f"builtin:{scene}", "--width", width, "--height", height, "--seed", seed,
               "--quiet", "--set", f"light_sampling.selection={selection}", "--set", "output.pixel_type=float",
               "--stats-json", stats, "-o", out]
    if preset:
        command += ["--preset", preset]
    else:
        command += ["--integrator", integrator, "--spp", spp]
    run(command)
    statistics_json = json.loads(stats.read_text())
    return statistics_json, out


def passes(stats):
    return {p["name"]: p["seconds"] for p in stats["passes"]}


def relmse(photond, image, reference):
    return json.loads(run([photond, "compare", image, reference, "--epsilon", EPSILON, "--json"]))["relmse"]


def reference_mean(photond, directory, workdir):
    halves = [directory / f"path_half_{h}.exr" for h in "ab"]
    if not all(h.exists() for h in halves):
        return None, None
    mean = Path(workdir) / f"reference_{directory.name}.exr"
    run([photond, "average", "-o", mean, *halves])
    return mean, relmse(photond, halves[0], halves[1])


def make_reference(photond):
    REFERENCE_DIR.mkdir(parents=True, exist_ok=True)
    for half, seed in (("a", 7001), ("b", 7002)):
        out = REFERENCE_DIR / f"path_half_{half}.exr"
        print(f"rendering {out.relative_to(REPO)} ({REFERENCE_SPP} spp)", flush=True)
        run([photond, "render", "builtin:large-city", "--integrator", "path", "--width", WIDTH, "--height", HEIGHT,
             "--spp", REFERENCE_SPP, "--seed", seed, "--quiet", "--set", "output.pixel_type=half",
             "--set", "light_sampling.selection=tree", "-o", out])


def equal_time(photond, workdir, scene, integrator, spp, seeds, reference, width, height):
    # Each seed's three renders run back to back, so that the machine's load falls on both alike.
    """The tree at `spp` against power at the samples of equal render time; medians."""
    rows = []
    for seed in seeds:
        tree_stats, tree_image = render(photond, workdir, scene, integrator, spp, seed, "tree", width, height)
        calibration, _ = render(photond, workdir, scene, integrator, spp, seed, "power", width, height)
        t_tree, t_power_same = passes(tree_stats)["render"], passes(calibration)["render"]
        power_spp = max(1, round(spp * t_tree / t_power_same))
        power_stats, power_image = render(photond, workdir, scene, integrator, power_spp, seed, "power", width, height)
        rows.append({"tree_seconds": t_tree, "tree_relmse": relmse(photond, tree_image, reference),
                     "power_spp": power_spp, "power_seconds": passes(power_stats)["render"],
                     "power_relmse": relmse(photond, power_image, reference),
                     "power_same_spp_seconds": t_power_same})
    return {key: statistics.median(r[key] for r in rows) for key in rows[0]}, rows


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--photond", default=str(REPO / "build/server/photond"))
    parser.add_argument("--bench", default=None, help="large_scene_bench (default: beside photond's build)")
    parser.add_argument("--spp", type=int, default=16, help="the tree's samples per pixel in the equal-time test")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--photons", type=int, default=200000, help="photons per tracing-rate run")
    parser.add_argument("--quick", action="store_true", help="one repeat, 8 spp, 50k photons (CI)")
    parser.add_argument("--make-reference", action="store_true")
    parser.add_argument("--check", action="store_true",
                        help="fail unless the tree's relMSE at equal time is below power's (ctest)")
    args = parser.parse_args()
    photond = Path(args.photond)
    if args.make_reference:
        make_reference(photond)
        return
    if args.quick:
        args.repeats, args.spp, args.photons = 1, 8, 50000
    bench = Path(args.bench) if args.bench else photond.parent.parent / "bench/large_scene_bench"
    seeds = [101 + r for r in range(args.repeats)]

    print("== large-city: build, memory, photon tracing against bare Embree", flush=True)
    print(run([bench, "large-city", args.photons, 3 if args.quick else 5]), end="", flush=True)

    with tempfile.TemporaryDirectory(prefix="photond-large-scene-") as workdir:
        reference, floor = reference_mean(photond, REFERENCE_DIR, workdir)
        print(f"== large-city: the final preset at {WIDTH}x{HEIGHT}, 2 threads, medians of {args.repeats}", flush=True)
        runs = {"tree": [], "power": []}
        for seed in seeds:  # interleaved, so that the machine's load falls on both alike
            for selection in runs:
                stats, image = render(photond, workdir, "large-city", "photon-map", 0, seed, selection, WIDTH, HEIGHT,
                                      preset="final")
                stats["relmse"] = relmse(photond, image, reference) if reference else float("nan")
                runs[selection].append(stats)
        names = ["scene", "acceleration", "photon_tracing", "irradiance_cache", "render"]
        for selection, stats in runs.items():
            figures = {n: statistics.median(passes(s).get(n, 0.0) for s in stats) for n in names}
            total = statistics.median(s["total_seconds"] for s in stats)
            error = statistics.median(s["relmse"] for s in stats)
            print(f"{selection:5s}: total {total:.2f} s (" + ", ".join(f"{n} {figures[n]:.2f} s" for n in names) +
                  f"), relMSE {error:.4f} against the path reference", flush=True)

        if reference is None:
            print(f"no reference under {REFERENCE_DIR.relative_to(REPO)}: run --make-reference", file=sys.stderr)
        else:
            print(f"== large-city: light tree against power at equal time, path at {WIDTH}x{HEIGHT}, the tree at "
                  f"{args.spp} spp, medians of {args.repeats} (reference halves differ by relMSE {floor:.4f})",
                  flush=True)
            m, _ = equal_time(photond, workdir, "large-city", "path", args.spp, seeds, reference, WIDTH, HEIGHT)
            print(f"tree : {args.spp} spp in {m['tree_seconds']:.2f} s, relMSE {m['tree_relmse']:.4f}")
            print(f"power: {m['power_spp']:.0f} spp in {m['power_seconds']:.2f} s, relMSE {m['power_relmse']:.4f} "
                  f"(at {args.spp} spp: {m['power_same_spp_seconds']:.2f} s)")
            print(f"power's relMSE over the tree's at equal time: {m['power_relmse'] / m['tree_relmse']:.2f}x "
                  f"(the time power needs for the tree's error, relMSE ~ 1/time)", flush=True)
            if args.check and not m["tree_relmse"] < m["power_relmse"]:
                sys.exit("the light tree did not beat power selection at equal time")

        reference, floor = reference_mean(photond, CORNELL_REFERENCE_DIR, workdir)
        if reference is not None:
            print(f"== cornell-box (one light, two triangles): tree against power, path 256x256 at 16 spp, "
                  f"medians of {args.repeats}", flush=True)
            rows = {"tree": [], "power": []}
            for seed in seeds:  # interleaved
                for selection in rows:
                    stats, image = render(photond, workdir, "cornell-box", "path", 16, seed, selection, 256, 256)
                    rows[selection].append((passes(stats)["render"], relmse(photond, image, reference)))
            for selection, r in rows.items():
                print(f"{selection:5s}: {statistics.median(x[0] for x in r):.2f} s, relMSE "
                      f"{statistics.median(x[1] for x in r):.4f}", flush=True)


if __name__ == "__main__":
    main()
