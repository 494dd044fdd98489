#!/usr/bin/env python3
"""photond against another renderer: every Khronos sample model of tests/data/gltf-samples
rendered by Blender's Cycles (bench/cycles_render.py, Debian's `blender`) and by photond with the
same camera, the same uniform sky of radiance 1 and the same pixel filter, 256 x 256; photond's
`final` (photon-map) and a `path` render, each compared with Cycles: the image mean's bias, the
relMSE, and the 32 x 32 blocks' relMSE (which shows where the images differ, not only how much).

    python3 bench/cycles_compare.py --photond build/server/photond [--cycles-spp 1024]
        [--path-spp 256] [--models A,B] [--out DIR] [--keep DIR]

Writes DIR/cycles_compare.md and .csv (default bench/results) and prints the table. Needs
`blender` (Debian 12's 3.4) and python3-numpy, which its glTF importer imports; `make
cycles-compare` installs both. The two renderers take the glTF material each its own way (Cycles
through the importer's Principled BSDF: a Disney diffuse, its own clearcoat and sheen; photond
as the glTF specification writes it), so a few percent apart is agreement; a model far apart, or
one block far apart, is a place to look.
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SAMPLES = os.path.join(ROOT, "tests", "data", "gltf-samples")
CYCLES_SCRIPT = os.path.join(ROOT, "bench", "cycles_render.py")
SIZE = 256


def run(command, env=None):
    start = time.monotonic()
    result = subprocess.run(command, capture_output=True, text=True, env=env)
    if result.returncode != 0:
        sys.exit(f"{' '.join(command)} failed:\n{result.stdout[-4000:]}{result.stderr[-4000:]}")
    return time.monotonic() - start


def has_own_lights(scene):
    """Whether the glTF file lights itself: KHR_lights_punctual lights or emissive materials."""
    with open(scene) as f:
        doc = json.load(f)
    lights = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    emissive = any(any(c > 0 for c in m.get("emissiveFactor", [0, 0, 0])) for m in doc.get("materials", []))
    return bool(lights) or emissive


def run_blender_script(blender, script, arguments):
    """Runs `script` in Blender without its interface; returns the seconds it took."""
    # Blender's Python takes its prefix from the first python3.x on the PATH: the system's, next
    # to blender, and not a python3 of another installation (pyenv, a virtualenv) without numpy.
    env = dict(os.environ, PATH=os.path.dirname(os.path.realpath(blender)) + os.pathsep + os.environ.get("PATH", ""))
    return run([blender, "-b", "--factory-startup", "-noaudio", "--python-exit-code", "1", "-P", script, "--"] +
               arguments, env=env)


def cycles(blender, scene, exr, camera_json, spp, seed, sky=1.0):
    return run_blender_script(blender, CYCLES_SCRIPT, [scene, exr, camera_json, "--size", str(SIZE), "--spp", str(spp),
                                                       "--seed", str(seed), "--sky", str(sky)])


def photond_render(photond, scene, exr, job, extra):
    return run([photond, "render", scene, "--job", job, "--width", str(SIZE), "--height", str(SIZE), "--quiet",
                "--set", "output.pixel_type=float", "-o", exr] + extra)


def compare(photond, exr, reference, block=None):
    command = [photond, "compare", "--json", exr, reference]
    if block:
        command += ["--block", str(block)]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"compare failed: {result.stdout}{result.stderr}")
    return json.loads(result.stdout)


def errors(photond, exr, reference):
    """The image's bias (%), relMSE and relMSE over 32 x 32 blocks against `reference`, and the
    reference's mean."""
    pixels = compare(photond, exr, reference)
    blocks = compare(photond, exr, reference, block=32)
    return {"bias_pct": round(100.0 * pixels["bias"], 2), "relmse": float(f"{pixels['relmse']:.3g}"),
            "block_relmse": float(f"{blocks['relmse']:.3g}"), "reference_mean": float(f"{pixels['reference_mean']:.4g}")}


