#!/usr/bin/env python3
"""photond on glTF written by another tool: scenes built in Blender (bench/blender_scene.py),
exported by Blender's own glTF exporter (photometric lights, alpha clip as MASK, normal maps,
emission strength) and rendered there by Cycles as they were built; photond renders the
exported files through its `gltf_camera` under the world's uniform sky, and each image is compared
with Cycles': the image mean's bias, the relMSE and the 32 x 32 blocks' relMSE.

    python3 bench/blender_authored.py --photond build/server/photond [--cycles-spp 1024]
        [--path-spp 256] [--scenes A,B] [--principled] [--out DIR] [--keep DIR [--reuse]]

Cycles renders each scene with its materials rebuilt as the glTF BRDF in Cycles' closures
(blender_scene.py, gltf_materials_in_cycles), once with every bounce (against photond's `final`
and `path` at --path-spp) and once with direct light alone (against photond's `direct`: the
lights' units, the textures, the alpha mask and the normal map with the least of the materials'
differences); with --principled also as the exporter read them, Blender's Principled BSDF, whose
Disney diffuse and added specular layer reflect a few percent more than the glTF BRDF (a closed
room's interreflections multiply that). Writes
DIR/blender_authored.md and .csv (default bench/results) and prints the table. Needs `blender`
(Debian 12's 3.4; `make blender-authored` installs it).
"""
import argparse
import json
import os
import shutil
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE_SCRIPT = os.path.join(ROOT, "bench", "blender_scene.py")
SCENES = ["window-room", "lamp-room"]
SIZE = 256

sys.path.insert(0, os.path.join(ROOT, "bench"))
from cycles_compare import blender_version, errors, photond_render, run_blender_script, write_results  # noqa: E402


def reference_path(work, name, materials, bounces):
    """Where blender_scene.py writes Cycles' render of scene `name`."""
    return os.path.join(work, f"{name}.cycles-{materials}{'-direct' if bounces == 0 else ''}.exr")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photond", default=os.path.join(ROOT, "build", "server", "photond"))
    parser.add_argument("--blender", default=shutil.which("blender") or "blender")
    parser.add_argument("--cycles-spp", type=int, default=1024)
    parser.add_argument("--path-spp", type=int, default=256)
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--principled", action="store_true",
                        help="also compare with Cycles rendering Blender's Principled BSDF")
    parser.add_argument("--out", default=os.path.join(ROOT, "bench", "results"))
    parser.add_argument("--keep", default="", help="keep the scenes and EXRs in this directory")
    parser.add_argument("--reuse", action="store_true",
                        help="take the exported scenes and Cycles' renders already in --keep DIR (photond alone runs)")
    args = parser.parse_args()
    if args.reuse and not args.keep:
        sys.exit("--reuse needs --keep DIR")

    work = os.path.abspath(args.keep or tempfile.mkdtemp(prefix="blender_authored_"))
    os.makedirs(work, exist_ok=True)
    # (Cycles materials, its bounces, photond's integrator): every light path, then direct light
    # alone, where the two renderers' materials differ least and the lights' units show plainly.
    variants = [("gltf", 64, "final"), ("gltf", 64, "path")]
    if args.principled:
        variants += [("principled", 64, "final"), ("principled", 64, "path")]
    variants.append(("gltf", 0, "direct"))
    rows = []
    for name in args.scenes.split(","):
        cycles_s = {}
        for materials, bounces, _ in variants:
            if (materials, bounces) in cycles_s:
                continue
            if args.reuse and os.path.exists(reference_path(work, name, materials, bounces)):
                cycles_s[materials, bounces] = float("nan")  # rendered before
            else:
                cycles_s[materials, bounces] = run_blender_script(
                    args.blender, SCENE_SCRIPT, [name, work, "--size", str(SIZE), "--spp", str(args.cycles_spp),
                                                 "--materials", materials, "--bounces", str(bounces)])
        scene = os.path.join(work, name, name + ".gltf")
        with open(os.path.join(work, name + ".world.json")) as f:
            sky = json.load(f)["color"]
        job_path = os.path.join(work, name + ".job.json")
        with open(job_path, "w") as f:
            json.dump({"camera": {"gltf_camera": 0}, "environment": {"color": sky} if any(sky) else None}, f)
        renders = {}
        for _, _, method in variants:
            if method in renders:
                continue
            exr = os.path.join(work, f"{name}.{method}.exr")
            extra = ["--preset", "final"] if method == "final" else ["--integrator", method, "--spp", str(args.path_spp)]
            renders[method] = (exr, photond_render(args.photond, scene, exr, job_path, extra))
        for materials, bounces, method in variants:
            exr, seconds = renders[method]
            e = errors(args.photond, exr, reference_path(work, name, materials, bounces))
            row = {"scene": name, "cycles": f"{materials}, {'direct light' if bounces == 0 else f'{bounces} bounces'}",
                   "cycles_spp": args.cycles_spp, "cycles_s": round(cycles_s[materials, bounces], 1),
                   "cycles_mean": e["reference_mean"],
                   "photond": method if method == "final" else f"{method} {args.path_spp} spp",
                   "photond_s": round(seconds, 2), "bias_pct": e["bias_pct"], "relmse": e["relmse"],
                   "block_relmse": e["block_relmse"]}
            rows.append(row)
            print(json.dumps(row), flush=True)

    lines = [f"photond on glTF exported by Blender {blender_version(args.blender)} against Cycles "
             f"({args.cycles_spp} spp) rendering the scenes as built, {SIZE}x{SIZE}, measured "
             f"{time.strftime('%Y-%m-%d %H:%M')}",
             "",
             "| scene | Cycles: materials, light | Cycles mean | photond | bias | relMSE | 32² blocks' relMSE | "
             "photond time (s) |",
             "|---|---|---:|---|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['cycles']} | {r['cycles_mean']} | {r['photond']} | {r['bias_pct']:+.2f} % | "
                     f"{r['relmse']} | {r['block_relmse']} | {r['photond_s']} |")
    write_results(args.out, "blender_authored", rows, lines)


if __name__ == "__main__":
    main()
