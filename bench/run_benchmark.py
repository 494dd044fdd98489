#!/usr/bin/env python3
"""Run time against error: photon-map settings and path spp swept on each benchmark scene.

Every run is compared with the scene's converged path-traced reference (the mean of its two
stored halves, bench/README.md). Each point is repeated with other seeds and the median of each
figure is quoted. Writes, under --out (default bench/results; bench/results/quick with --quick):

    benchmark_runs.csv   every run
    benchmark.csv        one row per point: medians, Pareto frontier, speed-up over path
    benchmark.md         the table for README, speed-ups at equal error, reference check
    error_vs_time.png    relMSE against seconds, log-log, one panel per scene (gnuplot)
    error_vs_time.gp     the gnuplot script that drew it (data inline)

and prints benchmark.md. Standard library only; needs photond and gnuplot.
"""

import argparse
import csv
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
EPSILON = 0.01  # relMSE's epsilon, as in the literature

# The photon-map settings of the presets (protocol/presets.cpp), for the table's settings column.
PRESET_SETTINGS = {
    "preview": {"photons.global": 50_000, "photons.caustic": 25_000, "gather.rays": 128,
                "irradiance_cache.a": 0.35, "image.spp": 4},
    "final": {"photons.global": 200_000, "photons.caustic": 50_000, "gather.rays": 256,
              "irradiance_cache.a": 0.3, "image.spp": 16},
}


@dataclass
class SceneSpec:
    """A benchmark scene: its reference and how renders are compared with it."""
    name: str
    reference_dir: str  # relative to the repository, holds path_half_a.exr, path_half_b.exr
    width: int
    height: int
    path_spp: list
    path_spp_quick: list
    region: tuple = None  # (x0, y0, x1, y1): rendered and compared only there
    block: int = 1  # compare block x block means (the reference is not converged per pixel)
    note: str = ""
    builtin: str = None  # the built-in scene rendered (default: name)

    @property
    def scene(self):
        return self.builtin or self.name


SCENES = [
    SceneSpec("cornell-box", "bench/references/cornell-box-256", 256, 256,
              [4, 16, 64, 256], [4, 16, 64]),
    SceneSpec("cornell-box-diffuse", "bench/references/cornell-box-diffuse-256", 256, 256,
              [4, 16, 64, 256], [4, 16, 64]),
    SceneSpec("caustic-area", "tests/data/references/caustic-area", 128, 96,
              [64, 256, 1024, 4096, 16384], [64, 256, 1024], region=(48, 44, 88, 72), block=4,
              note="the point-light caustic scene with the point light replaced by a 0.5 x 0.5 "
                   "area light of equal power (path cannot converge with a point light behind "
                   "glass); rendered and compared only in the caustic's region [48,44,88,72] of "
                   "the 128 x 96 frame, over 4 x 4 pixel blocks (the reference is converged in "
                   "block means, not per pixel), so RMSE and p99 are of block means"),
    SceneSpec("spheres-room", "bench/references/spheres-room-256", 256, 256,
              [4, 16, 64, 256], [4, 16, 64],
              note="115 332 triangles (built-in, generated): the cost of scene size"),
    SceneSpec("sunlit-room", "bench/references/sunlit-room-256", 256, 256,
              [4, 16, 64, 256], [4, 16, 64],
              note="a closed room lit only by a sky image and its sun through a window (built-in): "
                   "where photon maps must earn their place"),
    SceneSpec("foggy-room", "bench/references/foggy-room-256", 256, 256,
              [16, 64, 256, 1024], [16, 64, 256], block=4,
              note="god rays (built-in): a closed room in its own fog (the scene's atmosphere, "
                   "optical depth 0.72 across it), lit only by a spot light through a window in a "
                   "partition; compared over 4 x 4 pixel blocks, as its path reference converges "
                   "in block means, not per pixel (the fog's light outside the shafts comes from "
                   "few paths: fireflies), so RMSE and p99 are of block means"),
    SceneSpec("glossy-objects", "bench/references/glossy-objects-256", 256, 256,
              [4, 16, 64, 256], [4, 16, 64],
              note="glossy metals (roughness 0.1 to 0.5), plastics and a clear-coated box under a "
                   "ceiling light (built-in): glossy interreflection, no ideal mirror or glass"),
    SceneSpec("cornell-box-512", "bench/references/cornell-box-512", 512, 512,
              [4, 16, 64], [4, 16], builtin="cornell-box",
              note="cornell-box at 512 x 512: the presets' goals at four times the pixels"),
    SceneSpec("cornell-box-diffuse-512", "bench/references/cornell-box-diffuse-512", 512, 512,
              [4, 16, 64], [4, 16], builtin="cornell-box-diffuse",
              note="cornell-box-diffuse at 512 x 512"),
]