def write_results(out, name, rows, lines):
    """rows into OUT/NAME.csv, the table's `lines` into OUT/NAME.md, and the table printed."""
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, name + ".csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)
    with open(os.path.join(out, name + ".md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photond", default=os.path.join(ROOT, "build", "server", "photond"))
    parser.add_argument("--blender", default=shutil.which("blender") or "blender")
    parser.add_argument("--cycles-spp", type=int, default=1024)
    parser.add_argument("--path-spp", type=int, default=256)
    parser.add_argument("--models", default="", help="comma-separated model names (default: all)")
    parser.add_argument("--out", default=os.path.join(ROOT, "bench", "results"))
    parser.add_argument("--keep", default="", help="keep the EXRs and cameras in this directory")
    args = parser.parse_args()

    names = sorted(d for d in os.listdir(SAMPLES) if os.path.isdir(os.path.join(SAMPLES, d)))
    if args.models:
        names = [n for n in names if n in args.models.split(",")]
    work = args.keep or tempfile.mkdtemp(prefix="cycles_compare_")
    os.makedirs(work, exist_ok=True)
    rows = []
    for name in names:
        scene = os.path.join(SAMPLES, name, "glTF", name + ".gltf")
        camera = os.path.join(work, name + ".camera.json")
        with open(camera, "w") as f:
            json.dump({"auto": True}, f)  # cycles_render.py frames the bounds and writes the camera
        reference = os.path.join(work, name + ".cycles.exr")
        cycles_s = cycles(args.blender, scene, reference, camera, args.cycles_spp, 1)
        with open(camera) as f:
            view = json.load(f)
        # The sky is given, not left to the default: a model with lights of its own renders
        # without the default sky, and Cycles' world is there in every render. Such a model is
        # compared once more by its own lights alone (KHR_lights_punctual's units, emission).
        variants = [("", {"color": [1, 1, 1]}, 1.0)]
        if has_own_lights(scene):
            variants.append((" (own lights only)", None, 0.0))
        for suffix, environment, sky in variants:
            tag = name + (".dark" if suffix else "")
            if suffix:
                reference = os.path.join(work, tag + ".cycles.exr")
                cycles_s = cycles(args.blender, scene, reference, camera, args.cycles_spp, 1, sky)
            job_path = os.path.join(work, tag + ".job.json")
            with open(job_path, "w") as f:
                json.dump({"camera": view, "environment": environment}, f)
            final_exr = os.path.join(work, tag + ".final.exr")
            final_s = photond_render(args.photond, scene, final_exr, job_path, ["--preset", "final"])
            path_exr = os.path.join(work, tag + ".path.exr")
            path_s = photond_render(args.photond, scene, path_exr, job_path,
                                    ["--integrator", "path", "--spp", str(args.path_spp)])
            row = {"model": name + suffix, "cycles_spp": args.cycles_spp, "cycles_s": round(cycles_s, 1),
                   "final_s": round(final_s, 2), "path_s": round(path_s, 1)}
            for kind, exr in (("final", final_exr), ("path", path_exr)):
                e = errors(args.photond, exr, reference)
                row[f"{kind}_bias_pct"] = e["bias_pct"]
                row[f"{kind}_relmse"] = e["relmse"]
                row[f"{kind}_block_relmse"] = e["block_relmse"]
            row["cycles_mean"] = e["reference_mean"]
            rows.append(row)
            print(json.dumps(row), flush=True)

    lines = [f"photond against Cycles (Blender {blender_version(args.blender)}, {args.cycles_spp} spp), "
             f"{SIZE}x{SIZE}, uniform sky of radiance 1 (own lights only: none), measured "
             f"{time.strftime('%Y-%m-%d %H:%M')}",
             "",
             "| model | Cycles mean | final: bias | relMSE | 32² blocks' relMSE | path "
             f"{args.path_spp} spp: bias | relMSE | 32² blocks' relMSE |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['model']} | {r['cycles_mean']} | {r['final_bias_pct']:+.2f} % | {r['final_relmse']} | "
                     f"{r['final_block_relmse']} | {r['path_bias_pct']:+.2f} % | {r['path_relmse']} | "
                     f"{r['path_block_relmse']} |")
    write_results(args.out, "cycles_compare", rows, lines)


def blender_version(blender):
    result = subprocess.run([blender, "--version"], capture_output=True, text=True)
    first = result.stdout.splitlines()[0] if result.stdout else "?"
    return first.replace("Blender ", "").strip()


if __name__ == "__main__":
    main()