@dataclass
class Point:
    """One setting of one method: the preset it starts from and the job fields it overrides."""
    method: str  # "photon-map" | "path"
    name: str  # short label, unique within a scene and method
    preset: str  # the job preset the render starts from
    overrides: dict = field(default_factory=dict)
    label: str = ""  # preset points are labelled in the plot

    def settings(self):
        """The settings that matter for the method, as job field -> value."""
        if self.method == "path":
            return {"image.spp": self.overrides["image.spp"]}
        merged = dict(PRESET_SETTINGS[self.preset])
        merged.update(self.overrides)
        return merged

    def describe(self):
        s = self.settings()
        spp = f"{s['image.spp']} spp"
        if self.method == "path":
            return spp
        return (f"{count(s['photons.global'])}+{count(s['photons.caustic'])} photons, "
                f"{s['gather.rays']} gather, a {s['irradiance_cache.a']:g}, {spp}")


def count(n):
    """50000 -> '50k', 1200000 -> '1.2M'."""
    if n >= 1_000_000:
        return f"{n / 1e6:g}M"
    if n >= 1000:
        return f"{n / 1e3:g}k"
    return str(n)


def photon_map_points(quick):
    """The presets, and the final preset with one setting changed at a time."""
    points = [Point("photon-map", "preview", "preview", label="preview"),
              Point("photon-map", "final", "final", label="final"),
              Point("photon-map", "final-8spp", "final", {"image.spp": 8})]
    if quick:
        return points
    for g in (50_000, 800_000):
        points.append(Point("photon-map", f"final-photons-{count(g)}", "final",
                            {"photons.global": g, "photons.caustic": g // 4}))
    for rays in (128, 512):
        points.append(Point("photon-map", f"final-gather-{rays}", "final", {"gather.rays": rays}))
    for a in (0.2, 0.45):
        points.append(Point("photon-map", f"final-a-{a:g}", "final", {"irradiance_cache.a": a}))
    for spp in (32, 64):
        points.append(Point("photon-map", f"final-{spp}spp", "final", {"image.spp": spp}))
    return points


def path_points(scene, quick):
    return [Point("path", f"path-{spp}spp", "reference", {"image.spp": spp})
            for spp in (scene.path_spp_quick if quick else scene.path_spp)]


# ----------------------------------------------------------------------------------------------
# Running photond


def run(command, capture=True):
    result = subprocess.run(command, capture_output=capture, text=True)
    if result.returncode != 0:
        sys.exit(f"failed ({result.returncode}): {' '.join(map(str, command))}\n{result.stderr}")
    return result.stdout


def compare(photond, image, reference, scene):
    """photond compare's figures (relmse, rmse, p99, bias as a fraction, ...) as a dict."""
    command = [photond, "compare", image, reference, "--epsilon", str(EPSILON), "--json"]
    if scene.region:
        command += ["--region", ",".join(map(str, scene.region))]
    if scene.block > 1:
        command += ["--block", str(scene.block)]
    return json.loads(run(command))


def render(photond, scene, point, seed, threads, workdir):
    """One render; returns its time, ray count and error figures (without the comparison)."""
    out = Path(workdir) / f"{scene.name}_{point.method}_{point.name}_{seed}.exr"
    stats_file = out.with_suffix(".json")
    command = [photond, "render", f"builtin:{scene.scene}", "--integrator", point.method,
               "--preset", point.preset, "--width", str(scene.width), "--height",
               str(scene.height), "--seed", str(seed), "--threads", str(threads), "--quiet",
               "--set", f"photons.seed={seed}", "--set", "output.pixel_type=float",
               "--stats-json", str(stats_file), "-o", str(out)]
    if scene.region:
        command += ["--set", "image.region=[%d,%d,%d,%d]" % scene.region]
    for key, value in point.overrides.items():
        command += ["--set", f"{key}={value}"]
    start = time.monotonic()
    run(command)
    wall = time.monotonic() - start
    stats = json.loads(stats_file.read_text())
    passes = {p["name"]: p["seconds"] for p in stats["passes"]}
    photons = stats.get("photons", {})
    return out, {
        "time_s": stats["total_seconds"],
        "process_wall_s": wall,
        "photon_s": passes.get("photon_tracing", 0.0) + passes.get("photon_kdtree", 0.0),
        "cache_s": passes.get("irradiance_cache", 0.0),
        "render_s": stats["render_seconds"],
        # Every ray cast: camera paths and gathers, shadow rays, and photon paths.
        "rays": stats["rays"] + stats["shadow_rays"] + photons.get("rays", 0),
        "cache_records": stats.get("irradiance_cache", {}).get("records", 0),
    }


# ----------------------------------------------------------------------------------------------
# Analysis


def pareto(rows):
    """Marks the rows no other row beats in both time and relMSE (within one scene)."""
    for r in rows:
        r["pareto"] = not any(
            o is not r and o["time_s"] <= r["time_s"] and o["relmse"] <= r["relmse"]
            and (o["time_s"] < r["time_s"] or o["relmse"] < r["relmse"]) for o in rows)


def lower_envelope(rows):
    """The rows of one method that no row of it beats, by increasing time."""
    best = []
    for r in sorted(rows, key=lambda r: (r["time_s"], r["relmse"])):
        if not best or r["relmse"] < best[-1]["relmse"]:
            best.append(r)
    return best


def path_time_at(path_rows, error):
    """Path's time to reach relMSE `error` for good: where its curve (log-log, by increasing
    time) last crosses `error`, interpolated. Beyond its ends it is extrapolated with slope -1 (an
    unbiased estimator's relMSE falls as 1 / time). Short runs can look better than their trend
    (e.g. a caustic no path has found yet), hence the last crossing and not the first. Returns
    (seconds, extrapolated)."""
    curve = sorted(path_rows, key=lambda r: r["time_s"])
    if not curve:
        return None, False
    last = curve[-1]
    if last["relmse"] > error:
        return last["time_s"] * last["relmse"] / error, True
    for b, a in zip(reversed(curve), list(reversed(curve))[1:]):  # a before b in time
        if a["relmse"] > error >= b["relmse"]:
            f = math.log(error / a["relmse"]) / math.log(b["relmse"] / a["relmse"])
            return math.exp(math.log(a["time_s"]) + f * math.log(b["time_s"] / a["time_s"])), False
    first = curve[0]
    return first["time_s"] * first["relmse"] / error, error != first["relmse"]


def frontier_gap(row, rows):
    """How far a point lies above the frontier: its relMSE over the best relMSE any point
    reaches in no more time (1 = on the frontier)."""
    best = min(r["relmse"] for r in rows if r["time_s"] <= row["time_s"])
    return row["relmse"] / best


def summarise(runs, scene, points):
    """Median of every figure per point."""
    rows = []
    for point in points:
        mine = [r for r in runs if r["scene"] == scene.name and r["method"] == point.method
                and r["point"] == point.name]
        if not mine:
            continue
        row = {"scene": scene.name, "method": point.method, "point": point.name,
               "preset": point.label, "settings": point.describe(), "repeats": len(mine)}
        for key, value in point.settings().items():
            row[key] = value
        for key in ("time_s", "process_wall_s", "photon_s", "cache_s", "render_s", "rays",
                    "relmse", "rmse", "p99", "bias", "cache_records"):
            row[key] = statistics.median(r[key] for r in mine)
        rows.append(row)
    pareto(rows)
    path_rows = [r for r in rows if r["method"] == "path"]
    for r in rows:
        r["speedup"], r["speedup_extrapolated"] = None, False
        if r["method"] != "path" and path_rows:
            t, extrapolated = path_time_at(path_rows, r["relmse"])
            if t:
                r["speedup"], r["speedup_extrapolated"] = t / r["time_s"], extrapolated
    return rows


# ----------------------------------------------------------------------------------------------
# Output

RUN_COLUMNS = ["scene", "method", "point", "repeat", "seed", "time_s", "process_wall_s",
               "photon_s", "cache_s", "render_s", "rays", "cache_records", "relmse", "rmse",
               "p99", "bias"]
POINT_COLUMNS = ["scene", "method", "point", "preset", "settings", "image.spp",
                 "photons.global", "photons.caustic", "gather.rays", "irradiance_cache.a",
                 "repeats", "time_s", "process_wall_s", "photon_s", "cache_s", "render_s",
                 "rays", "cache_records", "relmse", "rmse", "p99", "bias", "pareto", "speedup",
                 "speedup_extrapolated"]


def write_csv(path, rows, columns):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        for r in rows:
            writer.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in columns})


def speedup_text(r):
    if r.get("speedup") is None:
        return ""
    return ("~" if r["speedup_extrapolated"] else "") + f"{r['speedup']:.2g}x"


def markdown(rows_by_scene, references, args, elapsed):
    lines = ["| scene | method | settings | time (s) | rays (M) | relMSE | RMSE | p99 | bias "
             "| frontier | speed-up |",
             "|---|---|---|---:|---:|---:|---:|---:|---:|:---:|---:|"]
    for scene, rows in rows_by_scene.items():
        for r in sorted(rows, key=lambda r: (r["method"] != "path", r["time_s"])):
            settings = r["settings"] + (f" (**{r['preset']}**)" if r["preset"] else "")
            lines.append(
                f"| {scene} | {r['method']} | {settings} | {r['time_s']:.2f} "
                f"| {r['rays'] / 1e6:.1f} | {r['relmse']:.4f} | {r['rmse']:.4f} "
                f"| {r['p99']:.4f} | {100 * r['bias']:+.2f}% | {'*' if r['pareto'] else ''} "
                f"| {speedup_text(r)} |")
    sweep = "--quick sweep" if args.quick else "full sweep"
    lines += ["", f"Medians of {args.repeats} run(s) per point, {args.threads} threads, "
              f"{sweep} ({elapsed / 60:.1f} min of renders). "
              "time: the job's wall-clock seconds (scene, acceleration, photons, irradiance "
              "cache, pixels); rays: all rays cast, photon paths included; relMSE with "
              f"epsilon {EPSILON}; p99: 99th percentile of the per-pixel absolute error; bias: "
              "relative difference of the image means; frontier: on the Pareto frontier of the "
              "scene (no point is both faster and more accurate); speed-up: path's time to the "
              "same relMSE (interpolated log-log where its curve last crosses it; ~ = extrapolated "
              "beyond its longest run with relMSE proportional to 1 / time) over the point's "
              "time.", ""]
    lines.append("**Speed-up at equal error over path**, per scene:")
    lines.append("")
    for scene, rows in rows_by_scene.items():
        pm = [r for r in rows if r["method"] == "photon-map" and r["speedup"] is not None]
        if not pm:
            continue
        parts = []
        for r in pm:
            if r["preset"]:
                gap = frontier_gap(r, rows)
                where = "on the frontier" if r["pareto"] else f"{gap:.2g}x the frontier's relMSE"
                parts.append(f"`{r['preset']}` {speedup_text(r)} (relMSE {r['relmse']:.4f} in "
                             f"{r['time_s']:.2f} s, {where})")
        best = max(pm, key=lambda r: r["speedup"])
        parts.append(f"best {speedup_text(best)} ({best['settings']})")
        lines.append(f"- {scene}: " + "; ".join(parts))
    lines += ["", "**References** (path, the mean of two independent halves: its own relMSE is "
              "about a quarter of the halves' relMSE, and it adds about that much to every "
              "figure above):", "",
              "| scene | reference | relMSE between halves | reference's own (about 1/4) "
              "| smallest measured relMSE | ratio |",
              "|---|---|---:|---:|---:|---:|"]
    for scene, ref in references.items():
        rows = rows_by_scene.get(scene, [])
        if not rows:
            continue
        smallest = min(r["relmse"] for r in rows)
        own = ref["relmse"] / 4
        lines.append(f"| {scene} | `{ref['dir']}/` | {ref['relmse']:.5f} | {own:.5f} "
                     f"| {smallest:.4f} | {smallest / own:.0f}x |")
    notes = [f"- {s.name}: {s.note}." for s in SCENES if s.note and s.name in rows_by_scene]
    if notes:
        lines += ["", *notes]
    return "\n".join(lines) + "\n"


def gnuplot_script(rows_by_scene, png):
    """One panel per scene: path's curve, photon-map's points and its lower envelope, the Pareto
    frontier circled, the presets labelled."""
    blocks, panels = [], []
    for i, (scene, rows) in enumerate(rows_by_scene.items()):
        def block(name, data):
            blocks.append(f"${name}{i} << EOD")
            blocks.extend(f"{r['time_s']:.6g} {r['relmse']:.6g} {r.get('preset') or '-'}"
                          for r in data)
            blocks.append("EOD")
        path = sorted([r for r in rows if r["method"] == "path"], key=lambda r: r["time_s"])
        pm = [r for r in rows if r["method"] == "photon-map"]
        block("path", path or [{"time_s": 1, "relmse": float("nan")}])
        block("pm", pm or [{"time_s": 1, "relmse": float("nan")}])
        block("pmcurve", lower_envelope(pm) or [{"time_s": 1, "relmse": float("nan")}])
        block("front", sorted([r for r in rows if r["pareto"]], key=lambda r: r["time_s"]))
        block("presets", [r for r in pm if r["preset"]] or [{"time_s": 1, "relmse": float("nan")}])
        # Room around the data (a factor on either side), so that no point sits on a border.
        times = [r["time_s"] for r in rows]
        errors = [r["relmse"] for r in rows]
        panels.append(
            f"set title '{scene}'\n"
            f"set xrange [{min(times) / 1.5:.6g}:{max(times) * 1.5:.6g}]\n"
            f"set yrange [{min(errors) / 2:.6g}:{max(errors) * 4:.6g}]\n"
            f"plot $path{i} using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' "
            f"title 'path', \\\n"
            f"     $pm{i} using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' "
            f"title 'photon-map (sweep)', \\\n"
            f"     $pmcurve{i} using 1:2 with lines lw 2 lc rgb '#d62728' "
            f"title 'photon-map (best)', \\\n"
            f"     $front{i} using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' "
            f"title 'Pareto frontier', \\\n"
            f"     $presets{i} using 1:2:3 with labels offset char 1.2,0.8 left "
            f"font ',10' notitle")
    n = max(1, len(panels))
    cols = 2 if n > 1 else 1
    nrows = (n + cols - 1) // cols
    header = [f"set terminal pngcairo size {640 * cols},{480 * nrows} font ',11'",
              f"set output '{png}'",
              "set logscale xy", "set format x '%g'", "set format y '%g'",
              "set xtics (0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, "
              "1000, 2000, 5000)",
              "set xlabel 'time (s)'", "set ylabel 'relMSE'", "set grid xtics ytics mxtics mytics",
              "set key top right box opaque font ',9'", "set datafile missing 'nan'",
              f"set multiplot layout {nrows},{cols} title "
              "'error against time (medians; circled: Pareto frontier)'"]
    return "\n".join(blocks + header + panels + ["unset multiplot", ""])


# ----------------------------------------------------------------------------------------------


def read_runs(path, plan):
    """The runs of an earlier sweep, for --replot (only those of the scenes in `plan`)."""
    if not path.exists():
        sys.exit(f"{path}: no runs to replot")
    runs = []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if row["scene"] not in plan:
                continue
            for key in RUN_COLUMNS:
                if key in ("repeat", "seed", "rays", "cache_records"):
                    row[key] = int(row[key])
                elif key not in ("scene", "method", "point"):
                    row[key] = float(row[key])
            runs.append(row)
    return runs


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--photond", default=str(REPO / "build" / "server" / "photond"),
                        help="the photond binary (default: build/server/photond)")
    parser.add_argument("--scenes", default=",".join(s.name for s in SCENES),
                        help="comma-separated scenes (default: all with a reference)")
    parser.add_argument("--quick", action="store_true",
                        help="a small sweep: the presets, 8 spp, three path points, 2 repeats")
    parser.add_argument("--repeats", type=int, default=None,
                        help="runs per point, other seeds each (default 3, --quick 2)")
    parser.add_argument("--threads", type=int, default=os.cpu_count(),
                        help="render threads (default: every core)")
    parser.add_argument("--out", default=None,
                        help="output directory (default bench/results; with --quick bench/results/quick, "
                             "so that a quick run leaves the full sweep's files alone)")
    parser.add_argument("--keep-renders", action="store_true",
                        help="keep the rendered EXRs under OUT/renders")
    parser.add_argument("--replot", action="store_true",
                        help="render nothing: redo the tables and the plot from "
                             "OUT/benchmark_runs.csv (same --quick and --scenes)")
    args = parser.parse_args()
    if args.repeats is None:
        args.repeats = 2 if args.quick else 3
    photond = str(Path(args.photond).resolve())
    if not os.access(photond, os.X_OK):
        sys.exit(f"{photond}: no photond binary (build it, or pass --photond)")
    by_name = {s.name: s for s in SCENES}
    wanted = [n.strip() for n in args.scenes.split(",") if n.strip()]
    for name in wanted:
        if name not in by_name:
            sys.exit(f"unknown scene '{name}'; benchmark scenes: {', '.join(by_name)}")
    out = Path(args.out) if args.out else REPO / "bench" / "results" / ("quick" if args.quick else "")
    out.mkdir(parents=True, exist_ok=True)
    workdir = Path(tempfile.mkdtemp(prefix="photond-bench-"))
    if args.keep_renders:
        workdir = out / "renders"
        workdir.mkdir(exist_ok=True)

    scenes, references = [], {}
    for name in wanted:
        scene = by_name[name]
        halves = [REPO / scene.reference_dir / f"path_half_{h}.exr" for h in "ab"]
        missing = [str(h.relative_to(REPO)) for h in halves if not h.exists()]
        if missing:
            print(f"skipping {name}: reference missing ({', '.join(missing)}); see "
                  "bench/README.md", file=sys.stderr)
            continue
        mean = workdir / f"reference_{name}.exr"
        run([photond, "average", "-o", str(mean), *map(str, halves)])
        check = compare(photond, str(halves[0]), str(halves[1]), scene)
        references[name] = {"dir": scene.reference_dir, "file": str(mean),
                            "relmse": check["relmse"]}
        print(f"{name}: reference halves differ by relMSE {check['relmse']:.5f}",
              file=sys.stderr)
        scenes.append(scene)
    if not scenes:
        sys.exit("no scene to benchmark")

    runs = []
    plan = {s.name: photon_map_points(args.quick) + path_points(s, args.quick) for s in scenes}
    total = sum(len(p) for p in plan.values()) * args.repeats
    done = 0
    if args.replot:
        runs = read_runs(out / "benchmark_runs.csv", plan)
        args.repeats = max((r["repeat"] for r in runs), default=0) + 1
    # Repeats outermost, so that a change in the machine's load spreads over every point.
    for repeat in range(0 if args.replot else args.repeats):
        seed = 101 + repeat
        for scene in scenes:
            for point in plan[scene.name]:
                image, figures = render(photond, scene, point, seed, args.threads, workdir)
                error = compare(photond, str(image), references[scene.name]["file"], scene)
                if not args.keep_renders:
                    image.unlink()
                    image.with_suffix(".json").unlink()
                figures.update({k: error[k] for k in ("relmse", "rmse", "p99", "bias")})
                figures.update({"scene": scene.name, "method": point.method,
                                "point": point.name, "repeat": repeat, "seed": seed})
                runs.append(figures)
                done += 1
                print(f"[{done}/{total}] {scene.name} {point.method} {point.describe()}: "
                      f"{figures['time_s']:.2f} s, relMSE {figures['relmse']:.4f}",
                      file=sys.stderr)
    # The renders' own time (the same after --replot); the comparisons add a little.
    elapsed = sum(r["process_wall_s"] for r in runs)

    rows_by_scene = {s.name: summarise(runs, s, plan[s.name]) for s in scenes}
    write_csv(out / "benchmark_runs.csv", runs, RUN_COLUMNS)
    write_csv(out / "benchmark.csv", [r for rows in rows_by_scene.values() for r in rows],
              POINT_COLUMNS)
    table = markdown(rows_by_scene, references, args, elapsed)
    (out / "benchmark.md").write_text(table)
    script = out / "error_vs_time.gp"
    script.write_text(gnuplot_script(rows_by_scene, str((out / "error_vs_time.png").resolve())))
    if shutil.which("gnuplot"):
        run(["gnuplot", str(script)])
    else:
        print("gnuplot not found (apt-get install gnuplot-nox): no plot drawn", file=sys.stderr)
    if not args.keep_renders:
        shutil.rmtree(workdir, ignore_errors=True)
    print(table)
    print(f"wrote {out}/benchmark.csv, benchmark_runs.csv, benchmark.md, error_vs_time.png",
          file=sys.stderr)


if __name__ == "__main__":
    main()
